#!/usr/bin/env bash
# make bench: every benchmark, figures printed (no thresholds). Usage: tools/bench/run_all.sh BUILD_DIR
set -euo pipefail
build=${1:-build}
bin=$build/bin
out=$(mktemp -d "${TMPDIR:-/tmp}/lanemap-bench.XXXXXX")
trap 'rm -rf "$out"' EXIT

echo "== machine: $(nproc) cores, $(awk '/MemTotal/ {printf "%.0f GiB", $2/1048576}' /proc/meminfo)"

echo "== road tracker and skeleton queries"
"$bin/lanemap-bench-road-tracker"

# Issue 2's target: a 2-minute drive renders in a few minutes on 2 cores (camera 10 Hz + VLP-16).
echo "== lanemap-sim: 120 s drive over West Oakland, camera 10 Hz, LIDAR, seed 1"
TIMEFORMAT="   wall %R s, user %U s, sys %S s"
if [ -x /usr/bin/time ]; then
  time /usr/bin/time -f "   peak RSS %M KiB" "$bin/lanemap-sim" -q --osm data/osm/west-oakland.osm --out "$out/drive" --duration 120 --seed 1
else
  time "$bin/lanemap-sim" -q --osm data/osm/west-oakland.osm --out "$out/drive" --duration 120 --seed 1
fi
du -sh "$out/drive"/* | sed 's/^/   /'

# Issue 17: the simulator's speed on a dense city (Monaco: buildings, parked cars), camera + LIDAR,
# beside the drive's duration (target >= 4x real time on 2 cores); about 2-3 minutes.
echo "== lanemap-sim speed: Monaco 60 s drive, camera + LIDAR (tools/bench/sim_speed.sh)"
tools/bench/sim_speed.sh "$build" --duration 60

echo "== lane exploration (particle filter per 100 m of road, N = 500 and 2000)"
"$bin/lanemap-bench-lanes"

# Issue 4: BEV projection per frame (flat, LIDAR mesh, cv::warpPerspective IPM), mesh per sweep, and
# the memory of accumulating a short and a long drive (it must stay flat: one grid per open road).
echo "== BEV builder: projection and mesh"
"$bin/lanemap-bench-bev"
echo "== BEV builder: memory, 30 s drive vs 120 s drive"
"$bin/lanemap-bench-bev" --memory 30
"$bin/lanemap-bench-bev" --memory 120

# Issue 17: lanemap-offline on the demo drive against the drive's duration (LIDAR mesh with the
# meshes on a second core, in the main thread, and flat), and its peak memory on a 240 s against a
# 60 s Monaco drive (about 6 minutes: the three drives are simulated first).
echo "== lanemap-offline: speed and memory (tools/bench/offline_speed.sh)"
tools/bench/offline_speed.sh "$build" "$out/offline-speed"

# Issue 7: the segmenter's frames/s at the camera resolution (640x360), OpenCV on 1 and 2 threads.
echo "== segmenter: shipped model on 640x360 frames"
"$bin/lanemap-bench-seg"

# Issue 6: the live graph at 1x on the demo drive (60 s, seed 1), segmenter on the model and on the
# truth labels: CPU share and latency per process, frame-to-BEV, drop counters, map completion.
# Issue 17: five runs on the model, each with its drop counters (the demo drive offline_speed.sh made).
echo "== live graph at real time (lanemap-logplayer 1x, demo.yaml, private netns): demo drive"
tools/bench/live_graph.sh "$build" --drive "$out/offline-speed/demo" --modes model --runs 5
tools/bench/live_graph.sh "$build" --drive "$out/offline-speed/demo" --modes oracle

# Issue 20: the viewer's CPU while the demo drive plays at 1x (loaded the way the page loads it).
echo "== lanemap-viewer CPU at 1x (tools/bench/viewer_cpu.sh)"
tools/bench/viewer_cpu.sh "$build"

# Issue 14: drives of one world fused into one map, aligned and not (about 6 minutes).
echo "== campaign: 3 drives of one West Oakland world fused (tools/bench/campaign.sh)"
tools/bench/campaign.sh "$build" 3 60 "$out/campaign"
# Issue 14: the cost of closing one road against the map's size (about 5 minutes: fsynced writes).
echo "== closing one road, against the store's size (lanemap-bench-store)"
"$build/bin/lanemap-bench-store"
# Issue 14: a coverage campaign, each drive planned on what the map covers (about 3 minutes).
tools/bench/coverage_campaign.sh "$build" 4 60 "$out/coverage-campaign"

# Issue 16: the broad benchmark (every OSM extract in data/, truth and model labels, --driven), the
# figure of merit for the mapping stages; about 5 minutes of one core per drive, 28 drives.
echo "== broad map-quality benchmark (tools/bench/quality.sh)"
tools/bench/quality.sh "$build" "$out/quality"

# Issue 6's bar: three 150 s simulated drives mapped on the truth labels (oracle), scored against
# the truth and pooled beside the paper's figures (about 15 minutes).
echo "== oracle-label drives vs the paper (lanemap-sim -> lanemap-offline -> lanemap-eval)"
tools/bench/oracle_drives.sh "$build" "$out/oracle"

#!/usr/bin/env bash
# make demo: simulate a drive over the bundled West Oakland street network, map it with the offline
# runner (camera frames segmented with the shipped model -> road tracker -> BEV on the LIDAR mesh ->
# lane exploration -> intersections), score the map against the ground truth of the roads the car
# drove (lanemap-eval --driven); then the same on the simulator's truth labels, offline and through
# the live process graph.
# Usage: scripts/demo.sh BUILD_DIR OUT_DIR
set -euo pipefail
build=${1:-build}
out=${2:-demo-out}
osm=data/osm/west-oakland.osm
bin=$build/bin
rm -rf "$out"
mkdir -p "$out"

echo "== skeleton of $osm"
"$bin/lanemap-skeleton" --osm "$osm" --geojson "$out/skeleton.geojson" --png "$out/skeleton.png"

echo "== simulating a 60 s drive (seed 1)"
"$bin/lanemap-sim" --osm "$osm" --out "$out/drive" --duration 60 --seed 1

echo "== what the log holds"
"$bin/lanemap-lcm-stats" --log "$out/drive/drive.lcmlog"

echo "== mapping the drive (lanemap-offline: segments CAMERA_FRONT with the shipped model, BEV, lanes, intersections)"
"$bin/lanemap-offline" --log "$out/drive/drive.lcmlog" --osm "$out/drive/roads.osm" --out "$out/map"
echo "== scores on the roads the car drove (lanemap-eval --driven scenario.json), model labels"
"$bin/lanemap-eval" --truth "$out/drive/groundtruth.osm" --map "$out/map/map.osm" --driven "$out/drive/scenario.json" --json "$out/map/eval.json"

echo "== the same with the simulator's truth labels (lanemap-offline --oracle), for comparison"
"$bin/lanemap-offline" -q --oracle --log "$out/drive/drive.lcmlog" --osm "$out/drive/roads.osm" --out "$out/map-oracle"
"$bin/lanemap-eval" --truth "$out/drive/groundtruth.osm" --map "$out/map-oracle/map.osm" --driven "$out/drive/scenario.json" --json "$out/map-oracle/eval.json"

echo "== the live graph (oracle labels): lanemap-logplayer at 1x -> segmenter --oracle -> road_tracker -> bev_builder"
echo "   -> lane_mapper over LCM, with lanemap-viewer (lanemap-launch config/launch/demo.yaml, inside a private"
echo "   network namespace, so that no multicast reaches this host's network; about 70 s)."
abs_out=$(cd "$out" && pwd)
mkdir -p "$abs_out/live/logs"
unshare -rn sh -c 'ip link set lo up && ip route add 224.0.0.0/4 dev lo && exec "$0" "$@"' \
  "$bin/lanemap-launch" config/launch/demo.yaml --all-hosts --set drive="$abs_out/drive" \
  --set store="$abs_out/live" --log-dir "$abs_out/live/logs" --status-interval 0 > "$abs_out/live/launch.txt" 2>&1 &
graph=$!
# The viewer listens on 127.0.0.1:8765 inside that namespace; lanemap-port-bridge forwards this
# host's 127.0.0.1:8765 (loopback only) into it while the graph runs.
viewer_port=${LANEMAP_DEMO_VIEWER_PORT:-8765}
rm -f "$abs_out/live/viewer.url"
"$bin/lanemap-port-bridge" --pid "$graph" --port 8765 --listen-port "$viewer_port" \
  --ready-file "$abs_out/live/viewer.url" 2> "$abs_out/live/logs/port_bridge.log" &
bridge=$!
for _ in $(seq 50); do { [ -s "$abs_out/live/viewer.url" ] || ! kill -0 "$bridge" 2> /dev/null; } && break; sleep 0.1; done
if [ -s "$abs_out/live/viewer.url" ]; then
  echo "   The live viewer: open $(cat "$abs_out/live/viewer.url") in a browser on this machine while it runs."
else
  echo "   (no live viewer on this host: $(tail -n 1 "$abs_out/live/logs/port_bridge.log" 2> /dev/null))"
fi
graph_rc=0
wait "$graph" || graph_rc=$?
wait "$bridge" 2> /dev/null || true
tail -n 9 "$abs_out/live/launch.txt"
[ "$graph_rc" = 0 ] || { echo "the live graph failed (exit $graph_rc): $abs_out/live/launch.txt, $abs_out/live/logs/"; exit "$graph_rc"; }
echo "== did the live graph keep up? (lanemap-graph-report: STATUS counters, latency, CPU, from live/graph.lcmlog)"
"$bin/lanemap-graph-report" --log "$out/live/graph.lcmlog" --drive-log "$out/drive/drive.lcmlog" | tee "$out/live/report.txt"
cp "$out/live/lane_map.osm" "$out/live/map.osm"
echo "== live map vs the truth, and vs the offline oracle map"
"$bin/lanemap-eval" --truth "$out/drive/groundtruth.osm" --map "$out/live/map.osm" --driven "$out/drive/scenario.json" --json "$out/live/eval.json"
"$bin/lanemap-eval" --truth "$out/map-oracle/map.osm" --map "$out/live/map.osm" --json "$out/live/vs_offline.json" | grep -E "^lanes|precision"

cat <<EOT

Demo output in $out/:
  skeleton.png / skeleton.geojson   the OSM skeleton: atomic roads and intersection ROIs
  drive/drive.lcmlog                the simulated drive (replay: lcm-logplayer $out/drive/drive.lcmlog)
  drive/groundtruth.osm             the true lane-level map (Lanelet2)
  drive/groundtruth.png             a picture of it over the street network
  drive/roads.osm                   the road-level OSM the mapper is given
  drive/scenario.json               route, seed, options, counts
  map/map.osm, map.geojson, map.png the lane map built from the drive on the model's labels
  map/summary.json                  every road explored (lanes, or why it failed), labels, timing
  map/map.lanemap.json              lanemap's metadata for map.osm (copy both together)
  map/eval.json                     its scores against drive/groundtruth.osm
  map-oracle/                       the same on the simulator's truth labels
  live/map.osm, live/eval.json      the drive mapped by the live process graph over LCM (oracle)
  live/report.txt, graph.lcmlog     its drop counters, latency and CPU (lanemap-graph-report), and
                                    what it recorded: STATUS, ROAD_EVENT, BEV_ROAD, LANE_MAP, POSE
The live viewer (while the graph ran): $(cat "$abs_out/live/viewer.url" 2> /dev/null || echo "none: see live/logs/port_bridge.log")
Browse the live graph's map store in a web browser (no LCM, loopback only):
  $bin/lanemap-viewer --store $out/live --osm $out/drive/roads.osm    then open http://127.0.0.1:8765/
Map data (c) OpenStreetMap contributors, ODbL.
EOT

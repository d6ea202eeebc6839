#!/usr/bin/env bash
# Simulator speed (issue 17): a Monaco drive, camera 10 Hz + VLP-16, seed 4, timed with
# /usr/bin/time, printed beside its baseline, the drive's own duration (real time): wall and CPU
# seconds and the ratio drive / wall ("x real time"; issue 17's target: >= 4x on 2 cores). The
# fixed start-up (OSM, world, truth files) is timed on a 0.1 s drive and taken off for the
# "rendering only" line (the truth files are written by a thread of their own while the drive is
# rendered: on a long drive that part of the start-up is inside the rendering figure, on the 0.1 s
# drive it is most of the start-up's second half). Figures only, no thresholds.
#
#   tools/bench/sim_speed.sh BUILD_DIR [--duration S (60)] [--threads N (the cores)] [--osm FILE]
set -euo pipefail

build=${1:-build}
shift || true
duration=60
threads=$(nproc)
osm=data/osm/monaco.osm.pbf
while [ $# -gt 0 ]; do
  case $1 in
    --duration) duration=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --osm) osm=$2; shift 2 ;;
    *) echo "usage: $0 BUILD_DIR [--duration S] [--threads N] [--osm FILE]" >&2; exit 2 ;;
  esac
done
sim="$build/bin/lanemap-sim"
[ -x "$sim" ] || { echo "sim_speed.sh: no $sim (build lanemap-sim first)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "sim_speed.sh: needs /usr/bin/time (Debian package time)" >&2; exit 2; }
out=$(mktemp -d "${TMPDIR:-/tmp}/lanemap-sim-speed.XXXXXX")
trap 'rm -rf "$out"' EXIT

# run NAME DURATION: simulates, leaves "wall user sys rss_kib" in $out/NAME.time.
run() {
  /usr/bin/time -o "$out/$1.time" -f "%e %U %S %M" "$sim" -q --osm "$osm" --out "$out/$1" \
    --duration "$2" --seed 4 --threads "$threads" 2> "$out/$1.log" || { cat "$out/$1.log" >&2; exit 1; }
}
run setup 0.1
run drive "$duration"
drive_s=$(python3 -c "import json; print(json.load(open('$out/drive/scenario.json'))['duration_s'])")
frames=$(python3 -c "import json; c = json.load(open('$out/drive/scenario.json'))['counts']; print(c['camera_frames'], c['lidar_sweeps'])")
read -r sw su ss _ < "$out/setup.time"
read -r w u s rss < "$out/drive.time"
python3 - "$drive_s" "$sw" "$su" "$ss" "$w" "$u" "$s" "$rss" "$frames" "$threads" "$(basename "$osm")" << 'EOF'
import sys
d, sw, su, ss, w, u, s, rss = map(float, sys.argv[1:9])
cams, sweeps = sys.argv[9].split()
threads, osm = sys.argv[10], sys.argv[11]
cpu, scpu = u + s, su + ss
print(f"   {osm}, seed 4, camera + LIDAR, --threads {threads}: drive {d:.1f} s ({cams} frames, {sweeps} sweeps)")
print(f"   baseline (real time): {d:.1f} s")
print(f"   whole run:      wall {w:7.1f} s = {d / w:5.2f}x real time, CPU {cpu:7.1f} s ({cpu / d:.2f} CPU s per drive s), peak RSS {rss / 1024:.0f} MiB")
print(f"   start-up only:  wall {sw:7.1f} s, CPU {scpu:7.1f} s (0.1 s drive)")
rw, rc = max(w - sw, 1e-9), max(cpu - scpu, 1e-9)
print(f"   rendering only: wall {rw:7.1f} s = {d / rw:5.2f}x real time, CPU {rc:7.1f} s ({1000 * rc / max(1, int(cams)):.0f} ms CPU per frame + sweep)")
EOF

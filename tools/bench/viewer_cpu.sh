#!/usr/bin/env bash
# The viewer's CPU while the demo drive plays at 1x (issue 20: under 5 % of a core). Simulates the
# demo drive (West Oakland, 60 s, seed 1) or takes --drive DIR, runs config/launch/demo.yaml
# (viewer included, segmenter --oracle) in a private network namespace with a page's load on the
# viewer (curl on the event stream, the trail and state once a second, the lanes and OSM roads
# every 5 s, the BEV picture every second (the open road's changes at ~1 Hz): what web/viewer/src/app.js fetches), and prints the
# viewer's line of lanemap-graph-report (CPU share of one core, mean and max over its STATUS, from
# the run's recording) plus its HTTP request count. Figures only, no thresholds.
#
#   tools/bench/viewer_cpu.sh BUILD_DIR [--drive DIR]        (about 75 s, plus ~2 min to simulate)
set -euo pipefail

if [ "${1:-}" = "--in-netns" ]; then
  shift
  port=$1
  shift
  ip link set lo up
  ip route add 224.0.0.0/4 dev lo
  "$@" &
  launch=$!
  (
    url="http://127.0.0.1:$port"
    for _ in $(seq 1 240); do curl -sf -o /dev/null "$url/api/state" && break; sleep 0.5; done
    curl -sN "$url/api/events" > /dev/null 2>&1 &
    events=$!
    i=0
    while kill -0 "$launch" 2> /dev/null; do
      # The BEV picture changes about once a second while a road is open (BEV_OPEN): every poll.
      curl -s -o /dev/null "$url/api/state" -o /dev/null "$url/api/trail?from=$i" -o /dev/null "$url/api/bev.png" || true
      if [ $((i % 5)) -eq 0 ]; then
        curl -s -o /dev/null "$url/api/lanes.geojson" -o /dev/null "$url/api/skeleton.geojson" || true
      fi
      i=$((i + 1))
      sleep 1
    done
    kill "$events" 2> /dev/null || true
    echo "   page load: $i polls"
  ) &
  client=$!
  rc=0
  wait "$launch" || rc=$?
  wait "$client" || true
  exit $rc
fi

build=${1:-build}
shift || true
drive=""
while [ $# -gt 0 ]; do
  case $1 in
    --drive) drive=$2; shift 2 ;;
    *) echo "usage: $0 BUILD_DIR [--drive DIR]" >&2; exit 2 ;;
  esac
done
bin=$(cd "$build/bin" && pwd)
self=$(cd "$(dirname "$0")" && pwd)/$(basename "$0")
root=$(cd "$(dirname "$0")/../.." && pwd)
out=$(mktemp -d "${TMPDIR:-/tmp}/lanemap-viewer-cpu.XXXXXX")
trap 'rm -rf "$out"' EXIT
if [ -z "$drive" ]; then
  echo "   simulating the demo drive (60 s, seed 1)"
  "$bin/lanemap-sim" -q --osm "$root/data/osm/west-oakland.osm" --out "$out/drive" --duration 60 --seed 1
  drive=$out/drive
fi
drive=$(cd "$drive" && pwd)
port=8765
echo "== viewer CPU: demo.yaml at 1x (segmenter --oracle), a page's load on the viewer, private netns"
store=$out/store
mkdir -p "$store"
unshare -rn "$self" --in-netns "$port" "$bin/lanemap-launch" "$root/config/launch/demo.yaml" --all-hosts \
  --status-interval 0 --set drive="$drive" --set store="$store" --set segmenter_args=--oracle \
  --set viewer_port="$port" --log-dir "$store/logs" > "$store/launch.out" 2>&1 || { echo "   launch failed:"; tail -n 20 "$store/launch.out"; exit 1; }
grep "page load" "$store/launch.out" || true
"$bin/lanemap-graph-report" --log "$store/graph.lcmlog" --drive-log "$drive/drive.lcmlog" > "$store/report.txt"
grep -iE "process|viewer" "$store/report.txt" | sed 's/^/   /'

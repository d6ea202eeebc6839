#!/usr/bin/env bash
# The live graph at real time (issue 6): simulates the demo drive (scripts/demo.sh: West Oakland,
# 60 s, seed 1) or takes --drive DIR, runs config/launch/demo.yaml through lanemap-launch with
# lanemap-logplayer at 1x inside a private network namespace, once with the segmenter on the shipped
# model and once on the truth labels (--oracle), and prints what lanemap-graph-report reads from
# the run's recording (STATUS, LANE_MAP, POSE): each process's CPU share (mean, max), latency
# p50/p99, frame-to-BEV and camera-to-BEV latency, every drop counter and hand-over loss, and how
# long after the drive's end the map was complete; plus the kernel's UDP receive-buffer overflows
# in the namespace (a socket that could not keep up) and the CPU time of the whole launch
# (lanemap-logplayer and lcm-logger included, which report no STATUS). Figures only, no thresholds.
#
#   tools/bench/live_graph.sh BUILD_DIR [--drive DIR] [--modes "model oracle"] [--runs N]
# --runs N plays each mode N times (issue 17: five runs on the model) and ends each mode with one
# line per run: frames lost, whole-graph CPU, camera-to-BEV (labels-to-BEV on the oracle) p99.
# Takes about 75 s per mode and run, plus about 2 min to simulate the drive.
set -euo pipefail

# Inside the private namespace: bring lo up, route multicast to it, run the command, then print
# the namespace's UDP counters (RcvbufErrors: datagrams dropped because a socket buffer was full).
if [ "${1:-}" = "--in-netns" ]; then
  shift
  ip link set lo up
  ip route add 224.0.0.0/4 dev lo
  rc=0
  "$@" || rc=$?
  awk '/^Udp:/ { if (!seen) { for (i = 2; i <= NF; i++) name[i] = $i; seen = 1 }
                 else { for (i = 2; i <= NF; i++) if (name[i] == "RcvbufErrors" || name[i] == "InErrors") printf "   UDP %s in the namespace: %s\n", name[i], $i } }' /proc/net/snmp
  exit $rc
fi

build=${1:-build}
shift || true
drive=""
modes="model oracle"
runs=1
while [ $# -gt 0 ]; do
  case $1 in
    --drive) drive=$2; shift 2 ;;
    --modes) modes=$2; shift 2 ;;
    --runs) runs=$2; shift 2 ;;
    *) echo "usage: $0 BUILD_DIR [--drive DIR] [--modes \"model oracle\"] [--runs N]" >&2; exit 2 ;;
  esac
done
bin=$(cd "$build/bin" && pwd)
self=$(cd "$(dirname "$0")" && pwd)/$(basename "$0")
root=$(cd "$(dirname "$0")/../.." && pwd)
out=$(mktemp -d "${TMPDIR:-/tmp}/lanemap-live-graph.XXXXXX")
trap 'rm -rf "$out"' EXIT

if [ -z "$drive" ]; then
  echo "   simulating the demo drive (60 s, seed 1)"
  "$bin/lanemap-sim" -q --osm "$root/data/osm/west-oakland.osm" --out "$out/drive" --duration 60 --seed 1
  drive=$out/drive
fi
drive=$(cd "$drive" && pwd)
"$bin/lanemap-lcm-stats" --log "$drive/drive.lcmlog" | sed 's/^/   /'

for mode in $modes; do
  case $mode in
    model) args="" ;;
    oracle) args="--oracle" ;;
    *) echo "unknown mode $mode (model, oracle)" >&2; exit 2 ;;
  esac
  summary=""
  for run in $(seq 1 "$runs"); do
    echo "== live graph, segmenter on the $mode labels: lanemap-logplayer at 1x, demo.yaml, private netns (run $run of $runs)"
    store=$out/$mode-$run
    mkdir -p "$store"
    TIMEFORMAT="   whole launch (all processes, player and recorder included): wall %R s, CPU user %U s + sys %S s"
    time unshare -rn "$self" --in-netns "$bin/lanemap-launch" "$root/config/launch/demo.yaml" --all-hosts \
      --status-interval 0 --set drive="$drive" --set store="$store" --set segmenter_args="$args" \
      --log-dir "$store/logs" > "$store/launch.out" 2>&1 || { echo "   launch failed:"; tail -n 20 "$store/launch.out"; exit 1; }
    grep "UDP " "$store/launch.out" || true
    "$bin/lanemap-graph-report" --log "$store/graph.lcmlog" --drive-log "$drive/drive.lcmlog" > "$store/report.txt"
    sed 's/^/   /' "$store/report.txt"
    lost=$(grep -E "^(no frame dropped|[0-9]+ frame\(s\) dropped)" "$store/report.txt" | sed 's/^no frame dropped/0/; s/ frame(s).*//')
    cpu=$(awk '$1 == "all" { print $2 }' "$store/report.txt")
    p99=$(sed -n 's/.*\(camera\|labels\)-to-BEV.*p99 \([0-9.]*\) ms.*/\2/p' "$store/report.txt")
    summary="$summary   $mode run $run: frames lost ${lost:-?}, whole graph CPU ${cpu:-?} of a core, camera (labels) to BEV p99 ${p99:-?} ms\n"
  done
  if [ "$runs" -gt 1 ]; then
    echo "== live graph on the $mode labels, $runs runs (issue 17: 0 lost in 5 of 5 runs, graph <= 80 %, p99 <= 100 ms)"
    printf "%b" "$summary"
  fi
done

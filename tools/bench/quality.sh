#!/usr/bin/env bash
# The broad map-quality benchmark (issue 16): the figure of merit for every change to the mapping
# stages. Simulated drives over every OSM extract in data/ (West Oakland, all of Monaco, the twelve
# hard cases of data/osm/dev/), several seeds each, mapped by lanemap-offline on the simulator's
# truth labels (oracle) and on the shipped model's labels, scored by lanemap-eval --driven (the
# atomic roads the car drove to their end and the junction connections between them: a driven road
# the map has no lanes on counts as missed), printed per network and pooled beside the paper's
# figures (METHOD.md section 6). Do not tune parameters to one network: read the pooled row and the
# worst networks.
#
# Usage: tools/bench/quality.sh BUILD_DIR [OUT_DIR]
#   SEEDS="1 2"       seeds per network (default "1 2")
#   SECONDS_PER=150   drive length (s); the issue asks for at least 150
#   LABELS="oracle model"   which label sources to map on
#   NETWORKS="..."    a subset of OSM files (paths relative to data/osm), default all; an entry
#                     lanelet2:FILE is a world built from the Lanelet2 map data/lanelet2/FILE
#                     (lanemap-sim --lanelet2: the drawn lanes are the truth, roads.osm derived)
#   LIDAR=1           BEV on the LIDAR ground mesh (0: --no-lidar, flat plane; faster)
#   JOBS=$(nproc)     drives simulated and mapped at once
#   REPROJECT=1       project the drives again (after a change to segmentation, BEV or road tracking)
#   BEV_CONFIG=FILE   project with this BEV builder config (lanemap-offline --bev-config; e.g. one with
#                     projection.crown_slope 0.02): use a fresh OUT_DIR or REPROJECT=1
#   TRAINED_ON=monaco the networks the segmentation model was trained on (comma-separated; the
#                     shipped model: Monaco, models/README.md): the model's rows are also pooled
#                     over those and over the networks it never saw
#   LANES_CONFIG=FILE, TAG=NAME   judge a change to the mapping stages: map the kept projections
#                     with this lane mapper config (default: the shipped one) into map-LABEL-NAME
#                     (eval-LABEL-NAME.json), and end with a table of the networks whose figures
#                     differ from the untagged run's on the same OUT_DIR (quality_table.py --compare;
#                     that run's tables are printed too, and quality.json holds both)
# Drives already simulated in OUT_DIR are reused, and so are their projections (neither depends on
# the mapping stages: after a change there, run again on the same OUT_DIR); the maps and scores are
# always made anew.
# Cost: per 150 s drive about 3 min of one core to simulate (with LIDAR), 1 min to map on the
# truth labels, 3 min on the model; 30 drives in all by default. Run again on the same OUT_DIR
# (drives and projections kept), a change to the mapping stages costs seconds a drive.
set -euo pipefail
build=${1:-build}
bin=$(cd "$build/bin" && pwd)
out=${2:-$(mktemp -d "${TMPDIR:-/tmp}/lanemap-quality.XXXXXX")}
mkdir -p "$out"
out=$(cd "$out" && pwd)
seeds=${SEEDS:-1 2}
secs=${SECONDS_PER:-150}
labels=${LABELS:-oracle model}
jobs=${JOBS:-$(nproc)}
lidar=${LIDAR:-1}
root=$(cd "$(dirname "$0")/../.." && pwd)
tag=${TAG:+-$TAG}
if [ -z "${NETWORKS:-}" ]; then
  NETWORKS="west-oakland.osm monaco.osm.pbf $(cd "$root/data/osm" && ls dev/*.osm | tr '\n' ' ')"
  NETWORKS+=" lanelet2:karlsruhe_mapping_example.osm"
fi
# A file's absolute path (the drives run in sub-shells elsewhere).
abspath() { echo "$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"; }
sim_flags=()
map_flags=()
if [ "$lidar" = 0 ]; then sim_flags+=(--no-lidar); map_flags+=(--no-lidar); fi
if [ -n "${BEV_CONFIG:-}" ]; then
  [ -f "$BEV_CONFIG" ] || { echo "quality.sh: no such BEV builder config: $BEV_CONFIG" >&2; exit 2; }
  map_flags+=(--bev-config "$(abspath "$BEV_CONFIG")")
fi
if [ -n "${LANES_CONFIG:-}" ]; then
  [ -n "$tag" ] || { echo "quality.sh: LANES_CONFIG needs TAG (the maps it makes are named by it)" >&2; exit 2; }
  [ -f "$LANES_CONFIG" ] || { echo "quality.sh: no such lane mapper config: $LANES_CONFIG" >&2; exit 2; }
  LANES_CONFIG=$(abspath "$LANES_CONFIG")
fi

# One drive: simulate (unless already there), map on each label source, score.
run_one() {
  local osm=$1 seed=$2 name d src
  src=(--osm "$root/data/osm/$osm")
  case $osm in lanelet2:*) src=(--lanelet2 "$root/data/lanelet2/${osm#lanelet2:}") ;; esac
  name=$(basename "${osm#lanelet2:}")
  name=${name%%.*}-s$seed
  d="$out/$name"
  mkdir -p "$d"
  if [ ! -f "$d/drive/scenario.json" ]; then
    rm -rf "$d/drive"
    if ! "$bin/lanemap-sim" -q "${src[@]}" --out "$d/drive" --seed "$seed" --duration "$secs" \
      "${sim_flags[@]}" >"$d/sim.log" 2>&1; then
      echo "   $name: simulation failed (see $d/sim.log)"
      return 0
    fi
  fi
  for lab in $labels; do
    local flags=() lanes_cfg=() m="$lab$tag"
    [ "$lab" = oracle ] && flags=(--oracle)
    [ -n "${LANES_CONFIG:-}" ] && lanes_cfg=(--lanes-config "$LANES_CONFIG")
    rm -rf "$d/map-$m"
    # The drive's projection (segmentation, BEV, road tracking: what lanemap-offline --project-only
    # hands over) is kept and reused: the mapping stages run on it (--traversals), which gives the
    # map --log would (tests/mapping/city_test.cc). REPROJECT=1 after a change before them.
    if [ "${REPROJECT:-0}" = 1 ] || [ ! -f "$d/proj-$lab/projection.json" ]; then
      rm -rf "$d/proj-$lab"
      "$bin/lanemap-offline" -q --log "$d/drive/drive.lcmlog" --osm "$d/drive/roads.osm" --project-only "$d/proj-$lab" \
        "${flags[@]}" "${map_flags[@]}" >"$d/project-$lab.log" 2>&1 || rm -rf "$d/proj-$lab"
    fi
    if [ ! -f "$d/proj-$lab/projection.json" ] ||
      ! "$bin/lanemap-offline" -q --traversals "$d/proj-$lab" --osm "$d/drive/roads.osm" --out "$d/map-$m" \
        "${map_flags[@]}" "${lanes_cfg[@]}" >"$d/offline-$m.log" 2>&1; then
      [ -f "$d/proj-$lab/projection.json" ] || cp "$d/project-$lab.log" "$d/offline-$m.log"
      # No map at all (nothing mapped, or the run failed): scored as an empty map, every driven lane missed.
      echo "   $name ($m): lanemap-offline failed: $(tail -n 1 "$d/offline-$m.log")"
      mkdir -p "$d/map-$m"
      echo '<?xml version="1.0"?><osm version="0.6" generator="lanemap quality.sh: no map"/>' >"$d/map-$m/map.osm"
      touch "$d/map-$m/FAILED"
    fi
    "$bin/lanemap-eval" -q --truth "$d/drive/groundtruth.osm" --map "$d/map-$m/map.osm" \
      --driven "$d/drive/scenario.json" --json "$d/eval-$m.json" >"$d/eval-$m.log" 2>&1 ||
      echo "   $name ($m): lanemap-eval failed (see $d/eval-$m.log)"
    # Autoware's map requirements (lanemap-check): the table counts the maps that fail one.
    rm -f "$d/check-$m.txt"
    [ -f "$d/map-$m/FAILED" ] || "$bin/lanemap-check" "$d/map-$m/map.osm" >"$d/check-$m.txt" 2>&1 || true
  done
  echo "   $name done"
}
export -f run_one
export out bin root secs labels tag LANES_CONFIG
export sim_flags_str="${sim_flags[*]:-}" map_flags_str="${map_flags[*]:-}"

echo "== broad benchmark: $(echo $NETWORKS | wc -w) networks x seeds {$seeds}, ${secs} s each, labels {$labels}, LIDAR=$lidar, $jobs at once"
echo "   drives and maps in $out"
t0=$(date +%s)
tasks=()
for osm in $NETWORKS; do
  for seed in $seeds; do tasks+=("$osm $seed"); done
done
# xargs runs the drives in parallel; each sub-shell re-reads the flag arrays from the strings.
printf '%s\n' "${tasks[@]}" | xargs -P "$jobs" -L 1 bash -c '
  sim_flags=($sim_flags_str); map_flags=($map_flags_str); run_one "$0" "$1"'
echo "   wall $(( $(date +%s) - t0 )) s"

if [ -z "$tag" ]; then
  python3 "$root/tools/bench/quality_table.py" "$out" $labels --trained-on "${TRAINED_ON:-monaco}"
else
  # The tagged maps' tables (and the untagged run's on the same drives, where there is one), then
  # each tagged label beside its untagged one; one table run, so quality.json holds them all.
  table_labels="" compare=()
  for lab in $labels; do
    if ls "$out"/*/eval-"$lab".json > /dev/null 2>&1; then
      table_labels+=" $lab"
      compare+=(--compare "$lab" "$lab$tag")
    fi
    table_labels+=" $lab$tag"
  done
  python3 "$root/tools/bench/quality_table.py" "$out" $table_labels --trained-on "${TRAINED_ON:-monaco}" "${compare[@]}"
fi

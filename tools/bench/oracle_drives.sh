#!/usr/bin/env bash
# Issue 6's bar: on simulated drives with oracle labels (the simulator's truth segmentation, so the
# figures measure the mapping, not the segmenter), the whole camera path (BEV on the LIDAR mesh,
# lane exploration, intersections) scored by lanemap-eval --driven (the roads the car drove) against the truth,
# pooled over the drives and printed beside the paper's best (METHOD.md section 6: atomic roads
# P 0.84 R 0.73 RMS 0.24 m mIoU 0.79; intersections P 0.91 R 0.80 RMS 0.24 m).
# Usage: tools/bench/oracle_drives.sh BUILD_DIR [OUT_DIR]   (about 15 minutes on 2 cores)
set -euo pipefail
build=${1:-build}
bin=$build/bin
out=${2:-$(mktemp -d "${TMPDIR:-/tmp}/lanemap-oracle.XXXXXX")}
mkdir -p "$out"

# (osm file, seed, seconds): two West Oakland drives and one over Monaco's hills.
drives=("west-oakland.osm 3 150" "west-oakland.osm 11 150" "monaco.osm.pbf 2 150")
reports=()
for spec in "${drives[@]}"; do
  read -r osm seed seconds <<<"$spec"
  name="${osm%%.*}-s$seed"
  d="$out/$name"
  if [ ! -f "$d/drive/drive.lcmlog" ]; then
    rm -rf "$d/drive"
    "$bin/lanemap-sim" -q --osm "data/osm/$osm" --out "$d/drive" --seed "$seed" --duration "$seconds"
  fi
  rm -rf "$d/map"
  "$bin/lanemap-offline" -q --oracle --log "$d/drive/drive.lcmlog" --osm "$d/drive/roads.osm" --out "$d/map" >/dev/null
  echo "== $name: $seconds s, oracle labels"
  "$bin/lanemap-eval" --truth "$d/drive/groundtruth.osm" --map "$d/map/map.osm" --driven "$d/drive/scenario.json" \
    --json "$d/map/eval.json" | sed -n '3,7p'
  reports+=("$d/map/eval.json")
done

echo "== pooled over ${#reports[@]} drives (counts summed; RMS and mIoU averaged over drives)"
python3 - "${reports[@]}" <<'EOF'
import json, sys
r = [json.load(open(p)) for p in sys.argv[1:]]
det = sum(j["lanes"]["detected"] for j in r)
built = sum(j["lanes"]["built"] for j in r)
truth = sum(j["lanes"]["truth"] for j in r)
ok = sum(j["intersections"]["correct_pairs"] for j in r)
bp = sum(j["intersections"]["built_pairs"] for j in r)
tp = sum(j["intersections"]["truth_pairs"] for j in r)
mean = lambda k1, k2: sum(j[k1][k2] for j in r if j[k1][k2] is not None) / len(r)
rows = [("lanes precision", det / built, 0.84), ("lanes recall", det / truth, 0.73),
        ("lanes RMS (m)", mean("lanes", "rms_m"), 0.24), ("lanes mIoU", mean("lanes", "miou"), 0.79),
        ("intersections precision", ok / bp, 0.91), ("intersections recall", ok / tp, 0.80),
        ("intersections RMS (m)", mean("intersections", "rms_m"), 0.24)]
print(f"   lanes {det} detected of {built} built, {truth} true; intersection pairs {ok} correct of {bp} built, {tp} true")
print(f"   {'':26s} {'lanemap':>8s} {'paper':>7s}")
for name, v, paper in rows:
    better = v < paper if "RMS" in name else v > paper
    print(f"   {name:26s} {v:8.3f} {paper:7.2f}  {'better' if better else 'worse'} by {abs(v - paper):.3f}")
EOF

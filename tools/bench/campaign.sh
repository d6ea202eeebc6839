#!/usr/bin/env bash
# Many drives of one world (issue 14): DRIVES simulated drives of one West Oakland world
# (lanemap-sim --world-seed) along the route the first one planned, each with its own seed and so
# its own constant pose offset (config/sim_drive.yaml campaign_offset_sigma_m); each mapped alone,
# then the first k mapped into one map (lanemap-offline --log ... --log ...) with the BEV aligned
# before every merge (by a shift), by a shift and a small rotation (--align-rotation), and not
# aligned (--no-align). Every map is scored with lanemap-eval --driven
# against the world's truth (the roads the first drive closed). Truth labels, flat ground: what
# changes between the rows is the pose error and the fusion only.
#
# Usage: tools/bench/campaign.sh BUILD_DIR [DRIVES (3)] [SECONDS (60)] [OUT (a temporary folder)]
set -euo pipefail
build=${1:-build}
drives=${2:-3}
secs=${3:-60}
out=${4:-}
bin=$build/bin
if [ -z "$out" ]; then
  out=$(mktemp -d "${TMPDIR:-/tmp}/lanemap-campaign.XXXXXX")
  trap 'rm -rf "$out"' EXIT
fi
mkdir -p "$out"
osm=data/osm/west-oakland.osm
world=11

route=auto
for k in $(seq 1 "$drives"); do
  d=$out/drive$k
  if [ ! -f "$d/scenario.json" ]; then
    "$bin/lanemap-sim" -q --osm $osm --world-seed $world --seed "$k" --route "$route" --duration "$secs" \
      --no-lidar --out "$d" --force
  fi
  if [ "$route" = auto ]; then
    # the intersections the first drive passed, in order (its roads' start nodes, then the last end)
    route=$(python3 -c "import json,sys; r=json.load(open(sys.argv[1]))['route']; print(','.join(str(n) for n in [x['from'] for x in r] + [r[-1]['to']]))" "$d/scenario.json")
  fi
done

score() {  # score NAME LOG...: map the logs, score the map
  local name=$1; shift
  local args=()
  for l in "$@"; do args+=(--log "$l"); done
  if "$bin/lanemap-offline" -q --oracle --no-lidar "${args[@]}" $extra --osm "$out/drive1/roads.osm" \
      --out "$out/map-$name" > "$out/map-$name.log" 2>&1; then
    "$bin/lanemap-eval" -q --truth "$out/drive1/groundtruth.osm" --map "$out/map-$name/map.osm" \
      --driven "$out/drive1/scenario.json" --json "$out/eval-$name.json" > /dev/null 2>&1 || true
  fi
}

extra=""
for k in $(seq 1 "$drives"); do score "alone$k" "$out/drive$k/drive.lcmlog"; done
logs=()
for k in $(seq 1 "$drives"); do
  logs+=("$out/drive$k/drive.lcmlog")
  [ "$k" -lt 2 ] && continue
  extra=""; score "fused$k" "${logs[@]}"
  extra="--align-rotation"; score "turned$k" "${logs[@]}"
  extra="--no-align"; score "blurred$k" "${logs[@]}"
done

python3 - "$out" "$drives" <<'EOF'
import json, math, os, sys
out, n = sys.argv[1], int(sys.argv[2])
def row(name):
    p = os.path.join(out, f"eval-{name}.json")
    if not os.path.exists(p):
        return None
    l = json.load(open(p))["lanes"]
    return l
def bands(name):
    p = os.path.join(out, f"eval-{name}.json")
    if not os.path.exists(p):
        return ""
    c = json.load(open(p)).get("confidence", {}).get("bands", [])
    def p_of(b):
        return f"P {b['precision']:.2f}" if b["precision"] is not None else "P -"
    return "; ".join(f"[{b['lo']:.1f},{b['hi']:.1f}) {b['built']} lanes {p_of(b)}" for b in c)
def fmt(label, l, name=None):
    if l is None:
        print(f"  {label:<34} (mapping failed)"); return
    rms = l["rms_m"] if l["rms_m"] is not None else float("nan")
    print(f"  {label:<34} lane P {l['precision']:.3f} R {l['recall']:.3f}  centre RMS {rms:.3f} m  mIoU {l['miou'] or float('nan'):.3f}  ({l['truth']} truth lanes)")
    if name and bands(name):
        print(f"  {'':<34} by confidence: {bands(name)}")
print(f"== campaign: {n} drives of one West Oakland world, each with its own pose offset (truth labels, flat)")
for k in range(1, n + 1):
    sc = json.load(open(os.path.join(out, f"drive{k}", "scenario.json")))
    o = sc["pose_offset"]
    print(f"  drive {k}: seed {sc['seed']}, pose offset east {o['east_m']:+.2f} m north {o['north_m']:+.2f} m heading {o['heading_deg']:+.3f} deg")
alone = [row(f"alone{k}") for k in range(1, n + 1)]
for k, l in enumerate(alone, 1):
    fmt(f"drive {k} alone", l, f"alone{k}")
ok = [l for l in alone if l and l["rms_m"] is not None]
once = sum(l["rms_m"] for l in ok) / len(ok) if ok else float("nan")
print(f"  {'mean of the drives alone':<34} centre RMS {once:.3f} m (the baseline: lanes driven once)")
for k in range(2, n + 1):
    f, s, b = row(f"fused{k}"), row(f"turned{k}"), row(f"blurred{k}")
    fmt(f"first {k} fused, aligned", f, f"fused{k}")
    fmt(f"first {k} fused, aligned with turns", s)
    p = os.path.join(out, f"map-turned{k}", "summary.json")
    if os.path.exists(p):
        m = [x for d in json.load(open(p)).get("drives", []) for x in d.get("merged", []) if x.get("aligned")]
        turned = [x["rotation_deg"] for x in m if x.get("rotation_deg")]
        print(f"  {'':<34} {len(m)} merges aligned, {len(turned)} turned" +
              (f" ({', '.join(f'{t:+.1f}' for t in turned)} deg)" if turned else ""))
    fmt(f"first {k} fused, not aligned", b)
    if f and f["rms_m"] is not None and once == once:
        print(f"  {'':<34} aligned RMS / once: {f['rms_m'] / once:.2f} (target for 3+ drives: <= 0.70)")
EOF

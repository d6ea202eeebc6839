#!/usr/bin/env bash
# Reproduces the shipped segmentation model (models/lanesegnet.onnx + models/lanesegnet.json) from
# scratch on a CPU, in one command:
#   scripts/install-train-deps.sh     # once: python3-torch, python3-onnx, python3-opencv, python3-numpy
#   tools/seg/train.sh [BUILD_DIR] [WORK_DIR]
# 1. builds lanemap-seg-dataset, 2. renders the frames (varied light / sun / shadows / haze / noise /
# camera pitch-roll-yaw-height, more faded markings), one folder per street network, 3. trains
# tools/seg/model.py with /usr/bin/python3 (Debian's torch), exports ONNX and scores it through
# OpenCV DNN at 640x360 (pooled over the validation folders), 4. scores it per network
# (tools/seg/score.py: the tables of models/README.md).
# RECIPE=monaco (the default: the shipped lanesegnet-v3): training on Monaco alone (seeds 1-40,
# 100 frames each); validation on the whole West Oakland network (seeds 101-112, 40 frames each).
# RECIPE=many (lanesegnet-v4, trained 2026-12-06 and not shipped: models/README.md): training on
# Monaco (seeds 201-224, 100 frames each) and the eight data/osm/dev networks of TRAIN_DEV (seeds
# 201-210, 30 frames each); whole networks held out: West Oakland as above and the four of
# HELD_OUT (seeds 101-104, 30 frames each). Seeds 1-2 (the broad benchmark's drives,
# tools/bench/quality.sh) are not rendered for training in this recipe.
# Both recipes also score the folders of the other held-out networks when they are rendered
# (RECIPE=monaco renders the four HELD_OUT networks for its per-network table; never trained on).
# Frames are rendered once per WORK_DIR (a second run reuses them). Environment: WIDTH x HEIGHT
# (model input, 480 x 176), CROP_TOP (camera rows above the road the model never sees, 120),
# ARCH (tools/seg/model.py ARCHS: v3, the shipped network, or small), DICE (weight of the soft
# Dice loss, 0.5), STEPS (11900), MAX_MINUTES (240: a cap; the
# learning-rate schedule anneals within whichever comes first), THREADS (2), OUT (models/lanesegnet.onnx).
# A model trained at another input size or crop needs config/segmenter.yaml's model keys changed.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
build=${1:-$root/build}
work=${2:-$(mktemp -d "${TMPDIR:-/tmp}/lanemap-seg.XXXXXX")}
recipe=${RECIPE:-monaco}
TRAIN_DEV=${TRAIN_DEV:-"arizona_highways aurora_sausage_link borough_sausage_links fremantle_placement montlake_roundabout roosevelt_cycletrack seattle_slip_lane tiny_roundabout"}
HELD_OUT=${HELD_OUT:-"i5_exit_ramp kingsway_junction neukolln perth_peanut_roundabout"}
case $recipe in monaco|many) ;; *) echo "train.sh: RECIPE must be monaco or many, not '$recipe'" >&2; exit 2 ;; esac
cd "$root"
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build "$build" --target lanemap-seg-dataset -j"${THREADS:-2}"
gen="$build/bin/lanemap-seg-dataset"
t0=$(date +%s)
# render DIR OSM FIRST_SEED SEEDS FRAMES SPACING DURATION: one network's frames, once per WORK_DIR.
# Each seed's frames depend on that seed only (seeds 1-40 in one run are the frames of 1-20 and 21-40).
render() {
  [ -f "$1/index.csv" ] || "$gen" --osm "$2" --out "$1" --first-seed "$3" --seeds "$4" --frames "$5" \
    --spacing "$6" --duration "$7" --faded 0.25
}
render "$work/val/west-oakland" data/osm/west-oakland.osm 101 12 40 2 300
val_dirs=("$work/val/west-oakland") held_dirs=()
for n in $HELD_OUT; do
  render "$work/val/$n" "data/osm/dev/$n.osm" 101 4 30 2.5 100
  held_dirs+=("$work/val/$n")
done
if [ "$recipe" = monaco ]; then
  render "$work/train/monaco" data/osm/monaco.osm.pbf 1 40 100 2.5 400
  train_dirs=("$work/train/monaco")
else
  render "$work/train/monaco" data/osm/monaco.osm.pbf 201 24 100 2.5 400
  train_dirs=("$work/train/monaco")
  for n in $TRAIN_DEV; do
    render "$work/train/$n" "data/osm/dev/$n.osm" 201 10 30 2.5 100
    train_dirs+=("$work/train/$n")
  done
  val_dirs+=("${held_dirs[@]}")
fi
echo "train.sh: frames rendered in $(( $(date +%s) - t0 )) s into $work"
out=${OUT:-$root/models/lanesegnet.onnx}
/usr/bin/python3 "$here/train.py" --train "${train_dirs[@]}" --val "${val_dirs[@]}" --out "$out" \
  --arch "${ARCH:-v3}" --width "${WIDTH:-480}" --height "${HEIGHT:-176}" --crop-top "${CROP_TOP:-120}" --dice "${DICE:-0.5}" \
  --steps "${STEPS:-11900}" --max-minutes "${MAX_MINUTES:-240}" --threads "${THREADS:-2}"
/usr/bin/python3 "$here/score.py" --model "$out" --width "${WIDTH:-480}" --height "${HEIGHT:-176}" \
  --crop-top "${CROP_TOP:-120}" "$work/val/west-oakland" "${held_dirs[@]}"

#!/usr/bin/env bash
# Reproduces the shipped segmentation model (models/lanesegnet.onnx + models/lanesegnet.json) from
# scratch on a CPU, in one command:
#   scripts/install-train-deps.sh     # once: python3-torch, python3-onnx, python3-opencv, python3-numpy
#   tools/seg/train.sh [BUILD_DIR] [WORK_DIR]
# 1. builds lanemap-seg-dataset, 2. renders the training frames (Monaco, seeds 1-40, 100 frames
# each, varied light / sun / shadows / haze / noise / camera pitch-roll-yaw-height, more faded
# markings) and the validation frames (the whole West Oakland network, never trained on: seeds
# 101-112, 40 frames each), 3. trains tools/seg/model.py with /usr/bin/python3 (Debian's torch),
# exports ONNX and scores it through OpenCV DNN at 640x360 (models/README.md has the figures).
# Frames are rendered once per WORK_DIR (a second run reuses them). Environment: WIDTH x HEIGHT
# (model input, 480 x 176), CROP_TOP (camera rows above the road the model never sees, 120),
# DICE (weight of the soft Dice loss, 0.5), STEPS (11900), MAX_MINUTES (240: a cap; the
# learning-rate schedule anneals within whichever comes first), THREADS (2), OUT (models/lanesegnet.onnx).
# A model trained at another input size or crop needs config/segmenter.yaml's model keys changed.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
build=${1:-$root/build}
work=${2:-$(mktemp -d "${TMPDIR:-/tmp}/lanemap-seg.XXXXXX")}
cd "$root"
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build "$build" --target lanemap-seg-dataset -j"${THREADS:-2}"
gen="$build/bin/lanemap-seg-dataset"
t0=$(date +%s)
if [ ! -f "$work/val/index.csv" ]; then
  "$gen" --osm data/osm/west-oakland.osm --out "$work/val" --seeds 12 --first-seed 101 --frames 40 --spacing 2 --duration 300
fi
# Each seed's frames depend on that seed only: seeds 1-40 in one run are the frames of 1-20 and 21-40.
if [ ! -f "$work/train/index.csv" ]; then
  "$gen" --osm data/osm/monaco.osm.pbf --out "$work/train" --seeds 40 --first-seed 1 --frames 100 --spacing 2.5 \
    --duration 400 --faded 0.25
fi
echo "train.sh: frames rendered in $(( $(date +%s) - t0 )) s into $work"
/usr/bin/python3 "$here/train.py" --train "$work/train" --val "$work/val" --out "${OUT:-$root/models/lanesegnet.onnx}" \
  --width "${WIDTH:-480}" --height "${HEIGHT:-176}" --crop-top "${CROP_TOP:-120}" --dice "${DICE:-0.5}" \
  --steps "${STEPS:-11900}" --max-minutes "${MAX_MINUTES:-240}" --threads "${THREADS:-2}"

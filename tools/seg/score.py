#!/usr/bin/env /usr/bin/python3
"""Scores a segmentation model on rendered frames, one street network (folder) at a time, at the
camera's resolution through OpenCV DNN exactly as the segmenter runs it (train.py's evaluation):

  /usr/bin/python3 tools/seg/score.py --model models/lanesegnet.onnx DIR [DIR ...]

Each DIR is a lanemap-seg-dataset folder (index.csv, images/, labels/). Prints a table of per-class
IoU, one column per folder (named by the folder) and one pooled over all of them, then each class's
truth pixels; a class with no pixel in a folder's truth nor its prediction is "-" (with none in the
truth but some predicted, its IoU is 0). --json FILE also writes the figures.
"""
import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from train import CLASS_NAMES, evaluate_cv_dnn, ious, load_set  # noqa: E402
from model import NUM_CLASSES  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dirs", nargs="+", help="lanemap-seg-dataset folders, one per network")
    ap.add_argument("--model", required=True, help="ONNX model (input 1 x 3 x HEIGHT x WIDTH)")
    ap.add_argument("--width", type=int, default=480)
    ap.add_argument("--height", type=int, default=176)
    ap.add_argument("--crop-top", type=int, default=120)
    ap.add_argument("--json", help="also write the figures here")
    args = ap.parse_args()
    names, columns, pooled = [], [], np.zeros((NUM_CLASSES, NUM_CLASSES), np.int64)
    frames = {}
    for d in args.dirs:
        _, _, full, _ = load_set([d], args.width, args.height, args.crop_top, True)
        cm, _ = evaluate_cv_dnn(args.model, full, args.width, args.height, args.crop_top)
        pooled += cm
        names.append(os.path.basename(os.path.normpath(d)))
        columns.append(cm)
        frames[names[-1]] = len(full)
    names.append("pooled")
    columns.append(pooled)
    frames["pooled"] = sum(frames.values())
    table = {n: ious(cm) for n, cm in zip(names, columns)}
    fmt = lambda v: "-" if np.isnan(v) else "%.3f" % v  # noqa: E731
    print("| class | " + " | ".join("%s (%d)" % (n, frames[n]) for n in names) + " |")
    print("|---" * (len(names) + 1) + "|")
    for c, name in enumerate(CLASS_NAMES):
        print("| %s | " % name + " | ".join(fmt(table[n][c]) for n in names) + " |")
    print("| mIoU | " + " | ".join("%.3f" % np.nanmean(table[n]) for n in names) + " |")
    print("\ntruth pixels (thousands) per class:")
    for c, name in enumerate(CLASS_NAMES):
        print("| %s | " % name + " | ".join("%.0f" % (cm[c].sum() / 1000.0) for cm in columns) + " |")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({n: {"frames": frames[n],
                           "iou": {c: (None if np.isnan(v) else round(float(v), 4)) for c, v in zip(CLASS_NAMES, table[n])},
                           "miou": round(float(np.nanmean(table[n])), 4),
                           "truth_pixels": {c: int(cm[i].sum()) for i, c in enumerate(CLASS_NAMES)}}
                       for n, cm in zip(names, columns)}, f, indent=1)


if __name__ == "__main__":
    main()

#!/usr/bin/env /usr/bin/python3
"""Trains LaneSegNet (tools/seg/model.py) on frames rendered by lanemap-seg-dataset, scores it on a
held-out set at the camera's resolution through OpenCV DNN (exactly as the segmenter runs it), and
exports it to ONNX.

  /usr/bin/python3 tools/seg/train.py --train DIR [DIR ...] --val DIR --out models/lanesegnet.onnx

Each DIR holds index.csv, images/*.jpg, labels/*.png. Input: the JPEG below its top --crop-top rows
(the sky: no class is ever there; the segmenter labels them background) resized (INTER_AREA) to
--width x --height, RGB, (pixel / 255 - 0.5) / 0.25. Loss: class-weighted cross-entropy (plus
--dice times a soft Dice loss over the classes present in the batch) of the logits (v2: at the
input resolution; --logits half: v1's, upsampled x2, bilinear) against the labels sampled at the
input grid's pixel centres.
AdamW, warm-up then cosine learning rate over --steps (or over --max-minutes when that comes
first: the schedule anneals fully either way; the step count is then machine dependent). Writes <out> and <out minus .onnx>.json
(validation per-class IoU, timings, settings).
"""
import argparse
import csv
import json
import math
import os
import platform
import random
import sys
import time

import cv2
import numpy as np
import torch
import torch.nn.functional as F

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from model import ARCHS, LaneSegNet, NUM_CLASSES  # noqa: E402

CLASS_NAMES = ["background", "lane_ego", "lane_left", "lane_right", "lane_left_left", "lane_right_right",
               "dashed_line", "solid_line", "crosswalk", "curb", "stop_line"]
MEAN, STD = 0.5, 0.25


def centre_indices(n_out, n_in):
    return np.clip(np.round((np.arange(n_out) + 0.5) * n_in / n_out - 0.5).astype(int), 0, n_in - 1)


def load_set(dirs, width, height, crop_top, keep_full_labels):
    xs, ys, full, names = [], [], [], []
    for d in dirs:
        with open(os.path.join(d, "index.csv")) as f:
            rows = list(csv.DictReader(f))
        for r in rows:
            img = cv2.imread(os.path.join(d, "images", r["name"] + ".jpg"), cv2.IMREAD_COLOR)
            lab = cv2.imread(os.path.join(d, "labels", r["name"] + ".png"), cv2.IMREAD_UNCHANGED)
            if img is None or lab is None:
                raise RuntimeError("cannot read frame %s in %s" % (r["name"], d))
            if img.shape[:2] != lab.shape[:2] or img.shape[0] < crop_top + 16:
                raise RuntimeError("frame %s in %s: image %s, labels %s, --crop-top %d" %
                                   (r["name"], d, img.shape[:2], lab.shape[:2], crop_top))
            xs.append(model_input(img, width, height, crop_top))
            road = lab[crop_top:]
            yi, xi = centre_indices(height, road.shape[0]), centre_indices(width, road.shape[1])
            ys.append(road[np.ix_(yi, xi)])
            if keep_full_labels:
                full.append((img, lab))
            names.append(r["name"])
    return np.stack(xs), np.stack(ys), full, names


def model_input(bgr, width, height, crop_top):
    """What the segmenter gives the model: the frame below crop_top, resized (INTER_AREA), RGB."""
    return cv2.cvtColor(cv2.resize(bgr[crop_top:], (width, height), interpolation=cv2.INTER_AREA), cv2.COLOR_BGR2RGB)


def to_input(rgb_u8):
    x = torch.from_numpy(rgb_u8).permute(0, 3, 1, 2).float()
    return (x / 255.0 - MEAN) / STD


def confusion(truth, pred, n=NUM_CLASSES):
    return np.bincount(truth.astype(np.int64).ravel() * n + pred.astype(np.int64).ravel(),
                       minlength=n * n).reshape(n, n)


def ious(cm):
    tp = np.diag(cm).astype(float)
    union = cm.sum(0) + cm.sum(1) - tp
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(union > 0, tp / union, np.nan)


def evaluate_cv_dnn(onnx_path, frames, width, height, crop_top):
    """Per-class IoU at the camera resolution, through cv2.dnn as the C++ segmenter runs the model
    (rows above crop_top are background)."""
    net = cv2.dnn.readNetFromONNX(onnx_path)
    cm = np.zeros((NUM_CLASSES, NUM_CLASSES), np.int64)
    t0 = time.time()
    for img, lab in frames:
        small = model_input(img, width, height, crop_top)
        blob = ((small.astype(np.float32) / 255.0 - MEAN) / STD).transpose(2, 0, 1)[None].copy()
        net.setInput(blob)
        out = net.forward()[0]
        road = img.shape[0] - crop_top
        up = np.stack([cv2.resize(c, (img.shape[1], road), interpolation=cv2.INTER_LINEAR) for c in out])
        pred = np.zeros(lab.shape, np.int64)
        pred[crop_top:] = up.argmax(0)
        cm += confusion(lab, pred)
    return cm, (time.time() - t0) / max(1, len(frames))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--train", nargs="+", required=True)
    ap.add_argument("--val", nargs="+", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--width", type=int, default=480)
    ap.add_argument("--height", type=int, default=176)
    ap.add_argument("--crop-top", type=int, default=120,
                    help="camera rows above the road not given to the model (segmenter: model.crop_top)")
    ap.add_argument("--logits", choices=["full", "half"], default="full",
                    help="full: logits at the input resolution (v2); half: at 1/2 (v1)")
    ap.add_argument("--arch", choices=sorted(ARCHS), default="v3", help="network size (model.py ARCHS)")
    ap.add_argument("--dice", type=float, default=0.0, help="weight of the soft Dice loss added to cross-entropy")
    ap.add_argument("--steps", type=int, default=900)
    ap.add_argument("--batch", type=int, default=8)
    ap.add_argument("--lr", type=float, default=4e-3)
    ap.add_argument("--weight-decay", type=float, default=1e-4)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--max-minutes", type=float, default=0.0,
                    help="training time cap; the learning-rate schedule follows it (0: no cap)")
    ap.add_argument("--val-every", type=int, default=0, help="steps between quick validations (0: only at the end)")
    args = ap.parse_args()
    if args.width % 32 or args.height % 16:
        ap.error("--width must be a multiple of 32 and --height of 16 (four stride-2 stages, logits at 1/2)")
    torch.set_num_threads(args.threads)
    torch.manual_seed(args.seed)
    np.random.seed(args.seed)
    random.seed(args.seed)

    t_load = time.time()
    xtr, ytr, _, names = load_set(args.train, args.width, args.height, args.crop_top, False)
    xva, yva, val_full, _ = load_set(args.val, args.width, args.height, args.crop_top, True)
    print("train %d frames, val %d frames, loaded in %.0f s" % (len(xtr), len(xva), time.time() - t_load), flush=True)

    freq = np.bincount(ytr.ravel(), minlength=NUM_CLASSES).astype(float)
    freq /= freq.sum()
    present = freq > 0
    med = np.median(freq[present])
    weights = np.where(present, np.clip(np.sqrt(med / np.maximum(freq, 1e-12)), 0.25, 5.0), 1.0)
    print("class frequency", np.round(freq, 4).tolist())
    print("class weights  ", np.round(weights, 2).tolist(), flush=True)
    wt = torch.tensor(weights, dtype=torch.float32)

    net = LaneSegNet(logits=args.logits, **ARCHS[args.arch])

    def forward_full(x):
        out = net(x)
        return out if args.logits == "full" else F.interpolate(out, scale_factor=2.0, mode="bilinear",
                                                               align_corners=False)

    def dice_loss(logits, y):
        # 1 - soft Dice per class, averaged over the foreground classes present in the batch.
        # Per-class sums by index, without building an N x C x H x W one-hot tensor.
        p = torch.softmax(logits, 1)
        flat = y.reshape(-1)
        p_true = p.gather(1, y.unsqueeze(1)).reshape(-1)           # probability of each pixel's class
        inter = torch.zeros(NUM_CLASSES, dtype=p.dtype).index_add(0, flat, p_true)
        count = torch.bincount(flat, minlength=NUM_CLASSES).to(p.dtype)
        card = p.sum((0, 2, 3)) + count
        present = count[1:] > 0
        d = 1.0 - (2.0 * inter[1:] + 1.0) / (card[1:] + 1.0)
        return d[present].mean() if bool(present.any()) else logits.sum() * 0.0

    opt = torch.optim.AdamW(net.parameters(), lr=args.lr, weight_decay=args.weight_decay)

    def progress(step):
        # Fraction of the run done: by steps, or by time when --max-minutes caps it first (then the
        # schedule still anneals fully before the cap).
        p = step / args.steps
        if args.max_minutes > 0:
            p = max(p, (time.time() - t0) / (60.0 * args.max_minutes))
        return min(1.0, p)

    def lr_at(step):
        p = progress(step)
        if p < 0.05:
            return args.lr * max(p, 1.0 / args.steps) / 0.05
        q = (p - 0.05) / 0.95
        return args.lr * (0.02 + 0.98 * 0.5 * (1 + math.cos(math.pi * q)))

    def quick_val():
        net.eval()
        cm = np.zeros((NUM_CLASSES, NUM_CLASSES), np.int64)
        with torch.no_grad():
            for i in range(0, len(xva), 16):
                logits = forward_full(to_input(xva[i:i + 16]))
                cm += confusion(yva[i:i + 16], logits.argmax(1).numpy())
        net.train()
        return ious(cm)

    t0 = time.time()
    n = len(xtr)
    order = np.random.permutation(n)
    pos = 0
    losses = []
    steps_done = 0
    for step in range(args.steps):
        if progress(step) >= 1.0:
            print("time cap (--max-minutes) reached at step %d" % step, flush=True)
            break
        steps_done = step + 1
        if pos + args.batch > n:
            order = np.random.permutation(n)
            pos = 0
        idx = order[pos:pos + args.batch]
        pos += args.batch
        x = to_input(xtr[idx])
        # Photometric jitter on top of the rendered conditions: gain, offset, per-channel tint.
        g = 1.0 + 0.25 * (torch.rand(len(idx), 1, 1, 1) * 2 - 1)
        b = 0.3 * (torch.rand(len(idx), 1, 1, 1) * 2 - 1)
        tint = 0.15 * (torch.rand(len(idx), 3, 1, 1) * 2 - 1)
        x = x * g + b + tint
        y = torch.from_numpy(ytr[idx]).long()
        for gparam in opt.param_groups:
            gparam["lr"] = lr_at(step)
        logits = forward_full(x)
        loss = F.cross_entropy(logits, y, weight=wt)
        if args.dice > 0:
            loss = loss + args.dice * dice_loss(logits, y)
        opt.zero_grad()
        loss.backward()
        opt.step()
        losses.append(loss.item())
        if (step + 1) % 25 == 0:
            el = time.time() - t0
            print("step %d/%d loss %.4f lr %.5f  %.1f s/step  elapsed %.1f min" %
                  (step + 1, args.steps, np.mean(losses[-25:]), lr_at(step), el / (step + 1), el / 60), flush=True)
        if args.val_every and (step + 1) % args.val_every == 0:
            iou = quick_val()
            print("  val IoU (input grid):", " ".join("%s %.3f" % (c[:10], v) for c, v in zip(CLASS_NAMES, iou)),
                  flush=True)
    train_s = time.time() - t0

    # Export (BatchNorm folded by constant folding) and score through OpenCV DNN at 640x360.
    net.eval()
    dummy = torch.zeros(1, 3, args.height, args.width)
    torch.onnx.export(net, dummy, args.out, input_names=["image"], output_names=["logits"], opset_version=11,
                      do_constant_folding=True)
    with torch.no_grad():
        ref = net(to_input(xva[:1])).numpy()
    cvnet = cv2.dnn.readNetFromONNX(args.out)
    cvnet.setInput(to_input(xva[:1]).numpy())
    diff = float(np.abs(cvnet.forward() - ref).max())
    print("ONNX via cv2.dnn vs torch: max |diff| %.2e" % diff, flush=True)
    cm, infer_s = evaluate_cv_dnn(args.out, val_full, args.width, args.height, args.crop_top)
    iou = ious(cm)
    miou = float(np.nanmean(iou))
    for c, v in zip(CLASS_NAMES, iou):
        print("  val IoU %-17s %.3f" % (c, v))
    print("  val mIoU (11 classes) %.3f, pixel accuracy %.3f" % (miou, np.trace(cm) / cm.sum()), flush=True)
    report = {
        "model": os.path.basename(args.out),
        "input": {"width": args.width, "height": args.height, "crop_top": args.crop_top, "channels": "RGB",
                  "scale": 1 / 255.0, "mean": [MEAN] * 3, "std": [STD] * 3},
        "output": {"logits_width": args.width // (1 if args.logits == "full" else 2),
                   "logits_height": args.height // (1 if args.logits == "full" else 2), "classes": CLASS_NAMES},
        "loss": {"cross_entropy_class_weights": True, "dice": args.dice},
        "params": int(sum(p.numel() for p in net.parameters())),
        "train_frames": int(len(xtr)), "val_frames": int(len(xva)),
        "train_dirs": args.train, "val_dirs": args.val,
        "steps": steps_done, "batch": args.batch, "lr": args.lr, "seed": args.seed,
        "train_seconds": round(train_s, 1), "threads": args.threads,
        "machine": "%s, %d cores (%s)" % (platform.processor() or platform.machine(), os.cpu_count(), platform.platform()),
        "torch": torch.__version__, "opencv": cv2.__version__,
        "final_loss": float(np.mean(losses[-25:])) if losses else None,
        "class_weights": [round(float(w), 3) for w in weights],
        "val_iou": {c: (None if np.isnan(v) else round(float(v), 4)) for c, v in zip(CLASS_NAMES, iou)},
        "val_miou": round(miou, 4),
        "val_pixel_accuracy": round(float(np.trace(cm) / cm.sum()), 4),
        "cv_dnn_seconds_per_frame": round(infer_s, 4),
        "onnx_vs_torch_max_abs_diff": diff,
    }
    with open(os.path.splitext(args.out)[0] + ".json", "w") as f:
        json.dump(report, f, indent=2)
    print("wrote %s (%.0f KB) in %.1f min of training" % (args.out, os.path.getsize(args.out) / 1024, train_s / 60))


if __name__ == "__main__":
    main()

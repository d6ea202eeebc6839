#!/usr/bin/env python3
"""The broad benchmark's table (tools/bench/quality.sh): lanemap-eval --driven reports of every
drive in OUT_DIR, pooled per network and over all networks, per label source, beside the paper.

Pooling: precision and recall from summed counts (detections / built or truth lanes; correct /
built or truth intersection pairs); centre-line RMS and mIoU averaged over the matched lanes of
all drives, connection RMS over the correct pairs (each drive's mean weighted by its count).
A drive whose mapping failed outright is scored as an empty map: every driven truth lane and
pair missed.

Below each table, where the misses are (pooled): the truth lanes not detected, split into those no
built lane matched and those matched by a lane too far off or too short to be a detection (and how
many of either lie on roads under 10 m long); the built lanes that detect nothing; the truth pairs
missed and the built pairs wrong, split by whether both of their lanes were detected (a pair into
a lane not found cannot be right: lane recall bounds junction recall). quality.json has the same
per network under "misses".

Below that, the maps that fail one of lanemap-check's requirements (Autoware's, beyond
Lanelet2's validator: shared borders, bounds apart, ...), from the check-LABEL.txt quality.sh
keeps beside each map: how many of the maps checked, and which requirements (quality.json:
"lanemap_check").

With --trained-on a,b,c (the networks whose frames the segmentation model was trained on;
quality.sh passes TRAINED_ON) two more pooled rows for the model's labels split the networks by
whether the model saw them. (The shipped model's Monaco frames came from seeds 1-40, the
benchmark's seeds among them; train.sh's RECIPE=many renders seeds 201 and up.)

With --compare A B (two of the labels: a map before and after a change, e.g. quality.sh's
"model" and "model-TAG"; given once per pair), a last table lists each network whose figures differ between A and B,
A's row above B's, then both pooled rows, the networks beating the paper under each, and under
each the maps that fail lanemap-check, by name: what a
change to the mapping stages did, network by network (judge it on the pooled rows and on every
network it made worse).

Usage: quality_table.py OUT_DIR LABEL [LABEL ...] [--trained-on NET,NET,...] [--compare A B ...]
       (also writes OUT_DIR/quality.json)
"""
import json
import math
import os
import sys

PAPER = {"lane_p": 0.84, "lane_r": 0.73, "rms": 0.24, "miou": 0.79, "junc_p": 0.91, "junc_r": 0.80, "conn_rms": 0.24}
# METHOD.md section 6, Berkeley, camera only (what LIDAR=0 compares with)
PAPER_CAM = {"lane_p": 0.64, "lane_r": 0.56, "rms": 0.25, "miou": 0.73, "junc_p": 0.90, "junc_r": 0.81, "conn_rms": 0.30}
KEYS = ["lane_p", "lane_r", "rms", "miou", "junc_p", "junc_r", "conn_rms"]


def load(path):
    with open(path) as f:
        return json.load(f)


def counts(j):
    lanes, inter = j["lanes"], j["intersections"]
    num = lambda v: v if isinstance(v, (int, float)) and v is not None and math.isfinite(v) else None
    return {
        "drives": 1, "failed": 0,
        "det": lanes["detected"], "built": lanes["built"], "truth": lanes["truth"], "matched": lanes["matched"],
        "rms_sum": (num(lanes["rms_m"]) or 0.0) * lanes["matched"] if num(lanes["rms_m"]) is not None else 0.0,
        "rms_n": lanes["matched"] if num(lanes["rms_m"]) is not None else 0,
        "iou_sum": (num(lanes["miou"]) or 0.0) * lanes["matched"],
        "ok": inter["correct_pairs"], "bp": inter["built_pairs"], "tp": inter["truth_pairs"],
        "crms_sum": (num(inter["rms_m"]) or 0.0) * inter["correct_pairs"] if num(inter["rms_m"]) is not None else 0.0,
        "crms_n": inter["correct_pairs"] if num(inter["rms_m"]) is not None else 0,
    }


def misses(j):
    """Counts of what lanemap-eval's --json detail says was missed or wrong (see the docstring)."""
    m = {"lanes_unmatched": 0, "lanes_not_detected": 0, "lanes_missed_short": 0, "built_false": 0,
         "built_false_matched": 0, "pairs_missed_lane": 0, "pairs_missed_both_detected": 0,
         "pairs_wrong_lane": 0, "pairs_wrong_both_detected": 0}
    detected = {"truth": {}, "built": {}}
    for side, key in (("truth", "lanes_detail"), ("built", "built_lanes_detail")):
        for lane in j.get(key, []):
            for ll in lane.get("lanelets", []):
                detected[side][ll] = bool(lane.get("detected"))
            if lane.get("detected"):
                continue
            if side == "truth":
                m["lanes_unmatched" if not lane.get("built_lanelets") else "lanes_not_detected"] += 1
                m["lanes_missed_short"] += int(lane.get("length_m", 0.0) < 10.0)
            else:
                m["built_false"] += 1
                m["built_false_matched"] += int(bool(lane.get("truth_lanelets")))
    inter = j.get("intersections", {})
    for side, key, prefix in (("truth", "truth_pair_detail", "pairs_missed"), ("built", "built_pair_detail", "pairs_wrong")):
        for p in inter.get(key, []):
            if p.get("correct"):
                continue
            both = all(detected[side].get(p.get(end, {}).get("lanelet"), False) for end in ("in", "out"))
            m[prefix + ("_both_detected" if both else "_lane")] += 1
    return m


def misses_line(m):
    lanes = m.get("lanes_unmatched", 0) + m.get("lanes_not_detected", 0)
    pairs = m.get("pairs_missed_lane", 0) + m.get("pairs_missed_both_detected", 0)
    wrong = m.get("pairs_wrong_lane", 0) + m.get("pairs_wrong_both_detected", 0)
    return (f"   misses: truth lanes {lanes} ({m.get('lanes_unmatched', 0)} no built lane, "
            f"{m.get('lanes_not_detected', 0)} matched but not detected; {m.get('lanes_missed_short', 0)} on roads "
            f"under 10 m); built lanes detecting nothing {m.get('built_false', 0)} "
            f"({m.get('built_false_matched', 0)} matched a truth lane); truth pairs {pairs} "
            f"({m.get('pairs_missed_lane', 0)} with a lane not detected); wrong pairs {wrong} "
            f"({m.get('pairs_wrong_both_detected', 0)} between detected lanes)")


def lanemap_check(out, drives, lab):
    """The maps of `lab` that lanemap-check failed (its FAIL lines in check-LAB.txt), by requirement."""
    maps, failing, requirements, failing_maps = 0, 0, {}, []
    for d in drives:
        p = os.path.join(out, d, f"check-{lab}.txt")
        if not os.path.exists(p):
            continue
        maps += 1
        with open(p) as f:
            failed = [line.split()[1] for line in f if line.startswith("FAIL") and len(line.split()) > 1]
        failing += bool(failed)
        if failed:
            failing_maps.append(d)
        for r in failed:
            requirements[r] = requirements.get(r, 0) + 1
    return {"maps": maps, "failing": failing, "requirements": requirements, "failing_maps": failing_maps}


def check_line(check, label=None):
    """lanemap-check's verdict as one line; with `label`, naming the failing maps too."""
    which = ", ".join(f"{k} {v}" for k, v in sorted(check["requirements"].items()))
    line = f"   lanemap-check{' under ' + label if label else ''}: {check['failing']} of {check['maps']} maps fail a requirement"
    line += f" ({which})" if which else ""
    if label and check["failing_maps"]:
        line += ": " + ", ".join(check["failing_maps"])
    return line


def add(a, b):
    return {k: a.get(k, 0) + b.get(k, 0) for k in set(a) | set(b)}


def ratio(a, b):
    return a / b if b else float("nan")


def figures(c):
    return {
        "lane_p": ratio(c.get("det", 0), c.get("built", 0)), "lane_r": ratio(c.get("det", 0), c.get("truth", 0)),
        "rms": ratio(c.get("rms_sum", 0), c.get("rms_n", 0)), "miou": ratio(c.get("iou_sum", 0), c.get("matched", 0)),
        "junc_p": ratio(c.get("ok", 0), c.get("bp", 0)), "junc_r": ratio(c.get("ok", 0), c.get("tp", 0)),
        "conn_rms": ratio(c.get("crms_sum", 0), c.get("crms_n", 0)),
    }


def fmt(v):
    return "   -  " if v is None or (isinstance(v, float) and math.isnan(v)) else f"{v:6.3f}"


def trained_networks(argv):
    """--trained-on NET,NET,... (removed from argv): the networks the model was trained on."""
    if "--trained-on" not in argv:
        return set()
    i = argv.index("--trained-on")
    names = argv[i + 1].split(",") if i + 1 < len(argv) else []
    del argv[i:i + 2]
    return set(n for n in names if n)


def compare_labels(argv):
    """Every --compare A B (removed from argv): the pairs of labels to compare."""
    pairs = []
    while "--compare" in argv:
        i = argv.index("--compare")
        pair = argv[i + 1:i + 3]
        del argv[i:i + 3]
        if len(pair) != 2:
            sys.exit("quality_table.py: --compare needs two labels")
        pairs.append(pair)
    return pairs


def row(name, c):
    f = figures(c)
    return (f"   {name:28s} {c.get('drives', 0):6d} " + " ".join(fmt(f[k]) for k in KEYS) +
            f"  {c.get('det', 0):6d}/{c.get('built', 0):6d}/{c.get('truth', 0):6d}"
            f"   {c.get('ok', 0):5d}/{c.get('bp', 0):5d}/{c.get('tp', 0):5d}")


def beats_paper(c):
    return all(figures(c)[k] > PAPER[k] for k in ("lane_p", "lane_r", "junc_p", "junc_r"))


def print_comparison(result, a, b):
    if a not in result or b not in result:
        sys.exit(f"quality_table.py: --compare {a} {b}: both must be among the labels")
    na, nb = result[a]["networks"], result[b]["networks"]
    print(f"\n== {a} -> {b}: the networks whose figures differ ({a} above, {b} below)")
    changed = 0
    for n in sorted(set(na) | set(nb)):
        ca, cb = na.get(n, {}).get("counts", {}), nb.get(n, {}).get("counts", {})
        if row(n, ca) == row(n, cb):
            continue
        changed += 1
        print(row(n, ca))
        print(row(n, cb))
    print(f"   {changed} of {len(set(na) | set(nb))} networks changed")
    print(row(f"POOLED {a}", result[a]["pooled"]["counts"]))
    print(row(f"POOLED {b}", result[b]["pooled"]["counts"]))
    for lab, nets in ((a, na), (b, nb)):
        beat = sorted(n for n, v in nets.items() if beats_paper(v["counts"]))
        print(f"   beating the paper under {lab}: {len(beat)} ({', '.join(beat)})")
    # A map the change made fail lanemap-check is named here, beside the scores, not only in the
    # label's own table above.
    for lab in (a, b):
        if "lanemap_check" in result[lab]:
            print(check_line(result[lab]["lanemap_check"], lab))


def main():
    argv = sys.argv[1:]
    trained = trained_networks(argv)
    compare = compare_labels(argv)
    out, labels = argv[0], argv[1:]
    drives = sorted(d for d in os.listdir(out) if os.path.isdir(os.path.join(out, d, "drive")))
    result = {}
    for lab in labels:
        per_net, total, per_net_misses, total_misses = {}, {}, {}, {}
        for d in drives:
            net = d.rsplit("-s", 1)[0]
            p = os.path.join(out, d, f"eval-{lab}.json")
            if not os.path.exists(p):
                continue
            j = load(p)
            c = counts(j)
            c["failed"] = int(os.path.exists(os.path.join(out, d, f"map-{lab}", "FAILED")))
            per_net[net] = add(per_net.get(net, {}), c)
            total = add(total, c)
            m = misses(j)
            per_net_misses[net] = add(per_net_misses.get(net, {}), m)
            total_misses = add(total_misses, m)
        result[lab] = {"networks": {n: {**figures(c), "counts": c, "misses": per_net_misses[n]} for n, c in per_net.items()},
                       "pooled": {**figures(total), "counts": total, "misses": total_misses}}
        print(f"\n== labels: {lab} (lanemap-eval --driven; {total.get('drives', 0)} drives, "
              f"{total.get('failed', 0)} whose mapping failed outright)")
        head = f"   {'network':28s} {'drives':>6s} {'lane P':>6s} {'lane R':>6s} {'RMS m':>6s} {'mIoU':>6s} " \
               f"{'junc P':>6s} {'junc R':>6s} {'conn m':>6s}  {'lanes det/built/truth':>22s} {'pairs ok/built/truth':>21s}"
        print(head)
        rows = sorted(per_net.items()) + [("POOLED", total)]
        if lab != "oracle" and trained & set(per_net):
            # The networks pooled by whether the model was trained on them.
            result[lab]["groups"] = {}
            for group, member in (("model trained on", lambda n: n in trained),
                                  ("model never saw", lambda n: n not in trained)):
                nets = sorted(n for n in per_net if member(n))
                c = {}
                for n in nets:
                    c = add(c, per_net[n])
                if nets:
                    rows.append((f"POOLED, {group} ({len(nets)})", c))
                    result[lab]["groups"][group] = {**figures(c), "counts": c, "networks": nets}
        for n, c in rows:
            print(row(n, c))
        print(f"   {'paper (Berkeley LIDAR+Cam)':28s} {'':6s} " + " ".join(fmt(PAPER[k]) for k in KEYS))
        print(f"   {'paper (Berkeley Cam only)':28s} {'':6s} " + " ".join(fmt(PAPER_CAM[k]) for k in KEYS))
        beat = [n for n, c in per_net.items() if beats_paper(c)]
        print(f"   networks that beat the paper on lane P/R and junction P/R: {len(beat)} of {len(per_net)}")
        print(misses_line(total_misses))
        check = lanemap_check(out, drives, lab)
        if check["maps"]:
            result[lab]["lanemap_check"] = check
            print(check_line(check))
    for pair in compare:
        print_comparison(result, *pair)
    clean = lambda v: {k: clean(x) for k, x in v.items()} if isinstance(v, dict) else (
        None if isinstance(v, float) and math.isnan(v) else v)
    with open(os.path.join(out, "quality.json"), "w") as f:
        json.dump(clean(result), f, indent=2)


if __name__ == "__main__":
    main()

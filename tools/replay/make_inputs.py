#!/usr/bin/python3
"""Records the process replay inputs of tests/replay from a simulated drive (run once; the inputs
are then kept in the repository, as a recording would be).

  lanemap-sim --osm data/osm/west-oakland.osm --out D --seed 7 --duration 18 --camera-hz 5
  tools/replay/make_inputs.py D build/bin tests/replay

road_tracker.input.lcmlog: the drive's POSE, every 4th (25 Hz).
segmenter.input.lcmlog:    every 15th CAMERA_FRONT frame (JPEG, 640x360): 7 frames.
bev_builder.input.lcmlog:  those poses, SEMANTIC_FRONT_TRUTH (5 Hz) and the ROAD_EVENTs the road
                           tracker publishes on them (its replay), in time order.
roads.osm:                 the drive's road-level OSM.
An LCM log event: sync word 0xEDA1DA01, event number (int64), timestamp (int64, us), channel
length (int32), data length (int32), channel, data; all big-endian.
"""
import os
import shutil
import struct
import subprocess
import sys
import tempfile

SYNC = 0xEDA1DA01


def read_log(path):
    with open(path, "rb") as f:
        data = f.read()
    pos, events = 0, []
    while pos + 28 <= len(data):
        sync, _num, ts, clen, dlen = struct.unpack(">IqqII", data[pos:pos + 28])
        if sync != SYNC:
            raise SystemExit(f"{path}: no sync word at byte {pos}")
        pos += 28
        channel = data[pos:pos + clen].decode()
        pos += clen
        events.append((ts, channel, data[pos:pos + dlen]))
        pos += dlen
    return events


def write_log(path, events):
    with open(path, "wb") as f:
        for n, (ts, channel, payload) in enumerate(events):
            c = channel.encode()
            f.write(struct.pack(">IqqII", SYNC, n, ts, len(c), len(payload)) + c + payload)


def main():
    if len(sys.argv) != 4:
        raise SystemExit(__doc__)
    drive, bin_dir, out = sys.argv[1:]
    events = read_log(os.path.join(drive, "drive.lcmlog"))
    poses = [e for e in events if e[1] == "POSE"][::4]
    labels = [e for e in events if e[1] == "SEMANTIC_FRONT_TRUTH"]
    os.makedirs(out, exist_ok=True)
    shutil.copyfile(os.path.join(drive, "roads.osm"), os.path.join(out, "roads.osm"))
    write_log(os.path.join(out, "road_tracker.input.lcmlog"), poses)
    frames = [e for e in events if e[1] == "CAMERA_FRONT"][::15]
    write_log(os.path.join(out, "segmenter.input.lcmlog"), frames)
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    with tempfile.TemporaryDirectory() as tmp:
        rt_out = os.path.join(tmp, "rt.lcmlog")
        subprocess.run([os.path.join(bin_dir, "lanemap-road-tracker"), "--config", "config/road_tracker.yaml",
                        "--osm", os.path.join(out, "roads.osm"), "--replay", os.path.join(out, "road_tracker.input.lcmlog"),
                        "--replay-out", rt_out], check=True, cwd=root)
        road_events = [e for e in read_log(rt_out) if e[1] == "ROAD_EVENT"]
    # The road tracker answers a pose: its events go right after that pose (a stable sort keeps it).
    merged = sorted(poses + road_events + labels, key=lambda e: (e[0], {"POSE": 0, "ROAD_EVENT": 1}.get(e[1], 2)))
    write_log(os.path.join(out, "bev_builder.input.lcmlog"), merged)
    print(f"{len(poses)} poses, {len(labels)} label frames, {len(road_events)} road events, {len(frames)} camera frames -> {out}")


if __name__ == "__main__":
    main()

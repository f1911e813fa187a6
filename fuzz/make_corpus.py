#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Seed corpora of the libFuzzer targets (fuzz/) from a real recording and the
project's files: windows of a recording's messages in the targets' record format
(fuzz/fuzz_input.hpp: [channel index][length, 2 bytes LE][payload]), the configs,
and state files.

    fuzz/make_corpus.py --log RUN.lcmlog [--robot-state FILE] [--main-state FILE]
                        [--team-robot-state FILE] [--out fuzz/corpus]

Writes OUT/fuzz_robot_node/ (robot 1's inputs: SENSOR_1, DYNAMIC_NOTICE, GLOBAL_MOVING,
LMAP_RESYNC, POSE_1), OUT/fuzz_main_robot/ (LMAP_EVENT, LMAP_SNAPSHOT, POSE_1, POSE_2,
POSE_3, POSE_7, LMAP_EVENTS, TRACKS_1, TRACKS_2), OUT/fuzz_viewer/ (RUN_INFO, POSE_1-3, GLOBAL_MAP, DYNAMIC_NOTICE,
STATUS_ROBOT_1, CANDIDATES_1, GROUND_TRUTH, TRACKS_1, GLOBAL_TRACKS), each a few windows of consecutive frames from the first frame on;
OUT/fuzz_state/ (the state files with fuzz_state's selector byte: raw and sealed
robot state, main state, and robot 1's state from a run with the team's map on
(robot.team_map.fuse, main.team_map_period_frames), sealed); OUT/fuzz_mrclam/ (tests/dataset/data/tiny, robot 1). The
config corpus is config/*.yaml (copied). Needs the PyPI lcm (the project's .venv).
"""
import argparse
import os
import shutil
import struct
import sys

_here = os.path.dirname(os.path.realpath(__file__))
sys.path.insert(0, os.path.join(_here, "..", "tools"))
from elaslam_tool import add_version, need, parse_args, run_in_venv  # noqa: E402

ROBOT = ["SENSOR_1", "DYNAMIC_NOTICE", "GLOBAL_MOVING", "LMAP_RESYNC", "POSE_1"]
MAIN = ["LMAP_EVENT", "LMAP_SNAPSHOT", "POSE_1", "POSE_2", "POSE_3", "POSE_7", "LMAP_EVENTS", "TRACKS_1",
        "TRACKS_2"]  # fuzz_main_robot's order
VIEWER = ["RUN_INFO", "POSE_1", "POSE_2", "POSE_3", "GLOBAL_MAP", "DYNAMIC_NOTICE", "STATUS_ROBOT_1", "CANDIDATES_1",
          "GROUND_TRUTH", "TRACKS_1", "GLOBAL_TRACKS"]
MRCLAM = ["Barcodes.dat", "Landmark_Groundtruth.dat", "Robot1_Odometry.dat", "Robot1_Groundtruth.dat",
          "Robot1_Measurement.dat"]
# Windows of SENSOR_1 / POSE frames: [first, last) counted in robot 1's frames.
WINDOWS = [(0, 3), (0, 12), (0, 40), (10, 25), (60, 75)]
MAX_BYTES = 60000  # per corpus file


def record(index, payload):
    return struct.pack("<BH", index, min(len(payload), 0xFFFF)) + payload[:0xFFFF]


def windows(events, channels, frame_channel):
    """Per window, the records of `channels` between the frame_channel messages that
    open frame `first` and `last`."""
    out = []
    for first, last in WINDOWS:
        frame, buf = -1, b""
        for ch, data in events:
            if ch == frame_channel:
                frame += 1
            if ch not in channels or frame < first:
                continue
            if frame >= last or len(buf) > MAX_BYTES:
                break
            buf += record(channels.index(ch), data)
        if buf:
            out.append(buf)
    return out


def write(out_dir, name, blobs):
    d = os.path.join(out_dir, name)
    os.makedirs(d, exist_ok=True)
    for i, b in enumerate(blobs):
        with open(os.path.join(d, f"seed{i:02d}"), "wb") as f:
            f.write(b)
    print(f"make_corpus: {d}: {len(blobs)} files, {sum(map(len, blobs))} bytes")


def main():
    run_in_venv()
    ap = argparse.ArgumentParser(prog="make_corpus.py", description=__doc__.split("\n\n")[0])
    add_version(ap)
    ap.add_argument("--log", required=True)
    ap.add_argument("--robot-state")
    ap.add_argument("--main-state")
    ap.add_argument("--team-robot-state")
    ap.add_argument("--out", default=os.path.join(_here, "corpus"))
    args = parse_args(ap)
    lcm = need("lcm")
    events = [(ev.channel, bytes(ev.data)) for ev in lcm.EventLog(args.log, "r")]
    write(args.out, "fuzz_robot_node", windows(events, ROBOT, "SENSOR_1"))
    write(args.out, "fuzz_main_robot", windows(events, MAIN, "POSE_1"))
    write(args.out, "fuzz_viewer", windows(events, VIEWER, "POSE_1"))
    states = []
    if args.robot_state:
        text = open(args.robot_state, "rb").read()
        states += [b"\x00" + text, b"\x01" + text]
    if args.main_state:
        states.append(b"\x02" + open(args.main_state, "rb").read())
    if args.team_robot_state:
        states.append(b"\x03" + open(args.team_robot_state, "rb").read())
    if states:
        write(args.out, "fuzz_state", states)
    tiny = os.path.join(_here, "..", "tests", "dataset", "data", "tiny")
    blob = b""
    for i, name in enumerate(MRCLAM):
        data = open(os.path.join(tiny, name), "rb").read()
        for k in range(0, len(data), 0xFFFF):
            blob += record(i, data[k:k + 0xFFFF])
    write(args.out, "fuzz_mrclam", [blob])
    cfg = os.path.join(args.out, "fuzz_config")
    os.makedirs(cfg, exist_ok=True)
    for name in sorted(os.listdir(os.path.join(_here, "..", "config"))):
        if name.endswith(".yaml"):
            shutil.copy(os.path.join(_here, "..", "config", name), os.path.join(cfg, name))
    print(f"make_corpus: {cfg}: the configs")


if __name__ == "__main__":
    main()

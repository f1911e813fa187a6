#!/usr/bin/env python3
"""Decode an elaslam LCM log with the Python bindings (PyPI `lcm`) and the
generated types (build/lcmgen/python): per-channel counts and the last POSE and
GLOBAL_MAP in brief. Exit 1 if any event on one of our channels fails to decode.

    .venv/bin/python tools/decode_log.py LOG [--build-dir build]
"""
import argparse
import collections
import os
import re
import sys


def main() -> int:
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("log")
    ap.add_argument("--build-dir", default=os.path.join(root, "build"))
    args = ap.parse_args()
    sys.path.insert(0, os.path.join(args.build_dir, "lcmgen", "python"))
    import lcm  # noqa: E402  (the PyPI wheel, in .venv)
    from elaslam import (dynamic_notice_t, global_map_t, ground_truth_t, landmark_event_t,  # noqa: E402
                         lmap_snapshot_t, node_status_t, pose_estimate_t, sensor_frame_t)

    types = [(r"SENSOR_\d+", sensor_frame_t), (r"POSE_\d+", pose_estimate_t), (r"GROUND_TRUTH", ground_truth_t),
             (r"LMAP_EVENT", landmark_event_t), (r"LMAP_SNAPSHOT", lmap_snapshot_t), (r"GLOBAL_MAP", global_map_t),
             (r"DYNAMIC_NOTICE", dynamic_notice_t), (r"STATUS_.*", node_status_t)]
    if not os.path.exists(args.log):
        print(f"decode_log: no such log: {args.log}", file=sys.stderr)
        return 2
    counts, errors, last = collections.Counter(), collections.Counter(), {}
    for ev in lcm.EventLog(args.log, "r"):
        for pattern, cls in types:
            if re.fullmatch(pattern, ev.channel):
                try:
                    last[ev.channel] = cls.decode(ev.data)
                    counts[ev.channel] += 1
                except Exception:  # a corrupt or foreign event on our channel
                    errors[ev.channel] += 1
                break
    for ch in sorted(counts):
        print(f"{ch:16s} {counts[ch]:6d} decoded" + (f", {errors[ch]} failed" if errors[ch] else ""))
    if "POSE_1" in last:
        p = last["POSE_1"]
        print(f"last POSE_1: frame {p.frame}, x {p.x:.3f} y {p.y:.3f} theta {p.theta:.3f}, {p.num_landmarks} landmarks")
    if "GLOBAL_MAP" in last:
        g = last["GLOBAL_MAP"]
        print(f"last GLOBAL_MAP: frame {g.frame}, version {g.version}, {g.num_landmarks} static, {g.num_moving} moving")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())

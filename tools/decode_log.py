#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Decode an elaslam LCM log with the Python bindings (PyPI `lcm`) and the
generated message types: per-channel counts, the run (RUN_INFO) and the last POSE
and GLOBAL_MAP in brief. Exit 1 if any event on one of our channels fails to
decode, 2 on a bad command line, a missing log or a missing module.

    tools/decode_log.py LOG [--build-dir DIR]

The generated Python types come from DIR/lcmgen/python with --build-dir; without
it from $ELASLAM_BUILD_DIR/lcmgen/python, the installed
<prefix>/share/elaslam/python, or the source tree's build/lcmgen/python.
In a source tree the script runs itself in the project's .venv (tools/setup.sh
makes it, with the PyPI `lcm`); an installed copy runs with the python3 that
starts it, which needs `lcm` from PyPI (Debian has no package for it).
"""
# ---- start-up: standard library only, before any third-party import (tools/elaslam_tool.py)
import os
import sys

_here = os.path.dirname(os.path.realpath(__file__))
sys.path[:0] = [_here, os.path.join(_here, "..", "share", "elaslam", "tools")]
from elaslam_tool import doc_parser, load_lcm_types, need as _need, parse_args as _parse, run_in_venv  # noqa: E402

PROG = "decode_log"

if __name__ == "__main__":
    run_in_venv()
# ----------------------------------------------------------------------------------
import collections  # noqa: E402
import re  # noqa: E402


def fmt_known(value, unit="", none=-1):
    return "unknown" if value == none else f"{value:g}{unit}"


def describe_run_info(m):
    robots = " ".join(str(r) for r in m.robot_ids[:m.num_robots])
    seed = "none" if m.seed < 0 else str(m.seed)
    return (f"run info: source {m.source}, scenario {m.scenario}, mode {m.mode or 'unknown'}, seed {seed}, "
            f"dynamism {fmt_known(m.dynamism_percent, ' %')}, speed {fmt_known(m.landmark_speed_mps, ' m/s')}, "
            f"rate {m.rate_hz:g} Hz, frames {m.frames}, robots {robots}\n"
            f"          last at frame {m.frame}; {m.version}")


def main() -> int:
    ap = doc_parser("decode_log.py", __doc__)
    ap.add_argument("log", help="an LCM log (lcm-logger, tools/run_team.sh: runs/team_<time>/run.lcmlog)")
    ap.add_argument("--build-dir", help="the build directory whose lcmgen/python has the message types")
    args = _parse(ap)
    if not os.path.isfile(args.log):
        print(f"{PROG}: no such log: {args.log}", file=sys.stderr)
        return 2
    lcm = _need("lcm")
    T = load_lcm_types(args.build_dir, __file__)

    # Every channel of common/include/elaslam/common/channels.hpp with its type (as
    # logs/src/log_summary.cpp classifies them).
    types = [(r"SENSOR_\d+", T.sensor_frame_t), (r"POSE_\d+", T.pose_estimate_t), (r"GROUND_TRUTH", T.ground_truth_t),
             (r"LMAP_EVENT", T.landmark_event_t), (r"LMAP_EVENTS", T.lmap_events_t), (r"LMAP_SNAPSHOT", T.lmap_snapshot_t),
             (r"LMAP_RESYNC", T.resync_request_t), (r"GLOBAL_MAP", T.global_map_t), (r"GLOBAL_MOVING", T.global_map_t),
             (r"TEAM_MAP_\d+", T.global_map_t), (r"CANDIDATES_\d+", T.candidate_list_t),
             (r"TRACKS_\d+", T.track_list_t), (r"GLOBAL_TRACKS", T.global_tracks_t),
             (r"DYNAMIC_NOTICE", T.dynamic_notice_t), (r"STATUS_.*", T.node_status_t)]
    if hasattr(T, "run_info_t"):
        types.append((r"RUN_INFO.*", T.run_info_t))
    counts, errors, last = collections.Counter(), collections.Counter(), {}
    try:
        log = lcm.EventLog(args.log, "r")
    except Exception as e:  # not an LCM log, unreadable
        print(f"{PROG}: cannot read {args.log} as an LCM log: {e}", file=sys.stderr)
        return 2
    for ev in log:
        for pattern, cls in types:
            if re.fullmatch(pattern, ev.channel):
                try:
                    last[ev.channel] = cls.decode(ev.data)
                    counts[ev.channel] += 1
                except Exception:  # a corrupt or foreign event on our channel
                    errors[ev.channel] += 1
                break
    if not counts and not errors:
        print(f"{PROG}: no events on elaslam channels in {args.log} (not an LCM log, or empty?)", file=sys.stderr)
        return 1
    for ch in sorted(set(counts) | set(errors)):
        print(f"{ch:16s} {counts[ch]:6d} decoded" + (f", {errors[ch]} failed" if errors[ch] else ""))
    for ch in sorted(c for c in last if c.startswith("RUN_INFO")):
        print(describe_run_info(last[ch]))
    if "POSE_1" in last:
        p = last["POSE_1"]
        print(f"last POSE_1: frame {p.frame}, x {p.x:.3f} y {p.y:.3f} theta {p.theta:.3f}, {p.num_landmarks} landmarks")
    if "GLOBAL_MAP" in last:
        g = last["GLOBAL_MAP"]
        print(f"last GLOBAL_MAP chunk: frame {g.frame}, version {g.version}, chunk {g.chunk + 1} of {g.num_chunks}, "
              f"ids [{g.id_begin}, {g.id_end}): {g.num_landmarks} static, {g.num_moving} moving")
    if "GLOBAL_TRACKS" in last:
        g = last["GLOBAL_TRACKS"]
        print(f"last GLOBAL_TRACKS chunk: frame {g.frame}, chunk {g.chunk + 1} of {g.num_chunks}, "
              f"{g.num_tracks} fused tracks ({g.num_omitted} left out)")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())

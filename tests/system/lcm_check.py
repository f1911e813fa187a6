#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Helpers of the system tests (tests/system/*.sh): wait on live LCM traffic and
compare recorded LCM logs. Needs the PyPI `lcm` (the project's .venv) and the
generated Python types (BUILD/lcmgen/python).

  lcm_check.py --build-dir B wait-nodes N [--timeout S]
      wait until N distinct nodes published STATUS_* (robots + main) on LCM_DEFAULT_URL
  lcm_check.py --build-dir B wait-frame CHANNEL FRAME [--timeout S]
      wait until a pose_estimate_t on CHANNEL reaches FRAME
  lcm_check.py --build-dir B logged LOG [--frame F] [--since UTIME] CHANNEL...
      one look at a recording that may still be being written (lcm-logger and
      record flush every 100 ms): exit 0 when it holds a message on every CHANNEL
      (a regular expression, matched whole), with --frame one of frame F or later,
      with --since one recorded at or after UTIME (us since the epoch, the
      recorder's clock); else 1, naming what is missing. The system tests poll it with wait_for
      (tests/system/wait_for.sh) before they stop a recorder.
  lcm_check.py --build-dir B compare-poses LOG_A LOG_B --robots 1 2 3 --frames N [--tol T]
      POSE_<r> of both logs, by (robot, frame): every frame present once in both,
      max |dx|, |dy|, |dtheta| and covariance below T while the robot's input
      (SENSOR frames and the notices in effect before each) is the same;
      exit 0: all equal, 3: differences only after a robot's input differed
      (a late notice), 1: a difference with the same input or a missing pose
      (--allow-missing N: up to N frames per robot missing from a log are noted,
      not failed: the recorder's loss, when the nodes say they processed them)
  lcm_check.py --build-dir B compare-maps LOG_A LOG_B [--tol T]
      the last GLOBAL_MAP of each log: same static ids, positions within T,
      same moving ids
  lcm_check.py --build-dir B auth-refused LOG --nodes ROBOT_1 ... MAIN
      the largest auth_refused each named node reported on STATUS_<node> (exit 1
      when one reported none above 0)
  --roster R (before the command): read logs as an authenticated node does
      (docs/security.md): only events whose trailer verifies with the public key of
      their sender in the roster file R (elaslam-keys team), of R's mission (or
      --mission M), each (sender, incarnation, counter) once; forged,
      unauthenticated, other missions' and replayed events are left out (a
      recording has them: the recorder keeps all). A second implementation of the
      wire format, independent of transport/auth_transport.cpp (PyNaCl's Ed25519).
"""
# ---- start-up: standard library only, before any third-party import (tools/elaslam_tool.py)
import os
import sys

_here = os.path.dirname(os.path.realpath(__file__))
sys.path.insert(0, os.path.join(_here, "..", "..", "tools"))
from elaslam_tool import need as _need, parse_args as _parse, run_in_venv  # noqa: E402

if __name__ == "__main__":
    run_in_venv()
# ----------------------------------------------------------------------------------
import argparse  # noqa: E402
import hashlib  # noqa: E402
import math  # noqa: E402
import struct  # noqa: E402
import re  # noqa: E402
import time  # noqa: E402


def load_types(build_dir):
    sys.path.insert(0, os.path.join(build_dir, "lcmgen", "python"))
    import elaslam  # noqa: F401
    return elaslam


ROSTER = None  # --roster: {sender id: [public key bytes]}, mission; None: every event
MISSION = None
SENDERS = {"main": 100, "simulator": 101, "tool": 102, **{f"robot_{r}": r for r in range(1, 17)}}


def load_roster(path):
    """A roster file (elaslam-keys team's team.yaml): {sender id: [key, ...]} and the mission.
    Read line by line: it is the flat YAML the tool writes."""
    keys, mission = {}, None
    for line in open(path):
        name, _, value = line.strip().partition(":")
        value = value.strip().strip('"')
        if name == "mission":
            mission = int(value, 16)
        elif name in SENDERS and value:
            keys[SENDERS[name]] = [bytes.fromhex(k) for k in value.replace(",", " ").split()]
    return keys, mission


TRAILER = 98  # magic 4, sender 2, key id 4, mission 8, incarnation 8, counter 8, Ed25519 signature 64


def open_sealed(roster, mission, channel, data):
    """(payload, (sender, incarnation, counter)) when `data` carries a trailer whose
    signature verifies with its sender's key in `roster`, of `mission`, else None."""
    from nacl.exceptions import BadSignatureError  # noqa: E402
    from nacl.signing import VerifyKey  # noqa: E402
    if len(data) < TRAILER or data[-TRAILER:-TRAILER + 4] != b"ELA2":
        return None
    payload, header, sig = data[:-TRAILER], data[-TRAILER:-64], data[-64:]
    sender, key_id, msg_mission, incarnation, counter = struct.unpack(">hIQqQ", header[4:])
    key = next((k for k in roster.get(sender, []) if k[:4] == struct.pack(">I", key_id)), None)
    if key is None or msg_mission != mission:
        return None
    ch = channel.encode()
    digest = hashlib.sha512(struct.pack(">I", len(ch)) + ch + payload + header).digest()
    try:
        VerifyKey(key).verify(digest, sig)
    except BadSignatureError:
        return None
    return payload, (sender, incarnation, counter)


class _Event:
    def __init__(self, channel, data, timestamp):
        self.channel, self.data, self.timestamp = channel, data, timestamp


def read_log(path):
    lcm = _need("lcm")
    seen = set()
    for ev in lcm.EventLog(path, "r"):
        if ROSTER is None:
            yield ev
            continue
        opened = open_sealed(ROSTER, MISSION, ev.channel, ev.data)
        if opened is None or opened[1] in seen:
            continue
        seen.add(opened[1])
        yield _Event(ev.channel, opened[0], ev.timestamp)


def cmd_wait_nodes(args, T):
    lcm = _need("lcm")
    lc = lcm.LCM()
    seen = set()

    def on_status(_ch, data):
        m = T.node_status_t.decode(data)
        seen.add((m.node_kind, m.node_id))

    lc.subscribe("STATUS_.*", on_status)
    end = time.monotonic() + args.timeout
    while len(seen) < args.n and time.monotonic() < end:
        lc.handle_timeout(50)
    if len(seen) < args.n:
        print(f"wait-nodes: only {len(seen)} of {args.n} nodes announced themselves: {sorted(seen)}", file=sys.stderr)
        return 1
    return 0


def cmd_wait_frame(args, T):
    lcm = _need("lcm")
    lc = lcm.LCM()
    best = [-1]

    def on_pose(_ch, data):
        best[0] = max(best[0], T.pose_estimate_t.decode(data).frame)

    lc.subscribe(args.channel, on_pose).set_queue_capacity(10000)
    end = time.monotonic() + args.timeout
    while best[0] < args.frame and time.monotonic() < end:
        lc.handle_timeout(20)
    if best[0] < args.frame:
        print(f"wait-frame: {args.channel} reached frame {best[0]} only, wanted {args.frame}", file=sys.stderr)
        return 1
    print(best[0])
    return 0


def cmd_logged(args, T):
    lcm = _need("lcm")
    # Each message type by its fingerprint, to read the frame of any channel's message.
    types = {}
    for name in dir(T):
        fingerprint = getattr(getattr(T, name), "_get_packed_fingerprint", None)
        if fingerprint is not None:
            types[fingerprint()] = getattr(T, name)

    def frame_of(data):
        """The message's frame; None for a type this build does not know, one without
        a frame, or bytes that do not decode (a forger's datagram is recorded too)."""
        cls = types.get(data[:8])
        try:
            return getattr(cls.decode(data), "frame", None) if cls is not None else None
        except Exception:  # noqa: BLE001  (whatever the generated decoder raises on bad bytes)
            return None

    wanted = [(c, re.compile(c)) for c in args.channels]
    newest = {c: None for c in args.channels}  # the newest frame seen (True: seen, without --frame)
    unknown = {c: 0 for c in args.channels}
    if not os.path.exists(args.log):
        print(f"logged: no {args.log} yet")
        return 1

    def satisfied(c):
        return newest[c] is True or (newest[c] is not None and args.frame is not None and newest[c] >= args.frame)

    # The last event may be half written: the reader stops before it.
    for ev in lcm.EventLog(args.log, "r"):
        if args.since is not None and ev.timestamp < args.since:
            continue
        for c, pattern in wanted:
            if satisfied(c) or not pattern.fullmatch(ev.channel):
                continue
            if args.frame is None:
                newest[c] = True
                continue
            frame = frame_of(ev.data)
            if frame is None:
                unknown[c] += 1
            else:
                newest[c] = frame if newest[c] is None else max(newest[c], frame)
    missing = [c for c in args.channels if not satisfied(c)]
    for c in missing:
        seen = "nothing with a frame recorded" if newest[c] is None else f"newest frame {newest[c]}, wanted {args.frame}"
        if args.frame is None:
            seen = "nothing recorded"
        if args.since is not None:
            seen += f" since {args.since}"
        print(f"logged: {c}: {seen}" + (f" ({unknown[c]} messages of an unknown type, without a frame or not decoding)"
                                         if unknown[c] else ""))
    return 1 if missing else 0


def read_poses_and_inputs(path, T, robots):
    """POSE_<r> by (robot, frame), duplicates, notices, and each robot's input stream.

    On one host every socket of a multicast group gets the datagrams in the order
    they were sent, and a node handles its socket in that order; the logger's order
    is that order. Robot r's input is its SENSOR_r frames and the DYNAMIC_NOTICE
    messages of other robots' detections (r ignores its own). robot_node holds a
    notice of frame f until it has processed its own frame f (RobotNode::on_notice),
    so a notice takes effect after frame max(f, the last frame r had processed when
    it arrived): after frame f, as in the in-process run, unless it arrives after
    SENSOR_r of frame f + 1 (a late notice, the only timing-dependent input).
    inputs[r][k] = sorted notices that took effect between r's frames k - 1 and k."""
    poses, dup, notices = {}, [], []
    inputs = {r: {} for r in robots}
    last = {r: -1 for r in robots}
    for ev in read_log(path):
        if re.fullmatch(r"POSE_\d+", ev.channel):
            m = T.pose_estimate_t.decode(ev.data)
            key = (m.robot_id, m.frame)
            if key in poses:
                dup.append(key)
            poses[key] = m
        elif ev.channel == "DYNAMIC_NOTICE":
            n = T.dynamic_notice_t.decode(ev.data)
            notices.append(n)
            for r in robots:
                if n.detected_by != r:
                    effect = max(n.frame, last[r]) if last[r] >= 0 else -1
                    inputs[r].setdefault(effect + 1, []).append((n.frame, n.landmark_id, n.detected_by))
        elif re.fullmatch(r"SENSOR_\d+", ev.channel):
            m = T.sensor_frame_t.decode(ev.data)
            if m.robot_id in inputs:
                last[m.robot_id] = max(last[m.robot_id], m.frame)
    for r in robots:
        for k in inputs[r]:
            inputs[r][k].sort()
    return poses, dup, notices, inputs


def cmd_compare_poses(args, T):
    a, dup_a, not_a, in_a = read_poses_and_inputs(args.log_a, T, args.robots)
    b, dup_b, not_b, in_b = read_poses_and_inputs(args.log_b, T, args.robots)
    fails, notes = [], []
    if dup_a or dup_b:
        fails.append(f"duplicate POSE frames: {dup_a[:5]} / {dup_b[:5]}")
    # The same notices (their order within a frame follows which robot's MOVING
    # event reached main_robot first, a race without effect).
    na = sorted((n.frame, n.landmark_id, n.detected_by) for n in not_a)
    nb = sorted((n.frame, n.landmark_id, n.detected_by) for n in not_b)
    print(f"notices: {len(na)} / {len(nb)}" + ("" if na == nb else
          f"; only first {sorted(set(na) - set(nb))}, only second {sorted(set(nb) - set(na))}"))
    worst = 0.0
    for r in args.robots:
        missing_a = [k for k in range(args.frames) if (r, k) not in a]
        missing_b = [k for k in range(args.frames) if (r, k) not in b]
        if missing_a or missing_b:
            msg = f"robot {r}: frames without a pose: first log {missing_a[:10]}, second log {missing_b[:10]}"
            (notes if max(len(missing_a), len(missing_b)) <= args.allow_missing else fails).append(msg)
        # First frame whose input differs: a late notice in one of the two runs.
        same_input = args.frames
        for k in range(args.frames):
            if in_a[r].get(k) != in_b[r].get(k):
                same_input = k
                break
        late = sum(1 for k in range(args.frames) for (f, _, _) in in_a[r].get(k, []) if f < k - 1)
        first_diff, rmax = None, 0.0
        for k in range(args.frames):
            if (r, k) not in a or (r, k) not in b:
                continue
            pa, pb = a[(r, k)], b[(r, k)]
            d = max(abs(pa.x - pb.x), abs(pa.y - pb.y),
                    abs(math.remainder(pa.theta - pb.theta, 2 * math.pi)),
                    max(abs(pa.cov[i][j] - pb.cov[i][j]) for i in range(3) for j in range(3)))
            rmax = max(rmax, d)
            if d >= args.tol and first_diff is None:
                first_diff = k
        worst = max(worst, rmax)
        line = (f"robot {r}: {sum(1 for k in range(args.frames) if (r, k) in a and (r, k) in b)} frames compared, "
                f"max |diff| {rmax:.3g}; late notices (first log): {late}; ")
        if same_input < args.frames:
            ka, kb = in_a[r].get(same_input), in_b[r].get(same_input)
            line += f"input differs from frame {same_input} (notices before it: {ka} vs {kb})"
        else:
            line += "same input in every frame"
        print(line)
        if first_diff is not None:
            msg = f"robot {r}: poses differ from frame {first_diff} on (max {rmax:.3g})"
            if first_diff < same_input:
                fails.append(msg + " with the same input: a fault")
            else:
                notes.append(msg + f", after its input differed (frame {same_input}): notice timing, not a fault")
    print(f"poses: {len(a)} / {len(b)} messages, worst difference {worst:.3g} (tolerance {args.tol:g})")
    if notes:
        print("\n".join(notes))
    if fails:
        print("\n".join(fails))
        return 1
    return 3 if notes and worst >= args.tol else 0


class _Map:
    """The chunks of one GLOBAL_MAP publication put together (global_map_t)."""
    def __init__(self, first):
        self.key = (first.utime, first.incarnation, first.version, first.frame, first.num_chunks)
        self.frame, self.version, self.num_chunks = first.frame, first.version, first.num_chunks
        self.chunks = {}

    def add(self, c):
        self.chunks[c.chunk] = c
        return len(self.chunks) == self.num_chunks

    def finish(self):
        cs = [self.chunks[i] for i in sorted(self.chunks)]
        self.landmarks = [l for c in cs for l in c.landmarks[:c.num_landmarks]]
        self.moving_ids = [m for c in cs for m in c.moving_ids[:c.num_moving]]
        self.num_landmarks, self.num_moving = len(self.landmarks), len(self.moving_ids)
        return self


def last_map(path, T):
    """The last complete GLOBAL_MAP publication of a log: the final map."""
    last, building = None, None
    for ev in read_log(path):
        if ev.channel != "GLOBAL_MAP":
            continue
        c = T.global_map_t.decode(ev.data)
        key = (c.utime, c.incarnation, c.version, c.frame, c.num_chunks)
        if building is None or building.key != key:
            building = _Map(c)
        if building.add(c):
            last = building.finish()
    return last


def cmd_compare_maps(args, T):
    a, b = last_map(args.log_a, T), last_map(args.log_b, T)
    if a is None or b is None:
        print("compare-maps: a log has no GLOBAL_MAP")
        return 1
    la = {l.id: l for l in a.landmarks[:a.num_landmarks]}
    lb = {l.id: l for l in b.landmarks[:b.num_landmarks]}
    ma, mb = sorted(a.moving_ids[:a.num_moving]), sorted(b.moving_ids[:b.num_moving])
    fails = []
    if sorted(la) != sorted(lb):
        fails.append(f"static ids differ: only first {sorted(set(la) - set(lb))}, only second {sorted(set(lb) - set(la))}")
    if ma != mb:
        fails.append(f"moving ids differ: only first {sorted(set(ma) - set(mb))}, only second {sorted(set(mb) - set(ma))}")
    dmax, worst_id = 0.0, None
    for i in set(la) & set(lb):
        d = math.hypot(la[i].x - lb[i].x, la[i].y - lb[i].y)
        if d > dmax:
            dmax, worst_id = d, i
    print(f"maps: frame {a.frame} / {b.frame}, {len(la)} / {len(lb)} static, {len(ma)} / {len(mb)} moving, "
          f"max position difference {dmax:.3g} m (landmark {worst_id}, tolerance {args.tol:g})")
    if dmax > args.tol:
        fails.append(f"landmark {worst_id} is {dmax:.3g} m apart")
    if fails:
        print("\n".join(fails))
        return 1
    return 0


def cmd_auth_refused(args, T):
    best = {}
    for ev in read_log(args.log):
        if ev.channel.startswith("STATUS_"):
            node = ev.channel[len("STATUS_"):]
            best[node] = max(best.get(node, -1), T.node_status_t.decode(ev.data).auth_refused)
    print("auth_refused: " + ", ".join(f"{n} {best.get(n, 'no STATUS')}" for n in args.nodes))
    return 0 if all(best.get(n, 0) > 0 for n in args.nodes) else 1


def main():
    global ROSTER, MISSION
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build-dir", default=os.path.join(root, "build"))
    ap.add_argument("--roster", help="only events that verify with this roster's keys (docs/security.md)")
    ap.add_argument("--mission", help="the mission (16 hexadecimal digits; default: the roster's)")
    sub = ap.add_subparsers(dest="cmd", required=True)
    w = sub.add_parser("wait-nodes")
    w.add_argument("n", type=int)
    w.add_argument("--timeout", type=float, default=20.0)
    f = sub.add_parser("wait-frame")
    f.add_argument("channel")
    f.add_argument("frame", type=int)
    f.add_argument("--timeout", type=float, default=60.0)
    g = sub.add_parser("logged")
    g.add_argument("log")
    g.add_argument("channels", nargs="+")
    g.add_argument("--frame", type=int)
    g.add_argument("--since", type=int, help="only events recorded at or after this time [us since the epoch]")
    c = sub.add_parser("compare-poses")
    c.add_argument("log_a")
    c.add_argument("log_b")
    c.add_argument("--robots", type=int, nargs="+", required=True)
    c.add_argument("--frames", type=int, required=True)
    c.add_argument("--tol", type=float, default=1e-9)
    c.add_argument("--allow-missing", type=int, default=0)
    m = sub.add_parser("compare-maps")
    m.add_argument("log_a")
    m.add_argument("log_b")
    m.add_argument("--tol", type=float, default=0.05)
    a = sub.add_parser("auth-refused")
    a.add_argument("log")
    a.add_argument("--nodes", nargs="+", required=True)
    args = ap.parse_args()
    if args.roster:
        ROSTER, MISSION = load_roster(args.roster)
        if args.mission:
            MISSION = int(args.mission, 16)
    T = load_types(args.build_dir)
    return {"wait-nodes": cmd_wait_nodes, "wait-frame": cmd_wait_frame, "compare-poses": cmd_compare_poses,
            "compare-maps": cmd_compare_maps, "auth-refused": cmd_auth_refused, "logged": cmd_logged}[args.cmd](args, T)


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""A team member taken over (system test `system_insider`, tests/system/insider.sh;
docs/security.md "Threat model"): a process holding one node's secret key (robot
3's) that signs, with it, messages in other nodes' names, until SIGTERM / SIGINT or
--duration. Every --period seconds it sends, each signed with its key:

  - LMAP_EVENTS: a landmark ADD at (100, 100) with a tiny covariance in robot 2's
    name, with a newer incarnation: as sender 2 (its key is not robot 2's), and as
    sender 3 with robot 2's events (robot 3 may send events of robot 3 only);
  - DYNAMIC_NOTICE: "landmark k moves", as main (sender 100) and as itself;
  - SENSOR_1: a frame of robot 1 with its odometer 5 m off, as the simulator (101)
    and as itself;
  - GLOBAL_MOVING as main: every landmark moving.

With --silence-key FILE (another member's key, the simulator's) it also sends, once,
a SENSOR_1 frame signed with that key, of the simulator's live incarnation and
mission (learnt from its traffic) with a counter of 2^64 - 9: the datagram that
used to make robot 1 refuse every later frame as replayed.

With --replay LOG it also sends, once, mid-run, the SENSOR_1 datagrams of another
mission's recording as they were recorded (signed, genuine, of another mission).

Prints what it sent, by kind, at the end. Needs the PyPI lcm and PyNaCl (.venv) and
the generated types (BUILD/lcmgen/python); talks on LCM_DEFAULT_URL.
  insider.py --build-dir B --key FILE --sender N --roster FILE [--silence-key FILE]
             [--replay LOG] [--period S] [--duration S]
"""
# ---- start-up: standard library only, before any third-party import (tools/elaslam_tool.py)
import os
import sys

_here = os.path.dirname(os.path.realpath(__file__))
sys.path.insert(0, os.path.join(_here, "..", "..", "tools"))
from elaslam_tool import run_in_venv  # noqa: E402

if __name__ == "__main__":
    run_in_venv()
# ----------------------------------------------------------------------------------
import collections  # noqa: E402
import hashlib  # noqa: E402
import struct  # noqa: E402
import time  # noqa: E402

sys.path.insert(0, _here)
from attacker import Rounds, set_up  # noqa: E402
from lcm_check import load_roster  # noqa: E402


class Signer:
    """Signs as the wire format says (transport/auth_transport.hpp), with one secret key."""

    def __init__(self, key_file):
        from nacl.signing import SigningKey
        text = open(key_file, "rb").read().strip()
        self.key = SigningKey(bytes.fromhex(text.decode()) if len(text) == 64 else text)
        self.key_id = struct.unpack(">I", bytes(self.key.verify_key)[:4])[0]

    def seal(self, channel, payload, sender, mission, incarnation, counter):
        header = b"ELA2" + struct.pack(">hIQqQ", sender, self.key_id, mission, incarnation, counter)
        ch = channel.encode()
        digest = hashlib.sha512(struct.pack(">I", len(ch)) + ch + payload + header).digest()
        return payload + header + self.key.sign(digest).signature


def options(ap):
    ap.add_argument("--key", required=True, help="the taken-over member's secret key")
    ap.add_argument("--sender", type=int, required=True, help="its sender id")
    ap.add_argument("--roster", required=True)
    ap.add_argument("--silence-key")
    ap.add_argument("--replay")


def main():
    args, T, lcm, lc = set_up(__doc__, options, 0.1)
    _, mission = load_roster(args.roster)
    me = Signer(args.key)
    silencer = Signer(args.silence_key) if args.silence_key else None
    incarnation = int(time.time())  # newer than the real nodes' (start counts, boot milliseconds)
    counter = [0]
    sent = collections.Counter()
    sim = {}  # the simulator's live incarnation and newest counter, from its SENSOR frames

    def on_sensor(channel, data):
        if len(data) > 98 and data[-98:-94] == b"ELA2":
            s, kid, _, inc, ctr = struct.unpack(">hIQqQ", data[-94:-64])
            if s == 101 and kid != me.key_id:  # the real simulator's, not this process's own forgeries
                sim["incarnation"], sim["counter"] = inc, ctr

    lc.subscribe("SENSOR_1", on_sensor)

    def send(kind, channel, payload, sender, signer=None, inc=None, ctr=None):
        counter[0] += 1
        signer = signer or me
        lc.publish(channel, signer.seal(channel, payload, sender, mission, incarnation if inc is None else inc,
                                        counter[0] if ctr is None else ctr))
        sent[kind] += 1

    start = time.monotonic()
    rounds = Rounds(args.duration)
    silenced = replayed = False
    for n in rounds:
        now = int(time.time() * 1e6)
        e = T.landmark_event_t()
        e.utime, e.frame, e.robot_id, e.incarnation, e.seq = now, 10 + n, 2, incarnation, n
        e.kind, e.landmark_id, e.x, e.y, e.cov = T.landmark_event_t.ADD, n % 72, 100.0, 100.0, [[1e-6, 0.0], [0.0, 1e-6]]
        b = T.lmap_events_t()
        b.utime, b.frame, b.robot_id, b.incarnation, b.events, b.num_events = now, e.frame, 2, incarnation, [e], 1
        send("LMAP_EVENTS as robot 2", "LMAP_EVENTS", b.encode(), 2)
        send("LMAP_EVENTS of robot 2 as itself", "LMAP_EVENTS", b.encode(), args.sender)
        d = T.dynamic_notice_t()
        d.utime, d.frame, d.incarnation, d.seq, d.landmark_id, d.detected_by = now, 10 + n, incarnation, n, n % 72, 1
        send("DYNAMIC_NOTICE as main", "DYNAMIC_NOTICE", d.encode(), 100)
        send("DYNAMIC_NOTICE as itself", "DYNAMIC_NOTICE", d.encode(), args.sender)
        f = T.sensor_frame_t()
        f.utime, f.frame, f.robot_id, f.odom_x, f.odom_y, f.odom_theta = now, 10 + n, 1, 5.0, 5.0, 0.0
        f.odom_var_trans_per_m, f.odom_var_rot_per_rad, f.odom_var_rot_per_m = 1e-3, 1e-3, 1e-3
        f.num_obs, f.obs = 0, []
        send("SENSOR_1 as the simulator", "SENSOR_1", f.encode(), 101)
        send("SENSOR_1 as itself", "SENSOR_1", f.encode(), args.sender)
        g = T.global_map_t()
        g.utime, g.frame, g.incarnation, g.version, g.chunk, g.num_chunks = now, 10 + n, incarnation, n, 0, 1
        g.id_begin, g.id_end, g.num_landmarks, g.landmarks = 0, 72, 0, []
        g.num_moving, g.moving_ids, g.moving_frames, g.moving_by = 72, list(range(72)), [1] * 72, [1] * 72
        send("GLOBAL_MOVING as main", "GLOBAL_MOVING", g.encode(), 100)
        if silencer and not silenced and "incarnation" in sim:
            send("SENSOR_1 with counter 2^64-9 as the simulator", "SENSOR_1", f.encode(), 101, silencer,
                 sim["incarnation"], 2**64 - 9)
            silenced = True
        if args.replay and not replayed and time.monotonic() - start > 3.0:
            for ev in lcm.EventLog(args.replay, "r"):
                if ev.channel == "SENSOR_1":
                    lc.publish(ev.channel, ev.data)
                    sent["SENSOR_1 of another mission's recording"] += 1
            replayed = True
        rounds.listen(lc, args.period)
    print("insider: sent " + ", ".join(f"{k} {v}" for k, v in sorted(sent.items())))
    return 0


if __name__ == "__main__":
    sys.exit(main())

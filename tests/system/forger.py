#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""An attacker on the team's LCM network without any team member's key (system test
`system_forger`, tests/system/forger.sh). Until SIGTERM / SIGINT or
--duration, every --period seconds it sends:

  - LMAP_EVENT  ADD of a landmark at (100, 100) with a tiny covariance, from robot
                ids in the team (1..3) and not (9..11), plain and with a made-up
                trailer (magic, sender id, the team's mission, a counter, a random
                key id and signature); the same in an LMAP_EVENTS batch;
  - DYNAMIC_NOTICE  a landmark "found moving" (every id in turn), plain and trailed;
  - LMAP_SNAPSHOT   a robot's map with every landmark at (100, 100);
  - POSE_<r>        a robot's pose 100 m off;
  - replays of genuine (authenticated) datagrams it heard: at once, and long after
    (past the receivers' replay windows); a genuine datagram with a payload byte
    changed; a genuine POSE_1 moved to POSE_2.

Prints what it sent, by kind, at the end. Needs the PyPI lcm (.venv) and the
generated types (BUILD/lcmgen/python); talks on LCM_DEFAULT_URL.
  forger.py --build-dir B [--period S] [--duration S]
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
import random  # noqa: E402
import struct  # noqa: E402
import time  # noqa: E402

sys.path.insert(0, _here)
from attacker import Rounds, set_up  # noqa: E402


MISSION = 0  # the team's mission, learnt from the first trailer heard (it is not secret)


def fake_trailer(sender, counter):
    """A trailer of the right shape whose signature is random, with a random key id:
    what a forger without a team member's secret key can do (transport/auth_transport.hpp)."""
    return (b"ELA2" + struct.pack(">h", sender) + os.urandom(4) +
            struct.pack(">QqQ", MISSION, int(time.time() * 1e6), counter) + os.urandom(64))


def main():
    args, T, _, lc = set_up(__doc__, lambda ap: None, 0.02)
    rng = random.Random(15)
    sent = collections.Counter()
    heard = collections.defaultdict(list)  # channel -> genuine sealed datagrams, in order
    mine = set()                           # what this process sent (it hears itself)

    def on_any(channel, data):
        global MISSION
        if data not in mine and len(data) > 98 and data[-98:-94] == b"ELA2" and len(heard[channel]) < 400:
            MISSION = struct.unpack(">Q", data[-88:-80])[0]
            heard[channel].append(data)

    lc.subscribe(".*", on_any).set_queue_capacity(10000)

    def send(kind, channel, data):
        mine.add(data)
        lc.publish(channel, data)
        sent[kind] += 1

    rounds = Rounds(args.duration)
    for n in rounds:
        now = int(time.time() * 1e6)
        # LMAP_EVENT: ADD at (100, 100), tiny covariance, team and non-team robot ids.
        e = T.landmark_event_t()
        e.utime, e.frame, e.robot_id = now, n, [1, 2, 3, 9, 10, 11][n % 6]
        e.incarnation, e.seq, e.kind, e.landmark_id = 1, n, T.landmark_event_t.ADD, n % 72
        e.x, e.y, e.cov = 100.0, 100.0, [[1e-6, 0.0], [0.0, 1e-6]]
        ev = e.encode()
        send("LMAP_EVENT plain", "LMAP_EVENT", ev)
        send("LMAP_EVENT fake trailer", "LMAP_EVENT", ev + fake_trailer(e.robot_id, n))
        # LMAP_EVENTS: the same ADD in a frame's batch, as the robots send them.
        b = T.lmap_events_t()
        b.utime, b.frame, b.robot_id, b.incarnation = e.utime, e.frame, e.robot_id, e.incarnation
        b.events, b.num_events = [e], 1
        evs = b.encode()
        send("LMAP_EVENTS plain", "LMAP_EVENTS", evs)
        send("LMAP_EVENTS fake trailer", "LMAP_EVENTS", evs + fake_trailer(e.robot_id, n))
        # DYNAMIC_NOTICE: every landmark in turn "moving".
        d = T.dynamic_notice_t()
        d.utime, d.frame, d.incarnation, d.seq, d.landmark_id, d.detected_by = now, n, 1, n, n % 72, 1 + n % 3
        dn = d.encode()
        send("DYNAMIC_NOTICE plain", "DYNAMIC_NOTICE", dn)
        send("DYNAMIC_NOTICE fake trailer", "DYNAMIC_NOTICE", dn + fake_trailer(100, n))
        # LMAP_SNAPSHOT: robot r's map, every landmark of a range at (100, 100).
        sn = T.lmap_snapshot_t()
        sn.utime, sn.frame, sn.robot_id, sn.incarnation, sn.seq = now, n, 1 + n % 3, 1, n
        sn.chunk, sn.num_chunks, sn.id_begin, sn.id_end = 0, 1, 0, 72
        for i in range(0, 20):
            l = T.landmark_estimate_t()
            l.id, l.x, l.y, l.cov = i, 100.0, 100.0, [[1e-6, 0.0], [0.0, 1e-6]]
            sn.landmarks.append(l)
        sn.num_landmarks = len(sn.landmarks)
        sn.num_moving = 0
        send("LMAP_SNAPSHOT plain", "LMAP_SNAPSHOT", sn.encode())
        # POSE_r: 100 m off.
        r = 1 + n % 3
        p = T.pose_estimate_t()
        p.utime, p.frame, p.robot_id, p.incarnation, p.x, p.y = now, n, r, 1, 100.0, 100.0
        send("POSE plain", f"POSE_{r}", p.encode())
        send("POSE fake trailer", f"POSE_{r}", p.encode() + fake_trailer(r, n))
        # Replays of what the team sent: the newest (inside the replay window) and the
        # oldest (long gone), on every channel heard; an altered one; one moved.
        for ch, msgs in list(heard.items()):
            if len(msgs) >= 2:
                send("replay recent", ch, msgs[-2])
                send("replay old", ch, msgs[rng.randrange(0, max(1, len(msgs) // 2))])
        for ch, at in (("LMAP_EVENT", 45), ("LMAP_EVENTS", 70)):  # inside (the first event's) x
            if heard.get(ch):
                b = bytearray(heard[ch][-1])
                b[at] ^= 0x10
                send("altered genuine", ch, bytes(b))
        if heard.get("POSE_1"):
            send("genuine moved to another channel", "POSE_2", heard["POSE_1"][-1])
        # Hear the team meanwhile (the datagrams to replay).
        rounds.listen(lc, args.period)
        if len(mine) > 20000:
            mine.clear()
    print("forger: sent " + ", ".join(f"{k} {v}" for k, v in sorted(sent.items())))
    print("forger: heard genuine datagrams on " + ", ".join(f"{c} {len(m)}" for c, m in sorted(heard.items())))
    return 0


if __name__ == "__main__":
    sys.exit(main())

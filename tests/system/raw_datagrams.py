#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Malformed LCM datagrams, sent raw to the team's multicast group: what reaches a
node's LCM receive path from anyone on its network, key or not (system test
`system_datagrams`, tests/system/datagram_attack.sh; docs/security.md "Bytes from the
network"). Standard library only.

The datagrams (LCM 1.3.1's wire format: "LC02" | seq u32 | channel NUL | payload for a
short message; "LC03" | seq u32 | message size u32 | fragment offset u32 | fragment
number u16 | fragments u16 | [channel NUL, in fragment 0] | data for a fragment):

  - the pair that crashed every keyed process: 200 zero bytes, then a 16-byte
    datagram "LC02", a seq, "SENSOR_1" without its NUL (LCM then reports a payload
    size of -1), for each of the team's channels;
  - the same after a datagram of non-zero bytes (the name runs on into them);
  - every prefix of a valid datagram on each channel;
  - fragments with every size field at its extremes (0, 1, 2^31 - 1, 2^32 - 1, an
    offset past the size, more fragments than the size needs, fragment number past
    the count, a channel that runs off the end);
  - channel names of 0, 63, 64 and 255 bytes, with control characters and bytes
    above 127.

  raw_datagrams.py [--url udpm://GROUP:PORT] [--rounds N] [--period S] [--duration S]
                   [--write-corpus DIR]

The URL defaults to $LCM_DEFAULT_URL. Every --period seconds one round of the whole
family is sent, until --rounds rounds or --duration seconds (the first one reached),
or SIGTERM. Prints how many datagrams it sent. --write-corpus DIR writes the family as
fuzz inputs for fuzz_datagrams (fuzz/fuzz_datagrams.cpp: [u16 LE length][bytes]
repeated) instead of sending.
"""
import argparse
import os
import signal
import socket
import struct
import sys
import time
from urllib.parse import urlparse

CHANNELS = ["SENSOR_1", "SENSOR_2", "POSE_1", "LMAP_EVENT", "LMAP_EVENTS", "LMAP_SNAPSHOT", "GLOBAL_MAP",
            "GLOBAL_MOVING", "DYNAMIC_NOTICE", "STATUS_ROBOT_1", "STATUS_MAIN", "STATUS_SIM", "TEAM_MAP_1",
            "LMAP_RESYNC", "RUN_INFO", "GROUND_TRUTH", "CANDIDATES_1", "TRACKS_1", "GLOBAL_TRACKS"]
SHORT, FRAG = b"LC02", b"LC03"


def short(seq, channel, payload=b"", nul=True):
    return SHORT + struct.pack(">I", seq) + channel + (b"\0" if nul else b"") + payload


def fragment(seq, size, offset, number, count, channel=None, data=b""):
    head = FRAG + struct.pack(">IIIHH", seq, size & 0xFFFFFFFF, offset & 0xFFFFFFFF, number & 0xFFFF, count & 0xFFFF)
    return head + (channel + b"\0" if channel is not None else b"") + data


def family():
    """Every datagram of one round, in the order sent (some depend on the one before)."""
    seq = 0
    out = []

    def nxt():
        nonlocal seq
        seq += 1
        return seq

    payload = bytes(range(40))  # an 8-byte fingerprint's worth and more: not any real type's
    for name in CHANNELS:
        ch = name.encode()
        out.append(bytes(200))                               # the buffer's tail zeroed
        out.append(short(nxt(), ch, nul=False))              # the name ends at the datagram's end
        out.append(bytes([0x41]) * 300)                      # the buffer's tail not zero
        out.append(short(nxt(), ch, nul=False))              # the name runs on into it
        valid = short(nxt(), ch, payload)
        out.extend(valid[:k] for k in range(len(valid) + 1))  # every prefix, the empty datagram too
    ch = b"SENSOR_1"
    for size in (0, 1, 2, 1400, 65535, 1 << 20, (1 << 31) - 1, (1 << 32) - 1):
        for offset in (0, 1, size - 1, size, size + 1, (1 << 32) - 1):
            for number, count in ((0, 1), (0, 2), (1, 2), (0, 0), (5, 2), (0, 65535), (65535, 65535)):
                out.append(fragment(nxt(), size, offset, number, count, ch if number == 0 else None, payload[:16]))
    out.append(fragment(nxt(), 100, 0, 0, 2, None, b"SENSOR_1"))   # fragment 0 whose name runs off the end
    for name in (b"", b"A" * 63, b"A" * 64, b"A" * 255, b"SENSOR_1\x01\x7f", b"POSE_1\xff\xfe", b"\n\r\t"):
        out.append(short(nxt(), name, payload))
        out.append(short(nxt(), name, nul=False))
    for n in (1, 3, 4, 7, 8, 9):                               # shorter than any header
        out.append(SHORT[:n] if n <= 4 else SHORT + bytes(n - 4))
        out.append(FRAG[:n] if n <= 4 else FRAG + bytes(n - 4))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--url", default=os.environ.get("LCM_DEFAULT_URL", "udpm://239.255.76.67:7667?ttl=0"))
    ap.add_argument("--rounds", type=int, default=1)
    ap.add_argument("--period", type=float, default=0.2)
    ap.add_argument("--duration", type=float, default=600.0)
    ap.add_argument("--write-corpus", metavar="DIR")
    args = ap.parse_args()
    datagrams = family()
    if args.write_corpus:
        os.makedirs(args.write_corpus, exist_ok=True)
        # One input per group of a channel's datagrams (the pairs depend on order), and the fragments.
        per = len(datagrams) // 40 + 1
        for i in range(0, len(datagrams), per):
            with open(os.path.join(args.write_corpus, f"family_{i // per:03d}"), "wb") as f:
                for d in datagrams[i:i + per]:
                    f.write(struct.pack("<H", len(d)) + d)
        print(f"raw_datagrams: {len(datagrams)} datagrams in {(len(datagrams) + per - 1) // per} inputs "
              f"in {args.write_corpus}")
        return 0
    u = urlparse(args.url)
    if u.scheme != "udpm" or not u.hostname:
        sys.exit(f"raw_datagrams: not a udpm:// URL: {args.url}")
    target = (u.hostname, u.port or 7667)
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 0)  # this host only, as the team's ttl=0
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    sent = rounds = 0
    end = time.monotonic() + args.duration
    while not stop and rounds < args.rounds and time.monotonic() < end:
        for d in datagrams:
            sock.sendto(d, target)
            sent += 1
        rounds += 1
        time.sleep(args.period)
    print(f"raw_datagrams: sent {sent} datagrams in {rounds} rounds to {target[0]}:{target[1]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

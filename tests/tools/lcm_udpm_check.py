#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tools/lcm_udpm.py, the Python tools' LCM receiver (ctest `tools_lcm_udpm`; standard
library only, no network): every malformed datagram of tests/system/raw_datagrams.py's
family is refused or dropped with a reason and none raises; a message cut into
fragments as liblcm cuts it comes out whole, also between two senders' interleaved
fragments; a fragment out of order loses its message; URLs are parsed as LCM does.
Exit 0 when all hold, 1 naming the first that does not."""
import os
import struct
import sys

HERE = os.path.dirname(os.path.realpath(__file__))
sys.path[:0] = [os.path.join(HERE, "..", "..", "tools"), os.path.join(HERE, "..", "system")]
from lcm_udpm import DatagramAssembler, parse_udpm_url  # noqa: E402
import raw_datagrams  # noqa: E402


def fragments(seq, channel, payload, size=1400):
    """The datagrams liblcm sends for one message larger than a datagram (lcm_udpm.c)."""
    chunks = [payload[i:i + size] for i in range(0, len(payload), size)]
    out, offset = [], 0
    for n, c in enumerate(chunks):
        head = b"LC03" + struct.pack(">IIIHH", seq, len(payload), offset, n, len(chunks))
        out.append(head + (channel + b"\0" if n == 0 else b"") + c)
        offset += len(c)
    return out


def main():
    fails = []
    a = DatagramAssembler()
    kinds = {}
    for d in raw_datagrams.family():
        try:
            r = a.feed(d, ("10.0.0.1", 1))
        except Exception as e:  # the point of the module: never
            fails.append(f"{d[:24]!r}: {type(e).__name__}: {e}")
            continue
        kinds[r[0]] = kinds.get(r[0], 0) + 1
        if r[0] == "message" and (not 1 <= len(r[1]) <= 63 or not r[1].isprintable() or " " in r[1]):
            fails.append(f"a message on channel {r[1]!r}")
    print(f"lcm_udpm: raw_datagrams family of {sum(kinds.values())}: {kinds}")
    if kinds.get("refused", 0) < 700:  # 743: the prefixes of valid datagrams are valid short messages
        fails.append(f"only {kinds.get('refused', 0)} refused")

    payload = bytes(range(256)) * 40  # 10,240 bytes: 8 fragments
    b = DatagramAssembler()
    one, two = fragments(7, b"GLOBAL_MAP", payload), fragments(9, b"TEAM_MAP_1", payload[::-1])
    got = []
    for d1, d2 in zip(one, two):  # two senders interleaved
        for d, src in ((d1, ("10.0.0.1", 1)), (d2, ("10.0.0.2", 1))):
            r = b.feed(d, src)
            if r[0] == "message":
                got.append(r[1:])
    if got != [("GLOBAL_MAP", payload), ("TEAM_MAP_1", payload[::-1])]:
        fails.append(f"fragmented messages not assembled: {[(c, len(p)) for c, p in got]}")
    c = DatagramAssembler()
    f = fragments(3, b"GLOBAL_MAP", payload)
    rs = [c.feed(d, ("10.0.0.1", 1))[0] for d in [f[0], f[2], f[1]] + f[3:]]
    if "message" in rs or "dropped" not in rs:
        fails.append(f"a fragment out of order did not lose its message: {rs}")
    short = b"LC02" + struct.pack(">I", 1) + b"POSE_1\0" + b"xyz"
    if c.feed(short, ("10.0.0.1", 1)) != ("message", "POSE_1", b"xyz"):
        fails.append("a short message not read")

    if parse_udpm_url("udpm://239.255.76.67:7860?ttl=0&recv_buf_size=8388608") != ("239.255.76.67", 7860, 8388608):
        fails.append("URL with recv_buf_size")
    if parse_udpm_url("") != ("239.255.76.67", 7667, 0):
        fails.append("LCM's default URL")
    for bad in ("tcpq://1.2.3.4", "udpm://10.0.0.1:7667", "udpm://239.255.76.67:99999", "udpm://239.1.1.1?recv_buf_size=x"):
        try:
            parse_udpm_url(bad)
            fails.append(f"{bad} accepted")
        except ValueError:
            pass
    for f in fails:
        print(f"lcm_udpm: FAIL {f}")
    print("lcm_udpm: PASS" if not fails else "lcm_udpm: FAIL")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())

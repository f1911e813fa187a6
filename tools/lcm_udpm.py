# SPDX-License-Identifier: Apache-2.0
"""The receiving side of LCM's udpm:// transport in Python, every byte checked before
it is used: the Python tools' equivalent of transport/udpm_receiver.hpp (read its
comment for why liblcm's own receive thread is not used: one malformed datagram
kills it, in the PyPI wheel as in Debian's 1.3.1). Standard library only.

    group, port, recv_buf = parse_udpm_url(url)
    rx = UdpmReceiver(parse_udpm_url(url), ports=[port])   # one socket per port
    for channel, payload in rx.poll(timeout_s):            # whole messages, in order
        ...
    rx.refused        # Counter: malformed datagrams by reason (never read further)
    rx.dropped        # fragments of no message in progress (fragment 0 lost)

The wire format (lcm/lcm_udpm.c), big-endian:
  short message:  "LC02" | seq u32 | channel NUL | payload
  fragment:       "LC03" | seq u32 | message size u32 | offset u32 |
                  fragment number u16 | fragments u16 | [fragment 0: channel NUL] | data
A datagram is refused when it is shorter than its header, its channel name is not
1..63 printable characters ended by a NUL inside the datagram, a message size is 0 or
beyond 4 MiB (contract::kMaxMessageBytes), a fragment's number is not below the count
or its data does not fit the message where it says. Fragments must come in order; at
most four messages are assembled at once (one per sender), the oldest given up first.
"""
import collections
import select
import socket
import struct
from urllib.parse import urlparse, parse_qs

MAX_MESSAGE_BYTES = 4 << 20   # contract::kMaxMessageBytes
MAX_CHANNEL_BYTES = 63        # LCM's limit
ASSEMBLIES = 4
DEFAULT_URL = "udpm://239.255.76.67:7667?ttl=0"


def parse_udpm_url(url):
    """(group, port, recv_buf_size) of a udpm:// URL ("" or None: LCM's default).
    ValueError naming the problem when LCM would not accept it."""
    u = urlparse(url or DEFAULT_URL)
    if u.scheme != "udpm":
        raise ValueError(f"not a udpm:// URL: '{url}'")
    group = u.hostname or "239.255.76.67"
    try:
        if not 224 <= int(socket.inet_aton(group)[0]) <= 239:
            raise OSError
    except OSError:
        raise ValueError(f"not a multicast IPv4 address in the LCM URL '{url}': '{group}'") from None
    try:
        port = u.port or 7667
    except ValueError:
        raise ValueError(f"not a port in the LCM URL '{url}'") from None
    buf = 0
    for v in parse_qs(u.query).get("recv_buf_size", []):
        if not v.isdigit() or int(v) > 1 << 30:
            raise ValueError(f"not a receive buffer size in the LCM URL '{url}': '{v}'")
        buf = int(v)
    return group, port, buf


def _channel(data, start):
    """(name, end) of the NUL-ended channel name at data[start:], or (None, why)."""
    nul = data.find(b"\0", start, start + MAX_CHANNEL_BYTES + 1)
    if nul < 0:
        return None, ("a channel name longer than LCM's 63 characters" if len(data) - start > MAX_CHANNEL_BYTES
                      else "a channel name that runs past the datagram's end (no NUL)")
    if nul == start:
        return None, "an empty channel name"
    name = data[start:nul]
    if any(b <= 0x20 or b > 0x7E for b in name):
        return None, "a channel name with bytes that are not printable ASCII"
    return name.decode("ascii"), nul + 1


class _Assembly:
    __slots__ = ("source", "seq", "size", "count", "next", "filled", "channel", "data", "tick")


class DatagramAssembler:
    """Datagrams in, whole messages out; malformed ones refused with a reason."""

    def __init__(self):
        self._busy = {}   # source -> _Assembly
        self._tick = 0

    def feed(self, d, source):
        """('message', channel, payload) | ('pending',) | ('dropped',) | ('refused', why)."""
        if len(d) < 8:
            return ("refused", "shorter than LCM's header")
        magic = d[:4]
        if magic == b"LC02":
            name, end = _channel(d, 8)
            return ("refused", end) if name is None else ("message", name, d[end:])
        if magic != b"LC03":
            return ("refused", "not LCM's magic (LC02, LC03)")
        if len(d) < 20:
            return ("refused", "a fragment shorter than its 20-byte header")
        seq, total, offset, number, count = struct.unpack_from(">IIIHH", d, 4)
        if total == 0 or total > MAX_MESSAGE_BYTES:
            return ("refused", "a fragment of a message size 0 or larger than any message")
        if count == 0 or number >= count:
            return ("refused", "a fragment number not below its message's fragment count")
        body = 20
        a = self._busy.get(source)
        if number == 0:
            name, end = _channel(d, body)
            if name is None:
                return ("refused", end)
            if offset + (len(d) - end) > total:
                return ("refused", "a fragment whose data does not fit its message where it says")
            if a is None:
                if len(self._busy) >= ASSEMBLIES:  # the one idle longest gives way
                    del self._busy[min(self._busy.values(), key=lambda x: x.tick).source]
                a = self._busy[source] = _Assembly()
            a.source, a.seq, a.size, a.count, a.next, a.filled = source, seq, total, count, 0, 0
            a.channel, a.data = name, bytearray(total)
            body = end
        elif offset + (len(d) - body) > total:
            return ("refused", "a fragment whose data does not fit its message where it says")
        if (a is None or a.seq != seq or a.size != total or a.count != count or a.next != number
                or a.filled != offset):
            if a is not None and a.seq == seq:
                del self._busy[source]  # out of order: the message is lost
            return ("dropped",)
        n = len(d) - body
        a.data[offset:offset + n] = d[body:]
        a.filled += n
        self._tick += 1
        a.tick = self._tick
        a.next += 1
        if a.next < a.count:
            return ("pending",)
        del self._busy[source]
        if a.filled != a.size:
            return ("refused", "a fragmented message whose fragments do not add up to its size")
        return ("message", a.channel, bytes(a.data))


class UdpmReceiver:
    """Sockets on the LCM group, one per port, read without blocking; whole messages out."""

    def __init__(self, address, ports=None):
        group, port, buf = address
        self.socks = []
        for p in ports or [port]:
            s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # every LCM process binds the port
            if buf:
                s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, buf)
            s.bind(("", p))
            try:
                s.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP,
                             socket.inet_aton(group) + socket.inet_aton("0.0.0.0"))
            except OSError as e:
                s.close()
                self.close()
                raise OSError(f"cannot join the multicast group {group} on port {p}: {e} "
                              "(multicast on loopback needs a route: ip route add 224.0.0.0/4 dev lo)") from None
            s.setblocking(False)
            self.socks.append(s)
        self._asm = {s.fileno(): DatagramAssembler() for s in self.socks}
        self.datagrams = 0
        self.refused = collections.Counter()
        self.dropped = 0

    def poll(self, timeout_s, budget=2000):
        """Whole messages (channel, payload) read within timeout_s (at most `budget` datagrams)."""
        ready, _, _ = select.select(self.socks, [], [], max(0.0, timeout_s))
        out = []
        for s in ready:
            asm = self._asm[s.fileno()]
            for _ in range(budget):
                try:
                    d, src = s.recvfrom(65535)
                except (BlockingIOError, InterruptedError):
                    break
                self.datagrams += 1
                r = asm.feed(d, src)
                if r[0] == "message":
                    out.append((r[1], r[2]))
                elif r[0] == "refused":
                    self.refused[r[1]] += 1
                elif r[0] == "dropped":
                    self.dropped += 1
        return out

    def close(self):
        for s in self.socks:
            s.close()
        self.socks = []

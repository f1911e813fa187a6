#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The viewer as an HTTP service under attack (system_viewer_attacks, started by
tests/system/viewer_attacks.sh; docs/security.md, "The viewer as an HTTP service"). Each case attacks a
running viewer, checks that it keeps answering and refuses what it should, and
reads the viewer's VmRSS (/proc/PID/status) every 50 ms during the attack: the peak
must stay under --rss-mb.

    viewer_attacks.py CASE URL --pid PID [--rss-mb MB] [--max-clients N]
                      [--source ADDR] [--token TOKEN]
CASE:
  flood      4 connections send 8 KB header lines without end: each is refused
             (431) and closed; /state.json answers within 1 s meanwhile
  limits     101 header lines (431), a 5000-byte request line (414), a body over
             the bound (413), a chunked body (411); 100 header lines are served
  slowloris  40 connections send their request a byte every 0.3 s or never end
             their head: /state.json answers within 1 s while they hang; each is
             closed by the viewer within 10 s
  crowd      100 idle connections from 127.0.0.1 (over the 64 per address): the
             surplus is refused at once (503); /state.json from 127.0.0.2 answers
             within 1 s; then 192 more from 3 addresses, each with 15 KiB of a head
             that never ends (the 256 connections the viewer takes, holding the most
             memory they can): a new one is answered (503) within 1 s; all are
             closed after the request timeout and 127.0.0.1 is served again
  streams    MAX event streams from 127.0.0.1 that are never read (2 KB receive
             buffers): /state.json answers within 1 s; a browser from 127.0.0.2 gets
             a stream at once; one from 127.0.0.1 within 10 s (a stalled stream is
             evicted); the viewer closes every stalled stream within 15 s; the
             browsers keep receiving states; clients is 0 once they close
  token      (URL on a non-loopback address, from --source, a non-loopback
             address) 401 without the token or with a wrong one on /, /state.json
             and /events; 200 with "Authorization: Bearer" and with ?token=
Exit 0 when the case holds, 1 otherwise. Python standard library only.
"""
import argparse
import json
import socket
import sys
import threading
import time
import urllib.parse

from event_stream import state_counts

BAD = []


def fail(msg):
    BAD.append(msg)
    print(f"viewer_attacks: FAIL {msg}", flush=True)


class Rss(threading.Thread):
    """The peak VmRSS (MB) of a process while the `with` block runs."""

    def __init__(self, pid):
        super().__init__(daemon=True)
        self.pid, self.stop, self.first, self.peak = pid, threading.Event(), None, 0.0

    def now(self):
        try:
            with open(f"/proc/{self.pid}/status") as f:
                for line in f:
                    if line.startswith("VmRSS:"):
                        return int(line.split()[1]) / 1024.0
        except OSError:
            pass
        return 0.0

    def run(self):
        while not self.stop.is_set():
            self.peak = max(self.peak, self.now())
            self.stop.wait(0.05)

    def __enter__(self):
        self.first = self.now()
        self.start()
        return self

    def __exit__(self, *exc):
        self.stop.set()
        self.join()


def connect(host, port, source=None, rcvbuf=None, timeout=5.0):
    s = socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET, socket.SOCK_STREAM)
    if rcvbuf:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
    if source:
        s.bind((source, 0))
    s.settimeout(timeout)
    s.connect((host, port))
    return s


def head_of(host, path, headers=""):
    return f"GET {path} HTTP/1.1\r\nHost: {host}\r\n{headers}".encode()


def status_of(data):
    """The status code of a response's first bytes, or None."""
    line = data.split(b"\r\n", 1)[0].split()
    return int(line[1]) if len(line) >= 2 and line[1].isdigit() else None


def read_answer(s, timeout=5.0, limit=1 << 20):
    """What the server sends until it closes (or `timeout`, or `limit` bytes)."""
    s.settimeout(timeout)
    data = b""
    try:
        while len(data) < limit:
            chunk = s.recv(65536)
            if not chunk:
                break
            data += chunk
    except (socket.timeout, ConnectionError, OSError):
        pass
    return data


def request(host, port, path, source=None, headers="", timeout=5.0):
    """(status or None, body, seconds) of one request on a fresh connection."""
    t0 = time.monotonic()
    try:
        s = connect(host, port, source, timeout=timeout)
        s.sendall(head_of(host, path, headers + "Connection: close\r\n\r\n"))
        data = read_answer(s, timeout)
        s.close()
    except OSError:
        data = b""
    took = time.monotonic() - t0
    return status_of(data), data.split(b"\r\n\r\n", 1)[-1], took


def state(host, port, source=None):
    code, body, took = request(host, port, "/state.json", source)
    try:
        return (json.loads(body) if code == 200 else None), code, took
    except ValueError:
        return None, code, took


def check_state_fast(host, port, what, source=None, within=1.0):
    s, code, took = state(host, port, source)
    if code != 200 or took > within:
        fail(f"/state.json from {source or 'the default address'} while {what}: {code} in {took:.2f} s "
             f"(expected 200 within {within:.0f} s)")
    return took


# ---------------------------------------------------------------------------- cases
def case_flood(host, port, args):
    line = b"X-Flood: " + b"a" * 8000 + b"\r\n"
    results = {}

    def flooder(i):
        sent, answer = 0, b""
        try:
            s = connect(host, port)
        except OSError:
            results[i] = (None, 0)
            return
        try:
            s.sendall(head_of(host, "/"))
            t0 = time.monotonic()
            # Until the viewer refuses (answer, reset) or for 20 s; stop early once its
            # memory is past twice the bound (the old viewer grew by 100 MB a second).
            while time.monotonic() - t0 < 20 and rss.now() < 2 * args.rss_mb:
                s.sendall(line)
                sent += len(line)
        except OSError:
            pass
        answer = read_answer(s, 3.0, 4096)
        s.close()
        results[i] = (status_of(answer), sent)

    with Rss(args.pid) as rss:
        threads = [threading.Thread(target=flooder, args=(i,)) for i in range(4)]
        for t in threads:
            t.start()
        time.sleep(0.5)
        took = check_state_fast(host, port, "4 connections flood it with header lines")
        for t in threads:
            t.join()
    for i, (code, sent) in sorted(results.items()):
        print(f"viewer_attacks: flood {i}: answered {code} after {sent / 1e6:.2f} MB sent")
        if code != 431:
            fail(f"flood connection {i} was not refused (431): {code} after {sent / 1e6:.1f} MB")
    print(f"viewer_attacks: flood: /state.json in {took * 1000:.0f} ms; VmRSS {rss.first:.1f} MB before, "
          f"peak {rss.peak:.1f} MB (bound {args.rss_mb} MB)")
    if rss.peak > args.rss_mb:
        fail(f"flood: VmRSS peaked at {rss.peak:.0f} MB, over {args.rss_mb} MB")


def raw(host, port, data, timeout=5.0):
    s = connect(host, port, timeout=timeout)
    try:
        s.sendall(data)
    except OSError:
        pass
    answer = read_answer(s, timeout, 1 << 16)
    s.close()
    return status_of(answer)


def case_limits(host, port, args):
    headers = lambda n: "".join(f"X-{i}: v\r\n" for i in range(n))  # noqa: E731
    cases = [
        ("100 header lines", head_of(host, "/state.json", headers(98) + "Connection: close\r\n") + b"\r\n", 200),
        ("101 header lines", head_of(host, "/state.json", headers(100)) + b"\r\n", 431),
        ("a 5000-byte request line", head_of(host, "/state.json?" + "a" * 5000) + b"\r\n", 414),
        ("a 100000-byte body", head_of(host, "/state.json", "Content-Length: 100000\r\n") + b"\r\n", 413),
        ("a chunked body", head_of(host, "/state.json", "Transfer-Encoding: chunked\r\n") + b"\r\n", 411),
        ("LF line ends", b"GET /state.json HTTP/1.1\nHost: x\n\n", 400),
    ]
    with Rss(args.pid) as rss:
        for what, data, want in cases:
            t0 = time.monotonic()
            got = raw(host, port, data, timeout=8.0)
            took = time.monotonic() - t0
            print(f"viewer_attacks: limits: {what}: {got} in {took * 1000:.0f} ms")
            if got != want:
                fail(f"{what}: answered {got}, expected {want}")
    if rss.peak > args.rss_mb:
        fail(f"limits: VmRSS peaked at {rss.peak:.0f} MB, over {args.rss_mb} MB")


def case_slowloris(host, port, args):
    n = 40
    closed_after = {}

    def slow(i):
        t0 = time.monotonic()
        try:
            s = connect(host, port, timeout=5)
        except OSError:
            closed_after[i] = (0.0, "refused")
            return
        if i % 2 == 0:  # a valid request, a byte every 0.3 s
            how, pause = "byte by byte", 0.3
            pieces = [bytes([b]) for b in head_of(host, "/state.json", "X-Slow: yes\r\n") + b"\r\n"]
        else:  # a head that never ends: a header line every 2 s
            how, pause = "never ends", 2.0
            pieces = [head_of(host, "/state.json")] + [b"X-%d: v\r\n" % k for k in range(1000)]
        s.settimeout(pause)
        answer = b""
        for piece in pieces:  # until the viewer closes the connection (or 30 s)
            if time.monotonic() - t0 > 30:
                break
            try:
                s.sendall(piece)
                chunk = s.recv(4096)  # waits `pause` while the connection stays open
            except socket.timeout:
                continue
            except OSError:
                break
            if not chunk:
                break
            answer += chunk
        closed_after[i] = (time.monotonic() - t0, f"{how}: {status_of(answer)}")
        s.close()

    with Rss(args.pid) as rss:
        threads = [threading.Thread(target=slow, args=(i,)) for i in range(n)]
        for t in threads:
            t.start()
        time.sleep(1.0)
        worst = 0.0
        for _ in range(8):  # during the next 4 s, while every one of them hangs
            worst = max(worst, check_state_fast(host, port, f"{n} slowloris connections hang"))
            time.sleep(0.5)
        for t in threads:
            t.join()
    longest = max(t for t, _ in closed_after.values())
    outcomes = sorted({w for _, w in closed_after.values()})
    print(f"viewer_attacks: slowloris: {n} slow connections; /state.json at worst {worst * 1000:.0f} ms while they "
          f"hung; each closed by the viewer within {longest:.1f} s ({', '.join(outcomes)}); VmRSS {rss.first:.1f} MB "
          f"before, peak {rss.peak:.1f} MB")
    if longest > 10.0:
        fail(f"slowloris: a slow connection was still open after {longest:.1f} s (expected closed within 10 s)")
    if rss.peak > args.rss_mb:
        fail(f"slowloris: VmRSS peaked at {rss.peak:.0f} MB, over {args.rss_mb} MB")


def case_crowd(host, port, args):
    n = 100
    socks, refused_fast = [], 0
    with Rss(args.pid) as rss:
        # 1. One address over its cap: 100 idle connections from 127.0.0.1.
        for _ in range(n):
            try:
                socks.append(connect(host, port, "127.0.0.1", timeout=5))
            except OSError:
                pass
        time.sleep(0.5)
        for s in socks:  # the surplus has its 503 already; the admitted ones say nothing yet
            s.settimeout(0.01)
            try:
                if status_of(s.recv(4096)) == 503:
                    refused_fast += 1
            except OSError:
                pass
        took_other = check_state_fast(host, port, f"{n} idle connections crowd 127.0.0.1", "127.0.0.2")
        _, code_same, took_same = state(host, port, "127.0.0.1")
        if took_same > 1.0:
            fail(f"crowd: /state.json from the crowded address took {took_same:.1f} s (expected an answer within 1 s)")
        # 2. Every connection the viewer takes (256), each with 15 KiB of a head that
        # never ends: the most memory requests can hold.
        partial = head_of(host, "/state.json") + b"".join(b"X-%d: %s\r\n" % (k, b"v" * 200) for k in range(70))
        for a in ("127.0.0.2", "127.0.0.3", "127.0.0.4"):
            for _ in range(64):
                try:
                    c = connect(host, port, a, timeout=5)
                    c.sendall(partial)
                    socks.append(c)
                except OSError:
                    pass
        time.sleep(0.5)
        _, code_full, took_full = state(host, port, "127.0.0.5")
        if code_full is None or took_full > 1.0:
            fail(f"crowd: /state.json with every connection taken: {code_full} in {took_full:.1f} s (expected an "
                 "answer, 503, within 1 s)")
        full_rss = rss.now()
        time.sleep(6.0)  # the idle and unfinished ones: closed after the request timeout (5 s)
        _, code_after, _ = state(host, port, "127.0.0.1")
    for s in socks:
        s.close()
    print(f"viewer_attacks: crowd: {n} idle connections from 127.0.0.1: {refused_fast} refused at once (503); "
          f"/state.json from 127.0.0.2 {took_other * 1000:.0f} ms; from 127.0.0.1 {code_same} in "
          f"{took_same * 1000:.0f} ms; with 256 connections holding {len(partial) / 1024:.1f} KiB heads: /state.json "
          f"{code_full} in {took_full * 1000:.0f} ms, VmRSS {full_rss:.1f} MB; from 127.0.0.1 {code_after} 6 s later; "
          f"VmRSS {rss.first:.1f} MB before, peak {rss.peak:.1f} MB")
    if refused_fast < n - 64 - 1:
        fail(f"crowd: only {refused_fast} of {n} connections from one address were refused at once (cap 64)")
    if code_after != 200:
        fail(f"crowd: /state.json from 127.0.0.1 after the idle connections timed out: {code_after}, not 200")
    if rss.peak > args.rss_mb:
        fail(f"crowd: VmRSS peaked at {rss.peak:.0f} MB, over {args.rss_mb} MB")


class Browser(threading.Thread):
    """An event stream that is read: its status, and the states it received."""

    def __init__(self, host, port, source, query=""):
        super().__init__(daemon=True)
        self.host, self.port, self.source, self.query = host, port, source, query
        self.status, self.states, self.stop, self.ready = None, 0, threading.Event(), threading.Event()

    def run(self):
        try:
            s = connect(self.host, self.port, self.source, timeout=3)
            s.sendall(head_of(self.host, "/events" + self.query, "Accept: text/event-stream\r\n\r\n"))
            data = s.recv(65536)
            self.status = status_of(data)
            self.states += data.count(b"event: state")
            self.ready.set()
            if self.status == 200:
                for n in state_counts(s, lambda: not self.stop.is_set(), 0.5):
                    self.states += n
            s.close()
        except OSError:
            pass
        self.ready.set()


def open_browser(host, port, source, within):
    """A read event stream from `source`, tried every 0.5 s for `within` s: (Browser or None, seconds)."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < within:
        b = Browser(host, port, source)
        b.start()
        b.ready.wait(3)
        if b.status == 200:
            return b, time.monotonic() - t0
        b.stop.set()
        time.sleep(0.5)
    return None, time.monotonic() - t0


def case_streams(host, port, args):
    stalled = []
    with Rss(args.pid) as rss:
        t_open = time.monotonic()
        for _ in range(args.max_clients):
            s = connect(host, port, "127.0.0.1", rcvbuf=1)  # the kernel's least: about 2 KB
            s.sendall(head_of(host, "/events", "\r\n"))
            stalled.append(s)
        held = None
        for _ in range(30):  # the state counts the clients once a second
            s0, _, _ = state(host, port)
            held = s0["viewer"]["clients"] if s0 else None
            if held == args.max_clients:
                break
            time.sleep(0.1)
        took = check_state_fast(host, port, f"{args.max_clients} event streams are never read")
        other, t_other = open_browser(host, port, "127.0.0.2", 2.0)
        same, t_same = open_browser(host, port, "127.0.0.1", 10.0)
        left = None
        while time.monotonic() - t_open < 15.0:  # the viewer closes the stalled ones itself
            s1, _, _ = state(host, port)
            left = s1["viewer"]["clients"] if s1 else None
            if left is not None and left == (other is not None) + (same is not None):
                break
            time.sleep(0.5)
        t_closed = time.monotonic() - t_open
        time.sleep(2.0)
        got = [b.states for b in (other, same) if b]
        for b in (other, same):
            if b:
                b.stop.set()
                b.join()
        for s in stalled:
            s.close()
        after = None
        for _ in range(30):
            s2, _, _ = state(host, port)
            after = s2["viewer"]["clients"] if s2 else None
            if after == 0:
                break
            time.sleep(0.1)
    print(f"viewer_attacks: streams: {args.max_clients} never read, clients {held}; /state.json in "
          f"{took * 1000:.0f} ms; a browser from 127.0.0.2 got a stream "
          f"{'after %.1f s' % t_other if other else 'never'}, one from 127.0.0.1 "
          f"{'after %.1f s' % t_same if same else 'never (10 s)'}; clients {left} {t_closed:.1f} s after the stalled "
          f"ones opened; the browsers received {got} states; clients {after} once all closed; VmRSS "
          f"{rss.first:.1f} MB before, peak {rss.peak:.1f} MB")
    if held != args.max_clients:
        fail(f"streams: {held} clients with {args.max_clients} streams open")
    if other is None:
        fail("streams: a browser from another address got no stream within 2 s")
    if same is None:
        fail("streams: a browser from the stalled streams' address got no stream within 10 s")
    if left != len(got):
        fail(f"streams: {left} clients 15 s after the stalled streams opened (expected the {len(got)} browsers)")
    if any(n < 2 for n in got):
        fail(f"streams: the browsers received {got} states (expected 2 or more each)")
    if after != 0:
        fail(f"streams: {after} clients once every stream closed")
    if rss.peak > args.rss_mb:
        fail(f"streams: VmRSS peaked at {rss.peak:.0f} MB, over {args.rss_mb} MB")


def case_token(host, port, args):
    tok = args.token
    src = args.source
    q = "?token=" + urllib.parse.quote(tok)
    with Rss(args.pid) as rss:
        for path in ("/", "/state.json", "/events"):
            code, _, _ = request(host, port, path, src, timeout=3)
            want(f"{path} from {src} without the token", code, 401)
            code, _, _ = request(host, port, path + "?token=" + "0" * len(tok), src, timeout=3)
            want(f"{path} from {src} with a wrong token", code, 401)
            code, _, _ = request(host, port, path, src, headers="Authorization: Bearer wrong\r\n", timeout=3)
            want(f"{path} from {src} with a wrong bearer", code, 401)
        for path in ("/", "/state.json"):
            code, _, _ = request(host, port, path, src, headers=f"Authorization: Bearer {tok}\r\n")
            want(f"{path} from {src} with Authorization: Bearer", code, 200)
            code, _, _ = request(host, port, path + q, src)
            want(f"{path} from {src} with ?token=", code, 200)
        b = Browser(host, port, src, q)
        b.start()
        b.ready.wait(3)
        time.sleep(1.5)
        b.stop.set()
        b.join()
        want(f"/events from {src} with ?token= ({b.states} states)", b.status, 200)
    if rss.peak > args.rss_mb:
        fail(f"token: VmRSS peaked at {rss.peak:.0f} MB, over {args.rss_mb} MB")


def want(what, got, expected):
    print(f"viewer_attacks: token: {what}: {got}")
    if got != expected:
        fail(f"{what}: {got}, expected {expected}")


CASES = {"flood": case_flood, "limits": case_limits, "slowloris": case_slowloris, "crowd": case_crowd,
         "streams": case_streams, "token": case_token}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("case", choices=sorted(CASES))
    ap.add_argument("url")
    ap.add_argument("--pid", type=int, required=True, help="the viewer's process id (its VmRSS is read)")
    ap.add_argument("--rss-mb", type=float, default=64.0, help="the bound on the viewer's VmRSS (MB)")
    ap.add_argument("--max-clients", type=int, default=8)
    ap.add_argument("--source", help="token: the non-loopback address to connect from")
    ap.add_argument("--token", help="token: the viewer's access token")
    args = ap.parse_args()
    u = urllib.parse.urlparse(args.url)
    CASES[args.case](u.hostname, u.port, args)
    return 1 if BAD else 0


if __name__ == "__main__":
    sys.exit(main())

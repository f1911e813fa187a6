#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Slow, stalled and too many browsers cost the viewer nothing unbounded
(system_viewer): MAX event streams are opened and never read while the viewer
publishes; /state.json still answers at once; a browser that reads gets a stream
within 10 s all the same (it evicts the stream stalled the longest: docs/
security_viewer.md); the viewer closes the stalled streams itself within 15 s (its
count of clients is then the one browser), and the count goes back to 0 once the
browser closes too.

    viewer_clients.py URL --max N
Exit 0 when all of that holds, 1 otherwise.
"""
import argparse
import json
import socket
import sys
import time
import urllib.parse
import urllib.request

from event_stream import state_counts


def open_stream(host, port):
    s = socket.create_connection((host, port), timeout=5)
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)  # fills at once: the viewer sees the reader stall
    s.sendall(f"GET /events HTTP/1.1\r\nHost: {host}\r\n\r\n".encode())
    return s


def state(url):
    t0 = time.monotonic()
    with urllib.request.urlopen(url + "/state.json", timeout=5) as r:
        s = json.load(r)
    return s, time.monotonic() - t0


def reading_stream(host, port, within):
    """A browser's stream, tried every 0.5 s for `within` s: (socket, first line, seconds)."""
    t0 = time.monotonic()
    first = ""
    while time.monotonic() - t0 < within:
        s = socket.create_connection((host, port), timeout=5)
        s.sendall(f"GET /events HTTP/1.1\r\nHost: {host}\r\n\r\n".encode())
        head = s.recv(65536).decode(errors="replace")
        first = head.splitlines()[0] if head else "nothing"
        if " 200 " in first:
            return s, first, time.monotonic() - t0
        s.close()
        time.sleep(0.5)
    return None, first, time.monotonic() - t0


def drain(s, seconds):
    """Reads the stream for `seconds`: the count of states received."""
    t_end = time.monotonic() + seconds
    return sum(state_counts(s, lambda: time.monotonic() < t_end, 0.2))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("url")
    ap.add_argument("--max", type=int, required=True)
    args = ap.parse_args()
    u = urllib.parse.urlparse(args.url)
    bad = []
    # A browser of the test before (browser_check.py) may still hold its stream for a
    # moment after it quit: the slots are all free first.
    t_free = time.monotonic()
    while state(args.url)[0]["viewer"]["clients"] != 0 and time.monotonic() - t_free < 10.0:
        time.sleep(0.2)
    t_open = time.monotonic()
    stalled = [open_stream(u.hostname, u.port) for _ in range(args.max)]
    time.sleep(3)  # 60 states at 20 Hz pile up against sockets nobody reads
    s, took = state(args.url)
    clients = s["viewer"]["clients"]
    # On a loaded machine the last streams may be counted a moment later (the state is
    # rebuilt at --rate): looked at again until all are, before any can be stalled
    # long enough to be closed (5 s).
    while clients != args.max and time.monotonic() - t_open < 4.5:
        time.sleep(0.2)
        clients = state(args.url)[0]["viewer"]["clients"]
    if clients != args.max:
        bad.append(f"clients {clients}, not {args.max}")
    if took > 1.0:
        bad.append(f"/state.json took {took:.1f} s with stalled streams")
    browser, first, waited = reading_stream(u.hostname, u.port, 10.0)
    print(f"viewer_clients: {args.max} stalled streams: clients {clients}, /state.json in {took * 1000:.0f} ms, "
          f"a browser's stream: {first} after {waited:.1f} s")
    if browser is None:
        bad.append(f"a browser got no stream within 10 s with {args.max} stalled ones: {first}")
    left = None
    while time.monotonic() - t_open < 15.0:  # the viewer closes the stalled ones itself
        if browser:
            drain(browser, 0.3)
        left = state(args.url)[0]["viewer"]["clients"]
        if left == (1 if browser else 0):
            break
    received = drain(browser, 1.0) if browser else 0
    print(f"viewer_clients: {time.monotonic() - t_open:.1f} s after the stalled streams opened, clients {left}; "
          f"the browser received {received} states in the last second")
    if left != (1 if browser else 0):
        bad.append(f"{left} clients 15 s after the stalled streams opened: the viewer did not close them")
    if browser and received < 1:
        bad.append("the browser received no state in a second")
    for st in stalled + ([browser] if browser else []):
        st.close()
    for _ in range(100):  # the next write to each fails; the count follows
        if state(args.url)[0]["viewer"]["clients"] == 0:
            break
        time.sleep(0.1)
    left = state(args.url)[0]["viewer"]["clients"]
    print(f"viewer_clients: after closing them, clients {left}")
    if left != 0:
        bad.append(f"{left} clients left after the streams closed")
    for b in bad:
        print("viewer_clients: FAIL " + b)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Slow, stalled and too many browsers cost the viewer nothing unbounded
(system_viewer): MAX event streams are opened and never read while the viewer
publishes; one more is refused (503); /state.json still answers at once; then the
stalled streams are closed and the viewer's count of clients goes back to 0.

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


def open_stream(host, port):
    s = socket.create_connection((host, port), timeout=5)
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)  # fills at once: the server's writes block
    s.sendall(f"GET /events HTTP/1.1\r\nHost: {host}\r\n\r\n".encode())
    return s


def state(url):
    t0 = time.monotonic()
    with urllib.request.urlopen(url + "/state.json", timeout=5) as r:
        s = json.load(r)
    return s, time.monotonic() - t0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("url")
    ap.add_argument("--max", type=int, required=True)
    args = ap.parse_args()
    u = urllib.parse.urlparse(args.url)
    bad = []
    stalled = [open_stream(u.hostname, u.port) for _ in range(args.max)]
    time.sleep(3)  # 60 states at 20 Hz pile up against sockets nobody reads
    extra = open_stream(u.hostname, u.port)
    head = extra.recv(64).decode(errors="replace")
    extra.close()
    if " 503 " not in head.split("\r\n")[0]:
        bad.append(f"stream {args.max + 1} was not refused: {head.splitlines()[0] if head else 'nothing'}")
    s, took = state(args.url)
    clients = s["viewer"]["clients"]
    print(f"viewer_clients: {args.max} stalled streams: clients {clients}, /state.json in {took * 1000:.0f} ms, "
          f"stream {args.max + 1}: {head.splitlines()[0] if head else 'nothing'}")
    if clients != args.max:
        bad.append(f"clients {clients}, not {args.max}")
    if took > 1.0:
        bad.append(f"/state.json took {took:.1f} s with stalled streams")
    for st in stalled:
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

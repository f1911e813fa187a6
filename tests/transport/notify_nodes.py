#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The real programs speak systemd's notify protocol (test `notify_nodes`).

robot_node, main_robot and the simulator are started as systemd would start them as
Type=notify services with WatchdogSec=: $NOTIFY_SOCKET names a datagram socket of this
test's, $WATCHDOG_USEC is set. Each must say READY=1, then WATCHDOG=1 about every
half period; stopped with SIGSTOP (a hang) it must say nothing; continued, it pings
again; SIGTERM: STOPPING=1 and exit 0. LCM on memq:// (nothing on any network); no
systemd needed.
    notify_nodes.py BUILD_DIR
"""
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time

WATCHDOG_US = 400_000  # pings every 200 ms


def recv_until(sock, want, timeout):
    """Datagrams until one equals `want` (True) or `timeout` s pass (False); all seen."""
    seen = []
    end = time.monotonic() + timeout
    while True:
        left = end - time.monotonic()
        if left <= 0:
            return False, seen
        sock.settimeout(left)
        try:
            d = sock.recv(512).decode(errors="replace")
        except socket.timeout:
            return False, seen
        seen.append(d)
        if d == want or d.startswith(want + "\n"):
            return True, seen


def count(sock, want, window):
    n = 0
    end = time.monotonic() + window
    while True:
        left = end - time.monotonic()
        if left <= 0:
            return n
        sock.settimeout(left)
        try:
            if sock.recv(512).decode(errors="replace") == want:
                n += 1
        except socket.timeout:
            return n


def check(name, cmd, tmp):
    path = os.path.join(tmp, name + ".sock")
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    sock.bind(path)
    env = dict(os.environ, NOTIFY_SOCKET=path, WATCHDOG_USEC=str(WATCHDOG_US), LCM_DEFAULT_URL="memq://")
    env.pop("WATCHDOG_PID", None)
    log = open(os.path.join(tmp, name + ".log"), "w+")
    p = subprocess.Popen(cmd, env=env, stdout=log, stderr=subprocess.STDOUT)
    problems = []
    try:
        ok, seen = recv_until(sock, "READY=1", 30)
        if not ok:
            problems.append(f"no READY=1 within 30 s (got {seen})")
            return problems
        t0 = time.monotonic()
        pings = count(sock, "WATCHDOG=1", 1.2)
        if pings < 3:
            problems.append(f"{pings} WATCHDOG=1 in 1.2 s after READY=1, expected about 6")
        p.send_signal(signal.SIGSTOP)  # hung: the loop turns no more
        count(sock, "WATCHDOG=1", 0.05)  # one in flight
        hung = count(sock, "WATCHDOG=1", 3 * WATCHDOG_US / 1e6)
        if hung:
            problems.append(f"{hung} WATCHDOG=1 while the process was stopped")
        p.send_signal(signal.SIGCONT)
        ok, _ = recv_until(sock, "WATCHDOG=1", 5)
        if not ok:
            problems.append("no WATCHDOG=1 after SIGCONT")
        p.send_signal(signal.SIGTERM)
        ok, seen = recv_until(sock, "STOPPING=1", 10)
        if not ok:
            problems.append(f"no STOPPING=1 after SIGTERM (got {seen[-3:]})")
        rc = p.wait(timeout=20)
        if rc != 0:
            problems.append(f"exit status {rc} after SIGTERM")
        print(f"{name}: READY=1, {pings} pings in 1.2 s, none while stopped, STOPPING=1, exit {rc} "
              f"({time.monotonic() - t0:.1f} s)")
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
        sock.close()
        if problems:
            log.seek(0)
            print(f"--- {name}'s log:\n{log.read()[-3000:]}", file=sys.stderr)
        log.close()
    return problems


def main():
    build = os.path.abspath(sys.argv[1])
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    config = os.path.join(root, "config", "paper.yaml")
    bins = os.path.join(build, "bin")
    progs = {
        "robot_node": [os.path.join(bins, "robot_node"), "--robot", "1", "--config", config],
        "main_robot": [os.path.join(bins, "main_robot"), "--config", config],
        "simulator": [os.path.join(bins, "simulator"), "--config", config, "--frames", "100000"],
    }
    failed = 0
    with tempfile.TemporaryDirectory(prefix="elaslam-notify-") as tmp:
        for name, cmd in progs.items():
            for problem in check(name, cmd, tmp):
                print(f"FAIL {name}: {problem}", file=sys.stderr)
                failed += 1
    print("PASS" if failed == 0 else f"FAIL ({failed} problems)")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())

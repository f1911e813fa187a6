# SPDX-License-Identifier: Apache-2.0
"""The run of an attacking process (forger.py, insider.py): numbered rounds until
SIGTERM / SIGINT or the end of its duration, and the team heard between rounds.
Standard library only, until set_up() imports lcm."""
import argparse
import signal
import time

from elaslam_tool import load_lcm_types, need


def set_up(doc, add_arguments, period):
    """The command line of an attacker documented by `doc` (its own options added by
    add_arguments(parser); theirs: --build-dir, --period [s] between rounds, default
    `period`, --duration [s]), the message types of the build, and an LCM on
    LCM_DEFAULT_URL: (args, types, the lcm module, lcm.LCM())."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--build-dir", required=True)
    add_arguments(ap)
    ap.add_argument("--period", type=float, default=period)
    ap.add_argument("--duration", type=float, default=600.0)
    args = ap.parse_args()
    types = load_lcm_types(args.build_dir, __file__)
    lcm = need("lcm")
    return args, types, lcm, lcm.LCM()


class Rounds:
    """Iterating gives the rounds 1, 2, ... while the process is neither stopped nor
    past `duration` seconds from now."""

    def __init__(self, duration):
        self.stopped = False
        for s in (signal.SIGTERM, signal.SIGINT):
            signal.signal(s, self._stop)
        self.end = time.monotonic() + duration

    def _stop(self, *_):
        self.stopped = True

    def __iter__(self):
        n = 0
        while not self.stopped and time.monotonic() < self.end:
            n += 1
            yield n

    def listen(self, lc, seconds):
        """Handles what `lc` (an lcm.LCM) hears for `seconds`, or until stopped."""
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline and not self.stopped:
            try:
                lc.handle_timeout(max(1, int((deadline - time.monotonic()) * 1000)))
            except OSError:  # the wait interrupted by SIGTERM / SIGINT
                pass

#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Seed corpus of fuzz_datagrams (fuzz/fuzz_datagrams.cpp): real signed traffic and the
malformed family, as raw udpm:// datagrams behind the target's selector byte.

    fuzz/make_datagram_corpus.py --fuzzer BUILD/bin/fuzz_datagrams [--out fuzz/corpus/fuzz_datagrams]

- The real traffic comes from the target itself (`fuzz_datagrams --write-seeds=DIR`):
  robot 1's SENSOR_1 frames of config/paper.yaml's scenario signed by the simulator's
  key, what robot_node 1 and main_robot publish on them (signed by robot 1 and main,
  the test team's keys: tests/support/test_keys.hpp), framed as liblcm frames them, whole
  or in fragments interleaved with another sender's; the same without the trailers for
  the configurations without authentication. Files robot_* and main_*.
- The malformed family of tests/system/raw_datagrams.py (--write-corpus: the pair that
  crashed liblcm's receive thread, every prefix of a valid datagram, fragments with every
  size field at its extremes, impossible channel names), its files family_NNN each behind
  a selector byte, the four configurations in turn (0 robot 1 signed, 1 main signed,
  2 robot 1 plain, 3 main plain).

Replaces the generated files in OUT; other files there (regression inputs: regression-*, found by fuzzing and fixed) stay.
Standard library only.
"""
import argparse
import glob
import os
import subprocess
import sys
import tempfile

_here = os.path.dirname(os.path.realpath(__file__))
sys.path.insert(0, os.path.join(_here, "..", "tools"))
from elaslam_tool import add_version, parse_args  # noqa: E402

RAW = os.path.join(_here, "..", "tests", "system", "raw_datagrams.py")
CONFIGS = 4  # fuzz_datagrams' selector % 4


def main():
    ap = argparse.ArgumentParser(prog="make_datagram_corpus.py", description=__doc__.split("\n\n")[0])
    add_version(ap)
    ap.add_argument("--fuzzer", required=True, help="the built fuzz_datagrams (e.g. build/fuzz/bin/fuzz_datagrams)")
    ap.add_argument("--out", default=os.path.join(_here, "corpus", "fuzz_datagrams"))
    args = parse_args(ap)
    if not os.access(args.fuzzer, os.X_OK):
        sys.exit(f"make_datagram_corpus: not an executable: {args.fuzzer} "
                 "(tools/fuzz.sh --targets fuzz_datagrams builds it)")
    os.makedirs(args.out, exist_ok=True)
    for old in glob.glob(os.path.join(args.out, "robot_*")) + glob.glob(os.path.join(args.out, "main_*")) + \
            glob.glob(os.path.join(args.out, "family_*")):
        os.remove(old)
    subprocess.run([args.fuzzer, f"--write-seeds={args.out}"], check=True)
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([sys.executable, RAW, "--write-corpus", tmp], check=True, stdout=subprocess.DEVNULL)
        names = sorted(os.listdir(tmp))
        for i, name in enumerate(names):
            with open(os.path.join(tmp, name), "rb") as f:
                records = f.read()
            with open(os.path.join(args.out, name), "wb") as f:
                f.write(bytes([i % CONFIGS]) + records)
    files = sorted(os.listdir(args.out))
    total = sum(os.path.getsize(os.path.join(args.out, n)) for n in files)
    print(f"make_datagram_corpus: {args.out}: {len(files)} files ({len(names)} of the malformed family), {total} bytes")


if __name__ == "__main__":
    main()

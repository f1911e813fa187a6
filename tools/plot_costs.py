#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Plot the cost curves from Google Benchmark JSON files.

    tools/plot_costs.py --ekf EKF.json --main MAIN.json [--out DIR]

EKF.json is `build/bin/bench_ekf --benchmark_format=json` (or --benchmark_out=...
--benchmark_out_format=json), MAIN.json the same of build/bin/bench_main; with
--benchmark_repetitions the medians are plotted. PNGs go to DIR (default .):

  cost_ekf_frame.png     robot frame time against landmarks in the filter (16-1,024),
                         default and Joseph forms, and the dense textbook EKF
  cost_main_frame.png    main_robot's time per team frame against robots (1-16, at 1,024
                         landmarks) and against global landmarks (72-4,096, 16 robots), with
                         the GLOBAL_MAP bytes per frame on a second axis

Exit status 1 (naming what is missing) when a file is absent or holds none of the
benchmarks above; 2 on a bad command line or a missing module (tools/setup.sh's
.venv, or Debian's python3-matplotlib for an installed copy).
"""
# ---- start-up: standard library only, before any third-party import (tools/elaslam_tool.py)
import os
import sys

_here = os.path.dirname(os.path.realpath(__file__))
sys.path[:0] = [_here, os.path.join(_here, "..", "share", "elaslam", "tools")]
from elaslam_tool import add_version, need as _need, parse_args as _parse, run_in_venv  # noqa: E402

if __name__ == "__main__":
    run_in_venv()
# ----------------------------------------------------------------------------------
import argparse  # noqa: E402
import json  # noqa: E402
import re  # noqa: E402

plt = None
DPI = 150


class InputError(Exception):
    pass


def load_modules():
    global plt
    matplotlib = _need("matplotlib", "python3-matplotlib")
    matplotlib.use("Agg")
    plt = _need("matplotlib.pyplot", "python3-matplotlib")


def read(path):
    """{run_name: (time_us, counters)} from a benchmark JSON file: the median of
    repetitions when there are aggregates, else the single run."""
    try:
        with open(path) as f:
            doc = json.load(f)
    except OSError as e:
        raise InputError(f"{path}: {e.strerror}")
    except json.JSONDecodeError as e:
        raise InputError(f"{path}: not JSON ({e})")
    rows = {}
    medians = {}
    for b in doc.get("benchmarks", []):
        name = b.get("run_name", b.get("name", ""))
        scale = {"ns": 1e-3, "us": 1.0, "ms": 1e3, "s": 1e6}.get(b.get("time_unit", "ns"), 1e-3)
        value = (b.get("real_time", 0.0) * scale, b)
        if b.get("aggregate_name") == "median":
            medians[name] = value
        elif b.get("run_type", "iteration") == "iteration":
            rows.setdefault(name, value)
    rows.update(medians)
    if not rows:
        raise InputError(f"{path}: no benchmarks in it")
    return rows


def series(rows, prefix, arg):
    """[(x, time_us, run)] for the runs `prefix/...arg:x...`, sorted by x."""
    out = []
    for name, (t, b) in rows.items():
        if not name.startswith(prefix + "/"):
            continue
        m = re.search(arg + r":(\d+)", name)
        if m:
            out.append((int(m.group(1)), t, b))
    return sorted(out)


def plot_ekf(rows, out):
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    drawn = 0
    for prefix, label, style in [("BM_EkfSlamFrame", "EkfSlam (default, batched rank-2k)", "o-"),
                                 ("BM_EkfSlamFrameJosephForm", "EkfSlam, Joseph form", "s--"),
                                 ("BM_DenseEkfFrame", "dense textbook EKF", "^:")]:
        s = series(rows, prefix, "landmarks")
        if not s:
            continue
        ax.plot([x for x, _, _ in s], [t for _, t, _ in s], style, label=label)
        drawn += 1
    if not drawn:
        raise InputError("no BM_EkfSlamFrame* / BM_DenseEkfFrame runs in the EKF file")
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xlabel("landmarks in the filter")
    ax.set_ylabel("time per frame (predict + 15 updates) [us]")
    ax.set_title("Robot filter frame time (bench_ekf)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    path = os.path.join(out, "cost_ekf_frame.png")
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


def plot_main(rows, out):
    s = series(rows, "BM_MainFrame", "robots")
    by_robots = [(x, t, b) for x, t, b in s if re.search(r"landmarks:1024\b", b.get("run_name", b.get("name", "")))]
    by_landmarks = [(int(re.search(r"landmarks:(\d+)", b.get("run_name", b.get("name", ""))).group(1)), t, b)
                    for x, t, b in s if x == 16]
    by_landmarks.sort()
    if not by_robots and not by_landmarks:
        raise InputError("no BM_MainFrame runs in the main_robot file")
    fig, (a, b2) = plt.subplots(1, 2, figsize=(10, 4.2))
    a.plot([x for x, _, _ in by_robots], [t for _, t, _ in by_robots], "o-")
    a.set_xlabel("robots (1,024 landmarks)")
    a.set_ylabel("main_robot time per team frame [us]")
    a.set_xscale("log", base=2)
    a.set_ylim(bottom=0)
    a.grid(True, alpha=0.3)
    a.set_title("against the team's size")
    b2.plot([x for x, _, _ in by_landmarks], [t for _, t, _ in by_landmarks], "o-", label="time per frame")
    b2.set_xscale("log")
    b2.set_xlabel("global landmarks (16 robots)")
    b2.set_ylabel("time per team frame [us]")
    b2.set_ylim(bottom=0)
    b2.grid(True, alpha=0.3)
    b2.set_title("against the world's size")
    kb = b2.twinx()
    kb.plot([x for x, _, _ in by_landmarks], [r.get("map_bytes", 0) / 1000.0 for _, _, r in by_landmarks], "s--",
            color="tab:red", label="GLOBAL_MAP per frame")
    kb.set_ylabel("GLOBAL_MAP per frame [kB]", color="tab:red")
    kb.set_ylim(bottom=0)
    fig.tight_layout()
    path = os.path.join(out, "cost_main_frame.png")
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


def main():
    ap = argparse.ArgumentParser(description="Plot bench_ekf / bench_main cost curves (docs/benchmarks.md).")
    add_version(ap)
    ap.add_argument("--ekf", required=True, help="bench_ekf JSON output")
    ap.add_argument("--main", required=True, help="bench_main JSON output")
    ap.add_argument("--out", default=".", help="directory for the PNGs (default .)")
    args = _parse(ap)
    try:
        ekf, main_rows = read(args.ekf), read(args.main)
        load_modules()
        os.makedirs(args.out, exist_ok=True)
        for p in (plot_ekf(ekf, args.out), plot_main(main_rows, args.out)):
            print(f"wrote {p}")
    except InputError as e:
        print(f"plot_costs.py: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

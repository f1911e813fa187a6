#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Which of a sweep's cell-metrics does one mode win against another, and which of
the wins and losses are more than noise?

Reads a sweep's runs.csv (`build/bin/sweep ... --out DIR`). For every cell
(dynamism, speed) and metric (landmark error, each robot's error) it pairs the
runs of the two modes by seed, takes the mean of the differences A - B and a
two-sided paired t-test at 5 %. A cell-metric is won when the mean difference is
below zero (the sweep's "cells won" rule); it is a significant win or loss when
|t| is above the critical value for n - 1 degrees of freedom.

Several sweeps (DIR DIR ...; other --seed-base, the same grid) are pooled: each
cell then has every sweep's runs. A seed run twice in a cell with one mode (the
same seed base twice) is refused: it would count one run as two.

Usage: tools/paired_cells.py DIR [DIR ...] [--a ela] [--b ekf]
"""
import argparse
import collections
import csv
import math
import os
import statistics
import sys

_here = os.path.dirname(os.path.realpath(__file__))
sys.path[:0] = [_here, os.path.join(_here, "..", "share", "elaslam", "tools")]
from elaslam_tool import add_version, parse_args  # noqa: E402  (standard library only)

# Two-sided 5 % critical values of Student's t, degrees of freedom 1-30; above, 1.96.
T975 = [12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228,
        2.201, 2.179, 2.160, 2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086,
        2.080, 2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048, 2.045, 2.042]


def t_critical(dof):
    return T975[dof - 1] if dof <= len(T975) else 1.96


def runs_files(dirs):
    """The runs.csv of each sweep directory, in the order given."""
    return [f"{d}/runs.csv" for d in dirs]


def read_runs(dirs):
    """The sweeps' runs pooled: {(dynamism, speed, seed): {mode: row}} and the
    metrics to compare (from the first row). Exits with file:line on a bad row or
    on a seed that is already in for its mode."""
    runs = collections.defaultdict(dict)
    metrics = None
    for path in runs_files(dirs):
        try:
            with open(path, newline="") as f:
                rows = list(csv.DictReader(f))
        except OSError as e:
            sys.exit(f"paired_cells.py: cannot read {path}: {e.strerror}")
        for i, r in enumerate(rows, start=2):
            try:
                key = (int(r["dynamism"]), float(r["speed"]), int(r["seed"]))
                mode = r["mode"]
            except (KeyError, TypeError, ValueError):
                sys.exit(f"paired_cells.py: {path}:{i}: not a sweep's runs.csv row (mode, dynamism, speed, seed)")
            if metrics is None:
                metrics = ["landmark_error"] + sorted(k for k in r if k.startswith("robot") and k.endswith("_error"))
            if mode in runs[key]:
                sys.exit(f"paired_cells.py: {path}:{i}: seed {key[2]} of mode {mode} at {key[0]} % / {key[1]} m/s "
                         "is already in (the same seed base twice?)")
            runs[key][mode] = r
    if metrics is None:
        sys.exit(f"paired_cells.py: {' '.join(runs_files(dirs))} has no runs")
    return runs, metrics


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_version(ap)
    ap.add_argument("dirs", nargs="+", metavar="DIR",
                    help="a sweep's output directory (its runs.csv); several are pooled")
    ap.add_argument("--a", default="ela", help="mode A (default ela)")
    ap.add_argument("--b", default="ekf", help="mode B (default ekf)")
    args = parse_args(ap)
    runs, metrics = read_runs(args.dirs)
    sources = " ".join(runs_files(args.dirs))  # what the messages below name
    diffs = collections.defaultdict(list)
    for (dyn, speed, _), by_mode in runs.items():
        if args.a not in by_mode or args.b not in by_mode:
            continue
        for m in metrics:
            try:
                d = float(by_mode[args.a][m]) - float(by_mode[args.b][m])
            except (KeyError, TypeError, ValueError):
                sys.exit(f"paired_cells.py: {sources}: no number for {m}")
            if math.isfinite(d):
                diffs[(dyn, speed, m)].append(d)
    if not diffs:
        sys.exit(f"paired_cells.py: {sources} has no seed run in both {args.a} and {args.b}")
    won = sig_won = lost = sig_lost = 0
    print(f"{args.a} - {args.b}, paired by seed: mean difference, paired t (two-sided 5 %)")
    for (dyn, speed, m), d in sorted(diffs.items()):
        mean = statistics.fmean(d)
        se = statistics.stdev(d) / math.sqrt(len(d)) if len(d) > 1 else float("inf")
        t = mean / se if se > 0 else 0.0
        significant = len(d) > 1 and abs(t) > t_critical(len(d) - 1)
        if mean < 0:
            won += 1
            sig_won += significant
        else:
            lost += 1
            sig_lost += significant
            print(f"  lost  {dyn:3d} % {speed:.1f} m/s {m:16s} {mean:+.4f} m  t {t:+.3g}"
                  f"{'  significant' if significant else ''}")
    total = won + lost
    print(f"{args.a} below {args.b} in {won} of {total} cell-metrics ({sig_won} significant); "
          f"lost {lost} ({sig_lost} significant)")


if __name__ == "__main__":
    main()

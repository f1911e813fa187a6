#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""A recording from many start times: the same MRCLAM recording started
later is a different run for the filters (other robots stand or drive when the maps
begin, other landmarks come first), so the mean over several starts says more than
one run. Runs run_dataset for each start, mode and barcode setting, in parallel, and
tabulates each robot's RMS position error, the five-robot mean, the worst robot and
how often the team map's verdicts fired (relocalised, lost: Robot::apply_team_map).

  tools/mrclam_starts.py [--dataset DIR] [--config FILE] [--build-dir DIR] [--out DIR]
                         [--starts 0,50,...,650] [--modes ela,consensus]
                         [--barcodes both|with|without] [--jobs N] [-- RUN_DATASET_ARGS...]

Writes OUT/report.md and OUT/report.json (default results/mrclam_starts) and prints
the table. Arguments after `--` go to every run_dataset (e.g. --robots 1,2).
Exit 0, 1 when a run failed, 2 bad arguments.
"""
import argparse
import concurrent.futures
import json
import os
import subprocess
import sys

_here = os.path.dirname(os.path.realpath(__file__))
sys.path[:0] = [_here, os.path.join(_here, "..", "share", "elaslam", "tools")]
from elaslam_tool import add_version, parse_args  # noqa: E402  (standard library only)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_STARTS = ",".join(str(s) for s in range(0, 651, 50))


def one_run(build, dataset, config, start, mode, barcodes, out, extra):
    cmd = [os.path.join(build, "bin", "run_dataset"), "--dataset", dataset, "--config", config, "--mode", mode,
           "--start", str(start), "--out", out, "--no-plots"] + extra
    if barcodes:
        cmd.append("--with-robot-barcodes")
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        return None, f"{' '.join(cmd)} exited {p.returncode}\n{p.stderr[-2000:]}"
    m = json.load(open(os.path.join(out, "metrics.json")))
    robots = {str(r["id"]): {"rms": r["error_rms"], "relocalised": r.get("relocalised", 0),
                             "lost": r.get("team_lost", 0)} for r in m["robots"]}
    return robots, None


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dataset", default=os.path.join(ROOT, "data", "mrclam", "dataset6"))
    ap.add_argument("--config", default=os.path.join(ROOT, "config", "mrclam.yaml"))
    ap.add_argument("--build-dir", default=os.path.join(ROOT, "build"))
    ap.add_argument("--out", default=os.path.join(ROOT, "results", "mrclam_starts"))
    ap.add_argument("--starts", default=DEFAULT_STARTS, help="start times [s], comma-separated")
    ap.add_argument("--modes", default="ela,consensus")
    ap.add_argument("--barcodes", default="both", help="both, with or without the other robots' barcodes")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("extra", nargs="*", help="after --: arguments for every run_dataset")
    add_version(ap)
    a = parse_args(ap)
    try:
        starts = [float(s) for s in a.starts.split(",")]
    except ValueError:
        ap.error(f"--starts {a.starts}: numbers separated by commas")
    if not starts or any(s < 0 for s in starts):
        ap.error("--starts: at least one, none negative")
    modes = a.modes.split(",")
    if not all(m in ("ekf", "gated", "ela", "consensus") for m in modes):
        ap.error("--modes: ekf, gated, ela, consensus")
    if a.barcodes not in ("both", "with", "without"):
        ap.error(f"--barcodes {a.barcodes}: both, with or without")
    if a.jobs < 1:
        ap.error("--jobs: at least 1")
    if not os.path.isdir(a.dataset):
        ap.error(f"--dataset {a.dataset}: not a directory")
    if not os.path.isfile(a.config):
        ap.error(f"--config {a.config}: no such file")
    settings = {"both": (False, True), "with": (True,), "without": (False,)}[a.barcodes]
    os.makedirs(a.out, exist_ok=True)
    jobs = []
    for mode in modes:
        for barcodes in settings:
            for s in starts:
                tag = f"{mode}{'_barcodes' if barcodes else ''}_start{s:g}"
                jobs.append((mode, barcodes, s, os.path.join(a.out, tag)))
    results = {}
    with concurrent.futures.ThreadPoolExecutor(max_workers=a.jobs) as pool:
        futures = {pool.submit(one_run, a.build_dir, a.dataset, a.config, s, mode, barcodes, out, a.extra):
                   (mode, barcodes, s) for mode, barcodes, s, out in jobs}
        for f in concurrent.futures.as_completed(futures):
            robots, err = f.result()
            if err:
                sys.stderr.write(f"mrclam_starts: {err}\n")
                return 1
            results[futures[f]] = robots
    report = {"dataset": os.path.abspath(a.dataset), "config": os.path.abspath(a.config), "starts": starts,
              "runs": []}
    lines = ["# MRCLAM from several start times (tools/mrclam_starts.py)", "",
             f"{os.path.basename(os.path.normpath(a.dataset))}, config {os.path.relpath(a.config, ROOT)}; "
             "RMS position error [m] per robot against the recording's ground truth; mean of the robots; "
             "worst robot; team-map verdicts (relocalised / lost) summed over the robots.", ""]
    for mode in modes:
        for barcodes in settings:
            name = mode + (", robot barcodes kept" if barcodes else "")
            lines += [f"## {name}", "", "| start [s] | per robot | mean | worst | relocalised / lost |",
                      "|---|---|---|---|---|"]
            means, worst_all = [], 0.0
            for s in starts:
                robots = results[(mode, barcodes, s)]
                rms = [r["rms"] for _, r in sorted(robots.items(), key=lambda kv: int(kv[0]))]
                mean = sum(rms) / len(rms)
                worst = max(rms)
                means.append(mean)
                worst_all = max(worst_all, worst)
                reloc = sum(r["relocalised"] for r in robots.values())
                lost = sum(r["lost"] for r in robots.values())
                lines.append(f"| {s:g} | {' '.join(f'{v:.3f}' for v in rms)} | {mean:.3f} | {worst:.3f} | "
                             f"{reloc} / {lost} |")
                report["runs"].append({"mode": mode, "barcodes": barcodes, "start": s, "robots": robots,
                                       "mean": mean, "worst": worst})
            lines += [f"| all | | {sum(means) / len(means):.3f} | {worst_all:.3f} | |", ""]
    with open(os.path.join(a.out, "report.json"), "w") as f:
        json.dump(report, f, indent=1)
    with open(os.path.join(a.out, "report.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())

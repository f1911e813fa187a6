#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Golden regression: today's results against a committed, seeded reference.

  golden.py check  --build DIR [--part P] the in-process outputs, exactly: --part simulated
                                          (the sweep and the scenarios: test golden_inprocess),
                                          mrclam (the MRCLAM slice: test golden_mrclam; exit 77,
                                          skipped, without the data) or all (the default)
  golden.py live   --build DIR            the live team against the in-process reference,
                                          within LIVE_TOL (test golden_live; root)
  golden.py update --build DIR            rewrite the reference (in the commit that means
                                          to change results, saying why)

The reference (tests/golden/reference/, README.md there) holds:
  sweep_runs.csv                 a reduced sweep: 4 modes x dynamism 20, 80 x speed 0.3, 0.9
                                 x 2 runs (seeds 1, 2): every figure of every run
  scenario_<name>.metrics.json   run_scenario's metrics.json of two seeded scenarios, and
  scenario_<name>.frames.csv     their per-frame errors
  mrclam_slice.report.json       run_dataset --report on the first 120 s of MRCLAM dataset6
                                 (ekf, ela, consensus, without and with robot barcodes);
                                 needs data/mrclam/dataset6 (tools/get_mrclam.sh): without it
                                 `check --part mrclam` says so and exits 77 (a ctest skip),
                                 `check` (all) and `update` say which file was not made
In-process results are deterministic: they are compared exactly (JSON numbers as
written, 17 significant digits; CSV text as written). What varies from run to run
is left out: processing times ("timing"), the version, the command line and paths.
The live team must match the in-process reference frame by frame within LIVE_TOL
(live and in-process runs compute the same thing; the tolerance only absorbs the
text round trip), and when the recorder lost no POSE, in its whole-run figures.
Exit 1 with every difference named; 77 (skip) for `live` without root and for
`check --part mrclam` without the data.
"""
import argparse
import csv
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.realpath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
REF = os.path.join(HERE, "reference")
CONFIG = os.path.join(ROOT, "config", "paper.yaml")
DATASET = os.path.join(ROOT, "data", "mrclam", "dataset6")
LIVE_TOL = 1e-6  # [m] live against in-process, per frame

# name -> run_scenario arguments (also the live team's, with run_team.sh).
SCENARIOS = {
    "ela_50_0.5_seed3": ["--mode", "ela", "--dynamism", "50", "--speed", "0.5", "--seed", "3"],
    "consensus_80_0.9_seed5": ["--mode", "consensus", "--dynamism", "80", "--speed", "0.9", "--seed", "5"],
}
SWEEP = ["--modes", "ekf,gated,ela,consensus", "--dynamism", "20,80", "--speed", "0.3,0.9", "--runs", "2",
         "--seed-base", "1", "--no-plots"]
MRCLAM = ["--report", "--modes", "ekf,ela,consensus", "--start", "0", "--duration", "120", "--no-plots"]
VOLATILE = ("timing", "elaslam_version", "command_line", "source")
MRCLAM_FILE = "mrclam_slice.report.json"
NO_DATA = (f"golden: SKIPPED {MRCLAM_FILE} (the MRCLAM slice): no {DATASET}. "
           "tools/get_mrclam.sh fetches it (or copies $ELASLAM_MRCLAM_SRC); tools/run_tests.sh runs it when it can")


def run(cmd, **kw):
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, **kw)
    if r.returncode != 0:
        sys.exit(f"golden: {' '.join(cmd)} failed ({r.returncode}):\n{r.stdout[-3000:]}")
    return r.stdout


def normalise(j):
    """metrics.json without what varies from run to run (or report.json: a list of them)."""
    if isinstance(j, list):
        return [normalise(x) for x in j]
    j = {k: v for k, v in j.items() if k not in VOLATILE}
    if isinstance(j.get("baseline"), dict):
        j["baseline"] = {k: v for k, v in j["baseline"].items() if k not in VOLATILE}
    if isinstance(j.get("dataset"), dict):
        j["dataset"] = {k: v for k, v in j["dataset"].items() if k != "dir"}
    return j


def produce(build, out, part="all"):
    """The in-process outputs of the reference (`part`: simulated, mrclam or all), into
    `out`, under the reference's names. The MRCLAM slice needs the data: without it,
    said (NO_DATA) and left out."""
    binp = os.path.join(build, "bin")
    files = {}
    if part in ("simulated", "all"):
        run([os.path.join(binp, "sweep"), "--config", CONFIG, *SWEEP, "--out", os.path.join(out, "sweep")])
        files["sweep_runs.csv"] = open(os.path.join(out, "sweep", "runs.csv")).read()
        for name, args in SCENARIOS.items():
            d = os.path.join(out, name)
            run([os.path.join(binp, "run_scenario"), "--config", CONFIG, *args, "--out", d])
            files[f"scenario_{name}.metrics.json"] = normalise(json.load(open(os.path.join(d, "metrics.json"))))
            files[f"scenario_{name}.frames.csv"] = open(os.path.join(d, "frames.csv")).read()
    if part in ("mrclam", "all"):
        if os.path.isdir(DATASET):
            d = os.path.join(out, "mrclam")
            run([os.path.join(binp, "run_dataset"), "--dataset", DATASET, *MRCLAM, "--out", d])
            files[MRCLAM_FILE] = normalise(json.load(open(os.path.join(d, "report.json"))))
        else:
            print(NO_DATA)
    return files


def json_diff(a, b, path="", out=None):
    out = [] if out is None else out
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if k not in a or k not in b:
                out.append(f"{path}.{k}: {'missing now' if k not in a else 'new'}")
            else:
                json_diff(a[k], b[k], f"{path}.{k}", out)
    elif isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        for i, (x, y) in enumerate(zip(a, b)):
            json_diff(x, y, f"{path}[{i}]", out)
    elif a != b:
        out.append(f"{path}: now {a!r}, reference {b!r}")
    return out


def text_diff(now, ref, limit=8):
    a, b = now.splitlines(), ref.splitlines()
    out = [f"line {i + 1}:\n    now {x}\n    ref {y}" for i, (x, y) in enumerate(zip(a, b)) if x != y]
    if len(a) != len(b):
        out.append(f"{len(a)} lines now, {len(b)} in the reference")
    return out[:limit] + ([f"... {len(out) - limit} more"] if len(out) > limit else [])


def cmd_check(args):
    if args.part == "mrclam" and not os.path.isdir(DATASET):
        print(NO_DATA)
        return 77
    with tempfile.TemporaryDirectory() as tmp:
        files = produce(args.build, tmp, args.part)
    failed = 0
    for name, now in files.items():
        path = os.path.join(REF, name)
        if not os.path.exists(path):
            print(f"golden: {name}: no reference (golden.py update)")
            failed += 1
            continue
        if name.endswith(".json"):
            diffs = json_diff(now, json.load(open(path)))
        else:
            diffs = text_diff(now, open(path).read())
        print(f"golden: {name}: {'identical' if not diffs else f'{len(diffs)} differences'}")
        for d in diffs[:20]:
            print("   ", d)
        failed += bool(diffs)
    if failed:
        print("golden: results changed. If that is meant, run tests/golden/golden.py update --build BUILD "
              "and commit the new reference with the reason.")
    return 1 if failed else 0


def cmd_update(args):
    with tempfile.TemporaryDirectory() as tmp:
        files = produce(args.build, tmp)
    os.makedirs(REF, exist_ok=True)
    for name, now in files.items():
        with open(os.path.join(REF, name), "w") as f:
            if name.endswith(".json"):
                json.dump(now, f, indent=1, sort_keys=True)
                f.write("\n")
            else:
                f.write(now)
        print(f"golden: wrote {os.path.relpath(os.path.join(REF, name), ROOT)}")
    return 0


def cmd_live(args):
    if os.geteuid() != 0 or shutil.which("ip") is None:
        print("golden: live: skipped (needs root for network namespaces)")
        return 77
    failed = []
    with tempfile.TemporaryDirectory() as tmp:
        for port, (name, scenario) in zip((7706, 7707), SCENARIOS.items()):
            out = os.path.join(tmp, name)
            run([os.path.join(ROOT, "tools", "netns_run.sh"), "--port", str(port), "--",
                 os.path.join(ROOT, "tools", "run_team.sh"), "--inside", "--no-progress", "--no-baseline",
                 "--build-dir", args.build, "--config", CONFIG, "--out", out, *scenario])
            live = json.load(open(os.path.join(out, "metrics.json")))
            ref = json.load(open(os.path.join(REF, f"scenario_{name}.metrics.json")))
            rows = lambda text: {int(r["frame"]): r for r in csv.DictReader(text.splitlines())}
            live_rows = rows(open(os.path.join(out, "frames.csv")).read())
            ref_rows = rows(open(os.path.join(REF, f"scenario_{name}.frames.csv")).read())
            n = 0
            for k, row in live_rows.items():
                for key, value in row.items():
                    if key.startswith("robot") and key.endswith("_error") and not math.isnan(float(value)):
                        n += 1
                        if abs(float(value) - float(ref_rows[k][key])) > LIVE_TOL:
                            failed.append(f"{name} frame {k} {key}: live {value}, reference {ref_rows[k][key]}")
            if live["frames_dropped"] != 0:
                failed.append(f"{name}: {live['frames_dropped']} frames dropped")
            whole = live["poses_missing_from_log"] == 0
            if whole:
                for a, b in zip(live["robots"], ref["robots"]):
                    if abs(a["error_mean"] - b["error_mean"]) > LIVE_TOL:
                        failed.append(f"{name} robot {a['id']} error_mean: live {a['error_mean']}, ref {b['error_mean']}")
                a, b = live["landmark_error"]["mean_euclidean"], ref["landmark_error"]["mean_euclidean"]
                if abs(a - b) > LIVE_TOL:
                    failed.append(f"{name} landmark error: live {a}, reference {b}")
            for key in ("precision", "recall"):
                if abs(live["detection"][key] - ref["detection"][key]) > LIVE_TOL:
                    failed.append(f"{name} {key}: live {live['detection'][key]}, reference {ref['detection'][key]}")
            print(f"golden: live {name}: {n} pose errors compared"
                  f"{', whole-run figures too' if whole else ' (the recorder lost a POSE: frame by frame only)'}")
    for f in failed[:30]:
        print("   ", f)
    return 1 if failed else 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("command", choices=["check", "live", "update"])
    ap.add_argument("--build", required=True, help="the build directory (its bin/)")
    ap.add_argument("--part", choices=["simulated", "mrclam", "all"], default="all",
                    help="check: the simulated runs, the MRCLAM slice or both (default)")
    args = ap.parse_args()
    args.build = os.path.abspath(args.build)
    return {"check": cmd_check, "live": cmd_live, "update": cmd_update}[args.command](args)


if __name__ == "__main__":
    sys.exit(main())

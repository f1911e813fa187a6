#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Plot a scenario like the paper's Fig. 4: landmarks (moving ones with their
paths over the run), the robots' paths, each robot's field of view at its start
pose, on a 2 m grid.

    tools/plot_scenario.py [--config config/paper.yaml] [--dynamism 50] [--speed 0.5] \
        [--seed 1] [--out scenario.png]

It runs scenario_dump (build/bin/scenario_dump; the simulator library itself, so
the plot shows exactly what the simulator publishes) and reads its CSV. Without
--config, scenario_dump's default config (config/paper.yaml in a build tree).
Exit status 1 on a failure (scenario_dump not found or failing), 2 on a bad
command line or a missing module: in a source tree the script runs itself in the
project's .venv (tools/setup.sh); an installed copy needs Debian's
python3-matplotlib.
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
import csv  # noqa: E402
import math  # noqa: E402
import shutil  # noqa: E402
import subprocess  # noqa: E402
import tempfile  # noqa: E402

# matplotlib: imported by load_modules() once the command line is parsed (so --help
# and usage errors need no third-party module).
plt = None


def load_modules():
    global plt
    _need("matplotlib", "python3-matplotlib").use("Agg")
    plt = _need("matplotlib.pyplot", "python3-matplotlib")


DUMP_NAMES = ["scenario_dump", "elaslam-scenario-dump", "elaslam-scenario_dump"]
ROBOT_COLOURS = ["tab:blue", "tab:green", "tab:purple", "tab:orange", "tab:brown", "tab:pink", "tab:olive", "tab:cyan"]


def find_dump():
    """scenario_dump: $ELASLAM_BUILD_DIR/bin, next to an installed or build-tree copy
    of this script (<prefix>/share/elaslam/tools -> <prefix>/bin), the source tree's
    build/bin, then PATH. Returns (path or None, places looked at)."""
    bins = []
    if os.environ.get("ELASLAM_BUILD_DIR"):
        bins.append(os.path.join(os.environ["ELASLAM_BUILD_DIR"], "bin"))
    for here in dict.fromkeys([os.path.dirname(os.path.abspath(__file__)), os.path.dirname(os.path.realpath(__file__))]):
        if here.endswith(os.path.join("share", "elaslam", "tools")):
            bins.append(os.path.normpath(os.path.join(here, "..", "..", "..", "bin")))
        elif os.path.basename(here) == "bin":
            bins.append(here)
    bins.append(os.path.join(os.path.dirname(os.path.dirname(os.path.realpath(__file__))), "build", "bin"))
    looked = []
    for b in dict.fromkeys(bins):
        for name in DUMP_NAMES:
            exe = os.path.join(b, name)
            looked.append(exe)
            if os.path.isfile(exe) and os.access(exe, os.X_OK):
                return exe, looked
    for name in DUMP_NAMES:
        exe = shutil.which(name)
        if exe:
            return exe, looked
    return None, looked + [f"{n} on PATH" for n in DUMP_NAMES]


def run_dump(args, csv_path):
    if args.dump:
        exe = args.dump
        if not (os.path.isfile(exe) and os.access(exe, os.X_OK)):
            sys.exit(f"plot_scenario: --dump {exe}: no such executable")
    else:
        exe, looked = find_dump()
        if exe is None:
            sys.exit("plot_scenario: scenario_dump not found (build first: cmake --build build); looked at:\n  "
                     + "\n  ".join(looked))
    cmd = [exe, "--out", csv_path]
    if args.config:
        cmd += ["--config", args.config]
    for flag, value in (("--dynamism", args.dynamism), ("--speed", args.speed), ("--seed", args.seed)):
        if value is not None:
            cmd += [flag, str(value)]
    result = subprocess.run(cmd, stderr=subprocess.PIPE, text=True)
    if result.returncode != 0:
        sys.exit(f"plot_scenario: scenario_dump failed ({result.returncode}):\n{result.stderr}")


def read_dump(csv_path):
    meta, robots, landmarks = {}, {}, {}
    with open(csv_path) as f:
        lines = []
        for line in f:
            if line.startswith("#"):
                key, _, value = line[1:].strip().partition("=")
                try:
                    meta[key] = float(value)
                except ValueError:  # movers=oscillating,constant_velocity: text
                    meta[key] = value
            else:
                lines.append(line)
    for row in csv.DictReader(lines):
        x, y = float(row["x"]), float(row["y"])
        if row["kind"] == "robot":
            robots.setdefault(int(row["id"]), []).append((x, y, float(row["theta"])))
        elif row["kind"] == "landmark":
            lm = landmarks.setdefault(int(row["id"]), {"xy": [], "moving": row["moving"] == "1",
                                                       "motion": row.get("motion") or "oscillating"})
            lm["xy"].append((x, y))
    return meta, robots, landmarks


# A moving landmark's colour by its mover kind (scenario.movers).
MOTION_COLOURS = {"oscillating": "tab:red", "constant_velocity": "tab:purple", "stop_and_go": "tab:orange"}


def plot(meta, robots, landmarks, out):
    fig, ax = plt.subplots(figsize=(7.5, 7.5))
    for lm in landmarks.values():
        x0, y0 = lm["xy"][0]
        if lm["moving"]:
            c = MOTION_COLOURS.get(lm["motion"], "tab:red")
            xs, ys = zip(*lm["xy"])
            ax.plot(xs, ys, "-", color=c, lw=1.0, alpha=0.7)
            ax.plot(x0, y0, "o", mfc="none", mec=c, ms=6)
        else:
            ax.plot(x0, y0, "k.", ms=7)
    half_d = 0.5 * meta["fov_diameter_m"]
    for i, (rid, poses) in enumerate(sorted(robots.items())):
        c = ROBOT_COLOURS[i % len(ROBOT_COLOURS)]
        xs, ys, _ = zip(*poses)
        ax.plot(xs, ys, "-", color=c, lw=2, label=f"robot {rid}")
        x0, y0, th0 = poses[0]
        ax.add_patch(plt.Circle((x0, y0), half_d, fill=False, ls="--", color=c, lw=1))
        ax.arrow(x0, y0, 0.8 * math.cos(th0), 0.8 * math.sin(th0), head_width=0.3, color=c)
    ax.plot([], [], "k.", label="static landmark")
    motions = sorted({lm["motion"] for lm in landmarks.values() if lm["moving"]})
    if motions == ["oscillating"] or not motions:
        ax.plot([], [], "o-", mfc="none", color="tab:red", label="moving landmark (path)")
    for m in ([] if motions == ["oscillating"] else motions):
        ax.plot([], [], "o-", mfc="none", color=MOTION_COLOURS.get(m, "tab:red"), label=f"{m} (path)")
    ax.plot([], [], "--", color="gray", label=f"field of view at start (D = {meta['fov_diameter_m']:g} m)")
    ax.set_xlim(meta["x_min_m"] - 0.5, meta["x_max_m"] + 0.5)
    ax.set_ylim(meta["y_min_m"] - 0.5, meta["y_max_m"] + 0.5)
    ax.set_xticks(range(int(math.floor(meta["x_min_m"])), int(math.ceil(meta["x_max_m"])) + 1, 2))
    ax.set_yticks(range(int(math.floor(meta["y_min_m"])), int(math.ceil(meta["y_max_m"])) + 1, 2))
    ax.grid(True, lw=0.5, alpha=0.5)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    n_moving = sum(1 for lm in landmarks.values() if lm["moving"])
    ax.set_title(f"{len(landmarks)} landmarks, {n_moving} moving ({meta['dynamism_percent']:g} %) at "
                 f"{meta['landmark_speed_mps']:g} m/s; {int(meta['frames'])} frames at {meta['rate_hz']:g} Hz, "
                 f"seed {int(meta['seed'])}", fontsize=9)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.08), ncol=3, fontsize=7)
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    fig.savefig(out, dpi=120, bbox_inches="tight")
    plt.close(fig)


def main():
    p = argparse.ArgumentParser(prog="plot_scenario.py", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    add_version(p)
    p.add_argument("--config", help="YAML config with a scenario: section (default: scenario_dump's: $ELASLAM_CONFIG, "
                   "else /etc/elaslam/elaslam.yaml, else the installed paper.yaml)")
    p.add_argument("--dynamism", type=float, help="override scenario.dynamism_percent [%%]")
    p.add_argument("--speed", type=float, help="override scenario.landmark_speed_mps [m/s]")
    p.add_argument("--seed", type=int, help="override scenario.seed")
    p.add_argument("--dump", help="path of scenario_dump (default: $ELASLAM_BUILD_DIR/bin, the build's bin/, PATH)")
    p.add_argument("--csv", help="keep the dumped CSV here")
    p.add_argument("--out", default="scenario.png", help="output PNG (default: scenario.png)")
    args = _parse(p)
    load_modules()
    with tempfile.TemporaryDirectory() as tmp:
        csv_path = args.csv or os.path.join(tmp, "scenario.csv")
        run_dump(args, csv_path)
        meta, robots, landmarks = read_dump(csv_path)
    plot(meta, robots, landmarks, args.out)
    print(f"plot_scenario: wrote {args.out}")


if __name__ == "__main__":
    main()

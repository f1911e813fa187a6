#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Plot a run on real data (run_dataset's output folder): one panel per robot with
its true (Vicon) and estimated paths, the true landmark positions and the team's
global map (estimates with 3-sigma ellipses; landmarks flagged as moving marked).

    tools/plot_dataset.py RUN_DIR [--out FILE.png]

RUN_DIR holds map.csv and trajectories/robot<R>.tum, robot<R>_gt.tum (written by
build/bin/run_dataset or run_scenario). Default output: RUN_DIR/paths.png.
Exit status 1 when RUN_DIR lacks them, 2 on a bad command line or a missing
module: in a source tree the script runs itself in the project's .venv
(tools/setup.sh); an installed copy needs Debian's python3-matplotlib.
"""
# ---- start-up: standard library only, before any third-party import (tools/elaslam_tool.py)
import os
import sys

_here = os.path.dirname(os.path.realpath(__file__))
sys.path[:0] = [_here, os.path.join(_here, "..", "share", "elaslam", "tools")]
from elaslam_tool import doc_parser, need as _need, parse_args as _parse, run_in_venv  # noqa: E402

if __name__ == "__main__":
    run_in_venv()
# ----------------------------------------------------------------------------------
import csv  # noqa: E402
import math  # noqa: E402

# matplotlib: imported by load_modules() once the command line is parsed (so --help
# and usage errors need no third-party module).
plt = Ellipse = None


def load_modules():
    global plt, Ellipse
    _need("matplotlib", "python3-matplotlib").use("Agg")
    plt = _need("matplotlib.pyplot", "python3-matplotlib")
    Ellipse = _need("matplotlib.patches", "python3-matplotlib").Ellipse


def read_tum(path):
    xs, ys = [], []
    with open(path) as f:
        for n, line in enumerate(f, 1):
            if not line.strip() or line.startswith("#"):
                continue
            cols = line.split()
            if len(cols) != 8:
                sys.exit(f"plot_dataset: {path}:{n}: expected 8 columns (t x y z qx qy qz qw), got {len(cols)}")
            xs.append(float(cols[1]))
            ys.append(float(cols[2]))
    return xs, ys


def read_map(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    need = {"id", "true_x", "true_y", "truly_moving", "status", "est_x", "est_y", "cov_xx", "cov_xy", "cov_yy"}
    if rows and not need.issubset(rows[0].keys()):
        sys.exit(f"plot_dataset: {path}: missing columns {sorted(need - set(rows[0].keys()))}")
    return rows


def ellipse(cxx, cxy, cyy, x, y, k=3.0, **kw):
    # Axes of the covariance: eigenvalues of the 2x2 matrix.
    tr, det = cxx + cyy, cxx * cyy - cxy * cxy
    disc = math.sqrt(max(tr * tr / 4 - det, 0.0))
    l1, l2 = tr / 2 + disc, max(tr / 2 - disc, 0.0)
    angle = math.degrees(math.atan2(l1 - cxx, cxy)) if abs(cxy) > 1e-15 else (0.0 if cxx >= cyy else 90.0)
    return Ellipse((x, y), 2 * k * math.sqrt(l1), 2 * k * math.sqrt(l2), angle=angle, fill=False, **kw)


def main():
    ap = doc_parser("plot_dataset.py", __doc__)
    ap.add_argument("run_dir", help="a run_dataset (or run_scenario) output folder")
    ap.add_argument("--out", help="the PNG to write (default: RUN_DIR/paths.png)")
    a = _parse(ap)
    load_modules()
    traj = os.path.join(a.run_dir, "trajectories")
    map_csv = os.path.join(a.run_dir, "map.csv")
    for p in (traj, map_csv):
        if not os.path.exists(p):
            sys.exit(f"plot_dataset: {p} not found (is {a.run_dir} a run_dataset output folder?)")
    robots = sorted(int(f[5:-4]) for f in os.listdir(traj) if f.startswith("robot") and f.endswith(".tum")
                    and not f.endswith("_gt.tum"))
    if not robots:
        sys.exit(f"plot_dataset: no trajectories/robot<R>.tum in {a.run_dir}")
    rows = read_map(map_csv)
    cols = min(len(robots), 3)
    nrows = math.ceil(len(robots) / cols)
    fig, axes = plt.subplots(nrows, cols, figsize=(3.8 * cols, 5.4 * nrows), squeeze=False)
    for i, r in enumerate(robots):
        ax = axes[i // cols][i % cols]
        tx, ty = read_tum(os.path.join(traj, f"robot{r}_gt.tum"))
        ex, ey = read_tum(os.path.join(traj, f"robot{r}.tum"))
        ax.plot(tx, ty, color="0.55", lw=2.2, alpha=0.6, label="true path (Vicon)")
        ax.plot(ex, ey, color="tab:blue", lw=0.9, label="estimated path")
        ax.plot(tx[:1], ty[:1], "k^", ms=7, label="start")
        for row in rows:
            x, y = float(row["true_x"]), float(row["true_y"])
            if row["truly_moving"] == "1":
                continue  # another robot: its path is in its own panel
            ax.plot(x, y, "ko", ms=4)
            if row["status"] == "static" and row["est_x"]:
                px, py = float(row["est_x"]), float(row["est_y"])
                ax.plot(px, py, "+", color="tab:red", ms=7)
                ax.plot([x, px], [y, py], color="tab:red", lw=0.6)
                ax.add_patch(ellipse(float(row["cov_xx"]), float(row["cov_xy"]), float(row["cov_yy"]), px, py,
                                     color="tab:red", lw=0.7))
            elif row["status"] == "moving":
                ax.plot(x, y, "x", color="m", ms=8)
        ax.set_title(f"robot {r}")
        ax.set_aspect("equal")
        ax.grid(alpha=0.3)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
    for j in range(len(robots), nrows * cols):
        axes[j // cols][j % cols].axis("off")
    h, l = axes[0][0].get_legend_handles_labels()
    h += [plt.Line2D([], [], color="k", marker="o", ls=""), plt.Line2D([], [], color="tab:red", marker="+", ls=""),
          plt.Line2D([], [], color="m", marker="x", ls="")]
    l += ["true landmark", "global map estimate (3-sigma)", "flagged moving"]
    fig.legend(h, l, loc="lower center", ncol=3, fontsize=9)
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    out = a.out or os.path.join(a.run_dir, "paths.png")
    fig.savefig(out, dpi=130)
    print(out)


if __name__ == "__main__":
    main()

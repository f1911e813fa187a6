#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Plot the results of build/bin/sweep like the paper's Figs 4-8.

    tools/plot_sweep.py DIR [--out DIR2]

DIR is a sweep output directory (runs.csv, frames.csv, maps/<mode>/ as written by
team/src/sweep_tables.cpp and eval/src/report.cpp); the PNGs go to DIR2 (default DIR):

  fig5_landmark_error.png   mean landmark error (eq 18) vs dynamism, a panel per speed
  fig6_robot_error.png      robot error (mean over robots) vs dynamism, a panel per speed
  fig6b_error_vs_speed.png  landmark and robot error vs speed, a panel per dynamism
  fig7_error_over_time.png  errors over frames at the lowest / highest dynamism, middle speed
  fig8_uncertainty.png      final uncertainty mean(diag P) vs dynamism, a panel per speed
  fig4_map.png              the final global map of each maps/<mode>/ run
  detection.png             moving-landmark precision and recall vs dynamism

Error bars are the sample standard deviation over runs. Exit status 1 (with the
missing file or column named) when runs.csv / frames.csv are absent or malformed;
a figure whose data is absent (e.g. no maps/) is skipped with a note. Exit status 2
on a bad command line or a missing module: in a source tree the script runs itself
in the project's .venv (tools/setup.sh); an installed copy needs Debian's
python3-numpy and python3-matplotlib.
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
import re  # noqa: E402
import textwrap  # noqa: E402

# numpy and matplotlib: imported by load_modules() once the command line is parsed
# (so --help and usage errors need neither).
matplotlib = plt = np = Ellipse = None


def load_modules():
    global matplotlib, plt, np, Ellipse
    np = _need("numpy", "python3-numpy")
    matplotlib = _need("matplotlib", "python3-matplotlib")
    matplotlib.use("Agg")
    plt = _need("matplotlib.pyplot", "python3-matplotlib")
    _need("matplotlib.ticker", "python3-matplotlib")
    _need("matplotlib.lines", "python3-matplotlib")
    Ellipse = _need("matplotlib.patches", "python3-matplotlib").Ellipse
    plt.rcParams.update({"font.size": 10, "axes.titlesize": 11, "axes.labelsize": 10, "legend.fontsize": 9})


DPI = 150
# One colour (and marker / line style) per mode, the same in every figure.
KNOWN_MODES = ["ekf", "gated", "ela", "consensus"]
MODE_STYLE = {
    "ekf": dict(color="tab:red", marker="s", ls="--"),
    "gated": dict(color="tab:orange", marker="^", ls="-."),
    "ela": dict(color="tab:blue", marker="o", ls="-"),
    "consensus": dict(color="tab:green", marker="D", ls=":"),
}
EXTRA_COLOURS = ["tab:purple", "tab:brown", "tab:pink", "tab:olive", "tab:cyan", "tab:gray"]
FLAG_COLOUR = "magenta"  # landmarks flagged moving in fig4 (no mode uses it)
ROBOT_COLOURS = ["tab:blue", "tab:green", "tab:purple", "tab:orange", "tab:brown", "tab:pink"]

RUNS_FIXED = ["mode", "dynamism", "speed", "run", "seed", "landmark_error", "landmark_rms"]
RUNS_TAIL = ["precision", "recall", "static_landmark_error", "frames_to_detect", "flagged"]
FRAMES_COLS = ["mode", "dynamism", "speed", "frame", "landmark_error", "robot_error_mean"]
MAP_COLS = ["id", "true_x", "true_y", "truly_moving", "status", "est_x", "est_y", "cov_xx", "cov_xy", "cov_yy"]

class InputError(Exception):
    pass


def fnum(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return math.nan


def read_csv(path, required, what):
    if not os.path.isfile(path):
        raise InputError(f"missing file {path} ({what})")
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        header = reader.fieldnames or []
        missing = [c for c in required if c not in header]
        if missing:
            raise InputError(f"{path}: missing column(s) {', '.join(missing)} (header: {','.join(header) or 'empty'})")
        rows = list(reader)
    if not rows:
        raise InputError(f"{path}: no data rows")
    return header, rows


def mode_order(modes):
    modes = list(dict.fromkeys(modes))
    known = [m for m in KNOWN_MODES if m in modes]
    return known + [m for m in modes if m not in KNOWN_MODES]


def style(mode, all_modes):
    if mode in MODE_STYLE:
        return MODE_STYLE[mode]
    extras = [m for m in all_modes if m not in MODE_STYLE]
    i = extras.index(mode) if mode in extras else 0
    return dict(color=EXTRA_COLOURS[i % len(EXTRA_COLOURS)], marker="v", ls="-")


def fmt_num(v):
    return f"{v:g}"


def mean_sd(values):
    v = np.asarray([x for x in values if not math.isnan(x)], dtype=float)
    if v.size == 0:
        return math.nan, math.nan
    return float(v.mean()), float(v.std(ddof=1)) if v.size > 1 else 0.0


class Sweep:
    def __init__(self, d):
        self.dir = d
        header, rows = read_csv(os.path.join(d, "runs.csv"), RUNS_FIXED + RUNS_TAIL, "written by sweep")
        self.robots = sorted({int(m.group(1)) for c in header for m in [re.fullmatch(r"robot(\d+)_error", c)] if m})
        if not self.robots:
            raise InputError(f"{d}/runs.csv: no robot<R>_error column")
        need = [f"robot{r}_{k}" for r in self.robots for k in ("error", "rms", "uncertainty")]
        missing = [c for c in need if c not in header]
        if missing:
            raise InputError(f"{d}/runs.csv: missing column(s) {', '.join(missing)}")
        self.runs = []
        for i, row in enumerate(rows, start=2):
            rec = {"mode": row["mode"], "dynamism": fnum(row["dynamism"]), "speed": fnum(row["speed"])}
            if not rec["mode"] or math.isnan(rec["dynamism"]) or math.isnan(rec["speed"]):
                raise InputError(f"{d}/runs.csv line {i}: mode/dynamism/speed not set")
            for c in ("landmark_error", "precision", "recall", "flagged"):
                rec[c] = fnum(row[c])
            # The sweep writes precision 1 for a run that flags nothing; plot it as undefined.
            if rec["flagged"] == 0:
                rec["precision"] = math.nan
            rec["robot_error"] = float(np.nanmean([fnum(row[f"robot{r}_error"]) for r in self.robots])) \
                if any(not math.isnan(fnum(row[f"robot{r}_error"])) for r in self.robots) else math.nan
            unc = [fnum(row[f"robot{r}_uncertainty"]) for r in self.robots]
            rec["uncertainty"] = float(np.nanmean(unc)) if any(not math.isnan(u) for u in unc) else math.nan
            self.runs.append(rec)
        self.modes = mode_order(r["mode"] for r in self.runs)
        self.dyn = sorted({r["dynamism"] for r in self.runs})
        self.speeds = sorted({r["speed"] for r in self.runs})
        self.n_runs = max(sum(1 for r in self.runs if (r["mode"], r["dynamism"], r["speed"]) == k)
                          for k in {(r["mode"], r["dynamism"], r["speed"]) for r in self.runs})

        _, frows = read_csv(os.path.join(d, "frames.csv"), FRAMES_COLS, "written by sweep")
        self.frames = {}
        for row in frows:
            key = (row["mode"], fnum(row["dynamism"]), fnum(row["speed"]))
            self.frames.setdefault(key, []).append(
                (fnum(row["frame"]), fnum(row["landmark_error"]), fnum(row["robot_error_mean"])))

    def cell(self, metric, mode, dyn=None, speed=None):
        vals = [r[metric] for r in self.runs if r["mode"] == mode and (dyn is None or r["dynamism"] == dyn)
                and (speed is None or r["speed"] == speed)]
        return mean_sd(vals)

    def colour(self, mode):
        return style(mode, self.modes)


def grid_shape(n, max_cols=3):
    cols = min(n, max_cols)
    return int(math.ceil(n / cols)), cols


def hide_unused(axes, used):
    for ax in axes[used:]:
        ax.set_visible(False)


def offsets(sweep, xs):
    """Small x offsets so that the error bars of the modes do not overlap."""
    span = (max(xs) - min(xs)) if len(xs) > 1 else 1.0
    step = 0.015 * span
    n = len(sweep.modes)
    return {m: (i - (n - 1) / 2) * step for i, m in enumerate(sweep.modes)}


def errorbar_lines(ax, sweep, metric, xs, key_of_x, fixed, clip=None):
    """Mean +- sample std per mode; returns the modes without any value."""
    off = offsets(sweep, xs)
    empty = []
    for mode in sweep.modes:
        st = sweep.colour(mode)
        ms = [sweep.cell(metric, mode, **{**fixed, **key_of_x(x)}) for x in xs]
        y = np.array([m for m, _ in ms])
        e = np.array([s for _, s in ms])
        if np.all(np.isnan(y)):
            empty.append(mode)
            continue
        yerr = e
        if clip is not None:  # keep the bars inside the metric's range
            yerr = np.vstack([np.minimum(e, y - clip[0]), np.minimum(e, clip[1] - y)])
        ax.errorbar(np.asarray(xs) + off[mode], y, yerr=yerr, label=mode, capsize=3, lw=1.6, ms=5, **st)
    return empty


def legend_below(fig, axes, ncol=None):
    """One legend for the figure: in an unused (hidden) panel if there is one, else
    below the panels. Returns True when it went below (the caller keeps room)."""
    handles, labels = [], []
    for ax in np.ravel(axes):
        for h, l in zip(*ax.get_legend_handles_labels()):
            if l not in labels:
                handles.append(h)
                labels.append(l)
    if not handles:
        return False
    order = mode_order(labels)  # the same mode order in every legend
    handles = [handles[labels.index(m)] for m in order]
    labels = order
    spare = [ax for ax in np.ravel(axes) if not ax.get_visible()]
    if spare:
        ax = spare[-1]
        ax.set_visible(True)
        ax.axis("off")
        ax.legend(handles, labels, loc="center", title="mode", fontsize=11, title_fontsize=11, frameon=True)
        return False
    fig.legend(handles, labels, loc="lower center", ncol=ncol or len(labels), frameon=False, fontsize=10,
               bbox_to_anchor=(0.5, 0.0))
    return True


def suptitle(fig, text, size=11.5):
    """A figure title wrapped to the figure's width."""
    width = max(30, int(fig.get_figwidth() * 72 / (0.55 * size)))
    fig.suptitle("\n".join(textwrap.wrap(text, width)), fontsize=size)


def finish(fig, path, written, bottom=0.1, top=1.0, tight=True):
    if tight:
        fig.tight_layout(rect=(0, bottom, 1, top))
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    written.append(path)


def runs_note(sweep):
    if sweep.n_runs == 1:
        return "1 run, no error bars"
    return f"mean ± sample std over {sweep.n_runs} runs"


def per_speed_figure(sweep, metric, ylabel, title, path, written, log=False):
    rows, cols = grid_shape(len(sweep.speeds))
    fig, axes = plt.subplots(rows, cols, figsize=(4.3 * cols, 3.4 * rows + 0.7), sharey=True, squeeze=False)
    axes = axes.ravel()
    for ax, speed in zip(axes, sweep.speeds):
        errorbar_lines(ax, sweep, metric, sweep.dyn, lambda x: {"dyn": x}, {"speed": speed})
        ax.set_title(f"landmark speed {fmt_num(speed)} m/s")
        ax.set_xlabel("dynamism [% moving landmarks]")
        ax.set_xticks(sweep.dyn)
        ax.grid(alpha=0.3)
        if log:
            ax.set_yscale("log")
    for r in range(rows):
        axes[r * cols].set_ylabel(ylabel)
    hide_unused(axes, len(sweep.speeds))
    if not log:
        axes[0].set_ylim(bottom=0)
    suptitle(fig, f"{title} ({runs_note(sweep)})")
    below = legend_below(fig, axes)
    finish(fig, path, written, bottom=0.45 / (3.4 * rows + 0.7) if below else 0.0)


def fig5(sweep, out, written):
    per_speed_figure(sweep, "landmark_error", "mean landmark error (eq 18) [m]",
                     "Global-map landmark error vs dynamism", os.path.join(out, "fig5_landmark_error.png"), written)


def fig6(sweep, out, written):
    per_speed_figure(sweep, "robot_error", f"robot position error [m]\n(mean over {len(sweep.robots)} robots)",
                     "Robot position error vs dynamism", os.path.join(out, "fig6_robot_error.png"), written)


def fig6b(sweep, out, written):
    n = len(sweep.dyn)
    cols = min(n, 3)
    blocks = int(math.ceil(n / cols))
    fig, axes = plt.subplots(2 * blocks, cols, figsize=(4.0 * cols + 0.6, 5.8 * blocks + 0.9), squeeze=False)
    metrics = (("landmark_error", "landmark error [m]"), ("robot_error", "robot error [m]"))
    for i, dyn in enumerate(sweep.dyn):
        b, c = divmod(i, cols)
        for k, (metric, ylabel) in enumerate(metrics):
            ax = axes[2 * b + k, c]
            errorbar_lines(ax, sweep, metric, sweep.speeds, lambda x: {"speed": x}, {"dyn": dyn})
            ax.set_title(f"dynamism {fmt_num(dyn)} %: {'landmarks' if k == 0 else 'robots'}")
            ax.set_xticks(sweep.speeds)
            ax.set_xticklabels([fmt_num(s) for s in sweep.speeds])
            ax.grid(alpha=0.3)
            ax.set_ylim(bottom=0)
            if c == 0:
                ax.set_ylabel(ylabel)
            ax.set_xlabel("landmark speed [m/s]")
    for i in range(n, blocks * cols):
        b, c = divmod(i, cols)
        axes[2 * b, c].set_visible(False)
        axes[2 * b + 1, c].set_visible(False)
    # Same y range within each metric row, so the panels compare directly.
    for k in range(2):
        row_axes = [axes[2 * b + k, c] for b in range(blocks) for c in range(cols) if b * cols + c < n]
        top = max(ax.get_ylim()[1] for ax in row_axes)
        for ax in row_axes:
            ax.set_ylim(0, top)
    suptitle(fig, f"Errors vs landmark speed at each dynamism ({runs_note(sweep)})")
    below = legend_below(fig, axes)
    finish(fig, os.path.join(out, "fig6b_error_vs_speed.png"), written, bottom=0.45 / (5.8 * blocks + 0.9) if below else 0.0)


def fig7(sweep, out, written):
    if not sweep.frames:
        print("plot_sweep: note: frames.csv has no rows, fig7 skipped")
        return
    speeds = sorted({k[2] for k in sweep.frames})
    dyns = sorted({k[1] for k in sweep.frames})
    speed = speeds[len(speeds) // 2]
    cols_dyn = [dyns[0]] if len(dyns) == 1 else [dyns[0], dyns[-1]]
    fig, axes = plt.subplots(2, len(cols_dyn), figsize=(5.2 * len(cols_dyn), 6.6), squeeze=False, sharex=True)
    for c, dyn in enumerate(cols_dyn):
        for mode in sweep.modes:
            pts = sorted(sweep.frames.get((mode, dyn, speed), []))
            if not pts:
                continue
            f, lm, rb = (np.array(v) for v in zip(*pts))
            st = sweep.colour(mode)
            axes[0, c].plot(f, lm, color=st["color"], ls=st["ls"], lw=1.6, label=mode)
            axes[1, c].plot(f, rb, color=st["color"], ls=st["ls"], lw=1.6, label=mode)
        axes[0, c].set_title(f"dynamism {fmt_num(dyn)} %, speed {fmt_num(speed)} m/s")
        axes[1, c].set_xlabel("frame")
        for r in range(2):
            axes[r, c].grid(alpha=0.3)
            axes[r, c].set_ylim(bottom=0)
    axes[0, 0].set_ylabel("landmark error (eq 17) [m]")
    axes[1, 0].set_ylabel("robot error (mean over robots) [m]")
    for r in range(2):  # shared y range per row
        top = max(ax.get_ylim()[1] for ax in axes[r])
        for ax in axes[r]:
            ax.set_ylim(0, top)
    suptitle(fig, f"Errors over time (mean over {sweep.n_runs} run{'s' if sweep.n_runs != 1 else ''} per frame)")
    legend_below(fig, axes)
    finish(fig, os.path.join(out, "fig7_error_over_time.png"), written, bottom=0.45 / 6.6)


def fig8(sweep, out, written):
    vals = np.array([r["uncertainty"] for r in sweep.runs if r["uncertainty"] > 0])
    if vals.size == 0:
        print("plot_sweep: note: no positive uncertainty in runs.csv, fig8 skipped")
        return
    log = vals.max() / vals.min() > 20
    per_speed_figure(sweep, "uncertainty", "final uncertainty mean(diag P)\n[m², θ in rad²]",
                     "Final map uncertainty vs dynamism", os.path.join(out, "fig8_uncertainty.png"), written, log=log)


def detection(sweep, out, written):
    fig, axes = plt.subplots(1, 2, figsize=(9.5, 4.1), sharey=True)
    for ax, metric in zip(axes, ("precision", "recall")):
        empty = errorbar_lines(ax, sweep, metric, sweep.dyn, lambda x: {"dyn": x}, {}, clip=(0.0, 1.0))
        if empty:
            ax.text(0.02, 0.03, f"{', '.join(empty)}: nothing flagged (precision undefined)", transform=ax.transAxes,
                    fontsize=9, color="0.3")
        ax.set_title(f"moving-landmark {metric}")
        ax.set_xlabel("dynamism [% moving landmarks]")
        ax.set_xticks(sweep.dyn)
        ax.set_ylim(-0.05, 1.05)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("fraction [0-1]")
    suptitle(fig, "Detection of moving landmarks (mean ± sample std over all speeds and runs; "
                 "bars clipped to [0, 1])", size=10.5)
    legend_below(fig, axes)
    finish(fig, os.path.join(out, "detection.png"), written, bottom=0.1)


def read_tum(path):
    pts = []
    with open(path) as f:
        for line in f:
            s = line.split()
            if not s or s[0].startswith("#"):
                continue
            if len(s) < 8:
                raise InputError(f"{path}: expected 't x y z qx qy qz qw', got {line.strip()!r}")
            pts.append((float(s[1]), float(s[2])))
    return np.array(pts).reshape(-1, 2)


def read_map_dir(d):
    _, rows = read_csv(os.path.join(d, "map.csv"), MAP_COLS, "written by sweep (eval/src/report.cpp)")
    trajs = {}
    tdir = os.path.join(d, "trajectories")
    if os.path.isdir(tdir):
        for name in sorted(os.listdir(tdir)):
            m = re.fullmatch(r"robot(\d+)(_gt)?\.tum", name)
            if m:
                trajs.setdefault(int(m.group(1)), {})["gt" if m.group(2) else "est"] = read_tum(os.path.join(tdir, name))
    meta = {}
    mpath = os.path.join(d, "metrics.json")
    if os.path.isfile(mpath):
        import json
        try:
            with open(mpath) as f:
                meta = json.load(f)
        except ValueError:
            meta = {}
    return rows, trajs, meta


def ellipse(ax, x, y, cxx, cxy, cyy, k, **kw):
    cov = np.array([[cxx, cxy], [cxy, cyy]])
    if not np.all(np.isfinite(cov)):
        return
    w, v = np.linalg.eigh(cov)
    w = np.clip(w, 0, None)
    angle = math.degrees(math.atan2(v[1, 1], v[0, 1]))
    ax.add_patch(Ellipse((x, y), 2 * k * math.sqrt(w[1]), 2 * k * math.sqrt(w[0]), angle=angle, fill=False, **kw))


def fig4(sweep, out, written):
    mroot = os.path.join(sweep.dir, "maps")
    if not os.path.isdir(mroot):
        print(f"plot_sweep: note: no {mroot}/, fig4 skipped")
        return
    dirs = [m for m in mode_order(sorted(os.listdir(mroot))) if os.path.isdir(os.path.join(mroot, m))]
    if not dirs:
        print(f"plot_sweep: note: {mroot}/ has no mode folder, fig4 skipped")
        return
    data = [(m, *read_map_dir(os.path.join(mroot, m))) for m in dirs]
    n = len(data)
    cols = min(n, 2)
    rows = int(math.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(7.2 * cols, 7.0 * rows + 1.4), squeeze=False, layout="constrained")
    axes = axes.ravel()
    K = 3.0  # 3-sigma ellipses
    for ax, (mode, mrows, trajs, meta) in zip(axes, data):
        colour = style(mode, mode_order(dirs + sweep.modes))["color"]
        n_est = n_flag = 0
        for r in mrows:
            tx, ty, moving = fnum(r["true_x"]), fnum(r["true_y"]), r["truly_moving"].strip() == "1"
            if moving:
                ax.plot(tx, ty, "o", mfc="none", mec="k", ms=7, mew=1.2, zorder=3)
            else:
                ax.plot(tx, ty, "k.", ms=6, zorder=3)
            status = r["status"].strip()
            if status == "static":
                ex, ey = fnum(r["est_x"]), fnum(r["est_y"])
                ax.plot([tx, ex], [ty, ey], "-", color="0.6", lw=0.6, zorder=2)
                ax.plot(ex, ey, "+", color=colour, ms=7, mew=1.3, zorder=4)
                ellipse(ax, ex, ey, fnum(r["cov_xx"]), fnum(r["cov_xy"]), fnum(r["cov_yy"]), K,
                        ec=colour, lw=0.9, zorder=4)
                n_est += 1
            elif status == "moving":
                ax.plot(tx, ty, "x", color=FLAG_COLOUR, ms=9, mew=2.0, zorder=5)
                ax.annotate(r["id"], (tx, ty), xytext=(4, 4), textcoords="offset points", fontsize=7, color=FLAG_COLOUR)
                n_flag += 1
        for i, (rid, t) in enumerate(sorted(trajs.items())):
            c = ROBOT_COLOURS[i % len(ROBOT_COLOURS)]
            if "gt" in t and len(t["gt"]):
                ax.plot(t["gt"][:, 0], t["gt"][:, 1], "-", color=c, lw=2.2, alpha=0.45)
            if "est" in t and len(t["est"]):
                e = t["est"]
                ax.plot(e[:, 0], e[:, 1], "--", color=c, lw=1.4)
                ax.plot(e[-1, 0], e[-1, 1], "^", color=c, ms=8, mec="k", zorder=6)
                ax.annotate(f"robot {rid}", (e[-1, 0], e[-1, 1]), xytext=(5, -10), textcoords="offset points",
                            fontsize=8, color=c, zorder=7,
                            bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.8))
        if not trajs:
            print(f"plot_sweep: note: no trajectories in {mroot}/{mode}/, paths not drawn")
        ax.set_aspect("equal")
        ax.xaxis.set_major_locator(matplotlib.ticker.MultipleLocator(2.0))
        ax.yaxis.set_major_locator(matplotlib.ticker.MultipleLocator(2.0))
        ax.tick_params(labelsize=8)
        ax.grid(alpha=0.3)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        desc = mode
        if meta:
            desc += f": dynamism {fmt_num(meta.get('dynamism', math.nan))} %, speed {fmt_num(meta.get('speed', math.nan))} m/s, seed {meta.get('seed', '?')}"
        ax.set_title(f"{desc}\n{n_est} landmarks in the final map, {n_flag} flagged moving")
    hide_unused(axes, n)
    # One legend for the symbols.
    L = matplotlib.lines.Line2D
    handles = [L([], [], ls="", marker=".", color="k", ms=8, label="true static landmark"),
               L([], [], ls="", marker="o", mfc="none", mec="k", ms=7, label="true moving landmark"),
               L([], [], ls="", marker="+", color="0.3", ms=8, mew=1.3,
                 label=f"estimate, {K:g}σ ellipse (mode colour)"),
               L([], [], ls="", marker="x", color=FLAG_COLOUR, ms=8, mew=2, label="flagged moving (id)"),
               L([], [], ls="-", color="0.4", lw=2.2, alpha=0.45, label="true robot path"),
               L([], [], ls="--", color="0.4", lw=1.4, label="estimated robot path"),
               L([], [], ls="", marker="^", color="0.6", mec="k", ms=8, label="final estimated pose")]
    ncol = 4 if cols > 1 else 3
    fig.legend(handles=handles, loc="outside lower center", ncol=ncol, frameon=False, fontsize=9)
    suptitle(fig, "Final global map: true vs estimated landmarks and robot paths")
    finish(fig, os.path.join(out, "fig4_map.png"), written, tight=False)


def main():
    ap = doc_parser("plot_sweep.py", __doc__)
    ap.add_argument("dir", help="sweep output directory (runs.csv, frames.csv, maps/)")
    ap.add_argument("--out", help="directory for the PNGs (default: DIR)")
    args = _parse(ap)
    load_modules()
    out = args.out or args.dir
    try:
        if not os.path.isdir(args.dir):
            raise InputError(f"missing directory {args.dir}")
        sweep = Sweep(args.dir)
        os.makedirs(out, exist_ok=True)
        written = []
        for fn in (fig5, fig6, fig6b, fig7, fig8, fig4, detection):
            fn(sweep, out, written)
    except InputError as e:
        print(f"plot_sweep: error: {e}", file=sys.stderr)
        return 1
    print("plot_sweep: wrote")
    for p in written:
        print(f"  {p}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

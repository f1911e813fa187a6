#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""An MRCLAM recording without the robots' Vicon files, as a held-out check.

Public copies of other MRCLAM recordings often lack RobotN_Groundtruth.dat (the largest
files). Without them run_dataset cannot start: it places every robot at its ground-truth
pose and scores it against that path. Two commands make such a recording usable:

  prepare SRC OUT [--swap-landmarks A,B]
      copies SRC to OUT and writes a stand-in RobotN_Groundtruth.dat for each robot:
      EKF localisation against the surveyed landmarks (Landmark_Groundtruth.dat), along
      the odometry, smoothed (Rauch-Tung-Striebel). It starts from a pose fitted to the
      robot's first sightings (2-D rigid fit, RANSAC on pairs then least squares, in the
      shortest window of 12, 20, 30, 45... s holding 10 inliers on 3 landmarks) and, when
      6 sightings in a row fail its gate, resets to a fix (the same fit over +-3 s,
      every 2 s). Its settings were chosen on dataset6 against Vicon, where it is 0.16-0.32
      m RMS off (start 0.2-0.44 m, 0.01-0.1 rad): a run scored against it reads about
      0.07 m higher there when its error is 0.2 m (docs/mrclam.md). --swap-landmarks
      exchanges two subjects' surveyed positions (dataset1's copies have 11 and 17
      exchanged: every robot maps each where the file puts the other).
  aligned MAP_CSV
      RMS error of a run's map (map.csv) over the surveyed landmarks it holds, after the
      best rigid alignment onto the surveyed positions. A robot alone anchors its map at
      its start pose, so a wrong start moves its map rigidly and leaves this figure
      unchanged: run one robot at a time (run_dataset --robots R) for a figure that does
      not depend on the stand-in at all.

Exit 0, 1 when the data cannot be used, 2 bad arguments.
"""
import bisect
import math
import os
import shutil
import sys

_here = os.path.dirname(os.path.realpath(__file__))
sys.path[:0] = [_here, os.path.join(_here, "..", "share", "elaslam", "tools")]
from elaslam_tool import add_version, need, parse_args, run_in_venv  # noqa: E402  (standard library only)

import argparse  # noqa: E402


class DataError(Exception):
    pass


def rows(path, ncols):
    """Numeric rows of a whitespace-separated .dat file (comments '#' skipped)."""
    out = []
    try:
        with open(path, encoding="utf-8") as f:
            for n, line in enumerate(f, 1):
                s = line.split()
                if not s or s[0].startswith("#"):
                    continue
                if len(s) < ncols:
                    raise DataError(f"{path}:{n}: {len(s)} columns, {ncols} expected")
                try:
                    v = [float(x) for x in s[:ncols]]
                except ValueError:
                    raise DataError(f"{path}:{n}: not a number") from None
                if not all(math.isfinite(x) for x in v):
                    raise DataError(f"{path}:{n}: not a finite number")
                out.append(v)
    except OSError as e:
        raise DataError(f"{path}: {e.strerror}") from None
    if not out:
        raise DataError(f"{path}: no data lines")
    return out


def rigid_fit(src, dst):
    """(angle, tx, ty) of the rotation + translation taking points src onto dst (least squares)."""
    n = len(src)
    sx = sum(p[0] for p in src) / n
    sy = sum(p[1] for p in src) / n
    dx = sum(p[0] for p in dst) / n
    dy = sum(p[1] for p in dst) / n
    h00 = h01 = h10 = h11 = 0.0
    for (a, b), (c, d) in zip(src, dst):
        a, b, c, d = a - sx, b - sy, c - dx, d - dy
        h00 += a * c
        h01 += a * d
        h10 += b * c
        h11 += b * d
    ang = math.atan2(h01 - h10, h00 + h11)
    ca, sa = math.cos(ang), math.sin(ang)
    return ang, dx - (ca * sx - sa * sy), dy - (sa * sx + ca * sy)


def apply(t, p):
    ang, tx, ty = t
    ca, sa = math.cos(ang), math.sin(ang)
    return (ca * p[0] - sa * p[1] + tx, sa * p[0] + ca * p[1] + ty)


def dead_reckon(odo):
    """Poses (t, x, y, heading) from the start (0, 0, 0) along raw odometry."""
    out = [(odo[0][0], 0.0, 0.0, 0.0)]
    for k in range(1, len(odo)):
        t0, v, w = odo[k - 1]
        _, x, y, th = out[-1]
        dt = odo[k][0] - t0
        out.append((odo[k][0], x + v * dt * math.cos(th), y + v * dt * math.sin(th), th + w * dt))
    return out


def window_fit(path, times, meas, subject_of, surveyed, t_from, t_to, inlier_m, min_inliers, cap=None):
    """Rigid transform from the dead-reckoning frame to the surveyed one, from the sightings
    in [t_from, t_to] (RANSAC on pairs of sightings of different landmarks, then least
    squares on the inliers); None unless min_inliers inliers on 3 landmarks or more."""
    src, dst = [], []
    for tm, code, rng, brg in meas:
        s = subject_of.get(int(code))
        if s not in surveyed or tm < t_from or tm > t_to:
            continue
        k = min(bisect.bisect_left(times, tm), len(times) - 1)
        _, x, y, th = path[k]
        src.append((x + rng * math.cos(th + brg), y + rng * math.sin(th + brg)))
        dst.append(surveyed[s])
    if len(set(dst)) < 3:
        return None

    def inliers(t):
        return [i for i in range(len(src)) if math.dist(apply(t, src[i]), dst[i]) < inlier_m]

    hyp = range(len(src)) if cap is None or len(src) <= cap else \
        [round(i * (len(src) - 1) / (cap - 1)) for i in range(cap)]
    best = []
    for i in hyp:
        for j in hyp:
            if j <= i or math.dist(dst[i], dst[j]) < 0.5:
                continue
            keep = inliers(rigid_fit([src[i], src[j]], [dst[i], dst[j]]))
            if len(keep) > len(best):
                best = keep
    for _ in range(5):
        if len(best) < 2:
            return None
        t = rigid_fit([src[i] for i in best], [dst[i] for i in best])
        best = inliers(t)
    if len(best) < min_inliers or len({dst[i] for i in best}) < 3:
        return None
    return t, len(src), len(best)


# The stand-in's localisation filter (chosen on dataset6 against its Vicon, docs/mrclam.md):
# range and bearing noise, chi-square gate (2 dof, 99 %), odometry scale (the commanded
# speed overstates the distance) and noise, the number of sightings in a row outside the
# gate after which the pose is reset to the nearest fix, and the fixes' spacing and window.
SIGMA_RANGE, SIGMA_BEARING, GATE = 0.25, 0.05, 9.21
ODOM_SCALE, NOISE_TRANS, NOISE_ROT, NOISE_ROT_PER_M = 0.92, 0.3, 0.2, 0.1
RESET_AFTER = 6
FIX_EVERY_S, FIX_HALF_WINDOW_S = 2.0, 3.0


def localise(np, odo, meas, subject_of, surveyed, start, fixes):
    """EKF localisation against the surveyed landmarks along the odometry, reset to the nearest
    fix when it has lost them, then a Rauch-Tung-Striebel smoother. Returns (poses, used, resets)."""
    t = np.array([o[0] for o in odo])
    n = len(t)
    ms = [m for m in meas if subject_of.get(int(m[1])) in surveyed]
    X = np.zeros((n, 3)); P = np.zeros((n, 3, 3)); Xp = np.zeros((n, 3)); Pp = np.zeros((n, 3, 3))
    F = np.zeros((n, 3, 3))
    x = np.array(start, dtype=float); C = np.diag([0.5 ** 2, 0.5 ** 2, 0.3 ** 2])
    R = np.diag([SIGMA_RANGE ** 2, SIGMA_BEARING ** 2])
    fix_t = np.array([f[0] for f in fixes]) if fixes else np.zeros(0)
    mi = used = streak = resets = 0
    for k in range(n):
        if k > 0:
            dt = t[k] - t[k - 1]
            ds, dth = odo[k - 1][1] * ODOM_SCALE * dt, odo[k - 1][2] * dt
            c, s = math.cos(x[2]), math.sin(x[2])
            Fk = np.array([[1.0, 0.0, -ds * s], [0.0, 1.0, ds * c], [0.0, 0.0, 1.0]])
            G = np.array([[c, 0.0], [s, 0.0], [0.0, 1.0]])
            Q = np.diag([(NOISE_TRANS * ds) ** 2 + 1e-8, (NOISE_ROT * abs(dth) + NOISE_ROT_PER_M * abs(ds)) ** 2 + 1e-8])
            x = x + np.array([ds * c, ds * s, dth])
            C = Fk @ C @ Fk.T + G @ Q @ G.T
            F[k] = Fk
        Xp[k], Pp[k] = x, C
        while mi < len(ms) and ms[mi][0] <= t[k]:
            _, code, rng, brg = ms[mi]
            mi += 1
            lx, ly = surveyed[subject_of[int(code)]]
            dx, dy = lx - x[0], ly - x[1]
            q = dx * dx + dy * dy
            if q < 1e-6:
                continue
            r = math.sqrt(q)
            H = np.array([[-dx / r, -dy / r, 0.0], [dy / q, -dx / q, -1.0]])
            nu = np.array([rng - r, math.remainder(brg - (math.atan2(dy, dx) - x[2]), 2 * math.pi)])
            S = H @ C @ H.T + R
            if nu @ np.linalg.solve(S, nu) > GATE:
                streak += 1
                continue
            K = C @ H.T @ np.linalg.inv(S)
            x = x + K @ nu
            I_KH = np.eye(3) - K @ H
            C = I_KH @ C @ I_KH.T + K @ R @ K.T
            used += 1
            streak = 0
        if streak >= RESET_AFTER and len(fix_t):
            j = int(np.argmin(np.abs(fix_t - t[k])))
            if abs(fix_t[j] - t[k]) <= FIX_HALF_WINDOW_S:
                x = np.array(fixes[j][1:4]); C = np.diag([0.3 ** 2, 0.3 ** 2, 0.15 ** 2])
                F[k] = 0.0  # the smoother does not carry information across a reset
                streak = 0
                resets += 1
        X[k], P[k] = x, C
    Xs = X.copy()
    for k in range(n - 2, -1, -1):
        G = P[k] @ F[k + 1].T @ np.linalg.inv(Pp[k + 1])
        d = Xs[k + 1] - Xp[k + 1]
        d[2] = math.remainder(d[2], 2 * math.pi)
        Xs[k] = X[k] + G @ d
    return [(t[k], Xs[k, 0], Xs[k, 1], math.remainder(Xs[k, 2], 2 * math.pi)) for k in range(n)], used, resets


def prepare(a):
    np = need("numpy", "python3-numpy")
    if os.path.abspath(a.src) == os.path.abspath(a.out):
        raise DataError("OUT must not be SRC (prepare writes ground-truth files)")
    os.makedirs(a.out, exist_ok=True)
    names = ["Barcodes.dat", "Landmark_Groundtruth.dat"] + [
        f"Robot{r}_{k}.dat" for r in range(1, 6) for k in ("Odometry", "Measurement")]
    for n in names:
        if not os.path.isfile(os.path.join(a.src, n)):
            raise DataError(f"{os.path.join(a.src, n)}: missing")
        shutil.copyfile(os.path.join(a.src, n), os.path.join(a.out, n))
    subject_of = {int(b): int(s) for s, b in rows(os.path.join(a.out, "Barcodes.dat"), 2)}
    lpath = os.path.join(a.out, "Landmark_Groundtruth.dat")
    lms = rows(lpath, 5)
    if a.swap_landmarks:
        p, q = a.swap_landmarks
        ids = [int(r[0]) for r in lms]
        if p not in ids or q not in ids:
            raise DataError(f"--swap-landmarks: subject {p if p not in ids else q} is not in {lpath}")
        for r in lms:
            r[0] = q if int(r[0]) == p else p if int(r[0]) == q else int(r[0])
        with open(lpath, "w", encoding="utf-8") as f:
            f.write(f"# surveyed landmarks, subjects {p} and {q} exchanged (mrclam_heldout.py prepare)\n")
            for r in sorted(lms):
                f.write(f"{int(r[0])} {r[1]:.8f} {r[2]:.8f} {r[3]:.8f} {r[4]:.8f}\n")
    surveyed = {int(r[0]): (r[1], r[2]) for r in lms}
    for r in range(1, 6):
        odo = rows(os.path.join(a.out, f"Robot{r}_Odometry.dat"), 3)
        meas = rows(os.path.join(a.out, f"Robot{r}_Measurement.dat"), 4)
        path = dead_reckon(odo)
        times = [p[0] for p in path]
        fit = None
        for window in (12, 20, 30, 45, 60, 90, 120, 180, 300):
            fit = window_fit(path, times, meas, subject_of, surveyed, times[0], times[0] + window, 0.4, 10)
            if fit:
                break
        if not fit:
            raise DataError(f"robot {r}: its sightings of the surveyed landmarks do not fix its start pose")
        to_surveyed = fit[0]
        fixes = []
        tc = times[0]
        while tc <= times[-1]:
            f = window_fit(path, times, meas, subject_of, surveyed, tc - FIX_HALF_WINDOW_S, tc + FIX_HALF_WINDOW_S,
                           0.3, 4, cap=24)
            if f:
                k = min(bisect.bisect_left(times, tc), len(times) - 1)
                fx, fy = apply(f[0], path[k][1:3])
                fixes.append((tc, fx, fy, math.remainder(path[k][3] + f[0][0], 2 * math.pi)))
            tc += FIX_EVERY_S
        sx, sy = apply(to_surveyed, (0.0, 0.0))
        poses, used, resets = localise(np, odo, meas, subject_of, surveyed, (sx, sy, to_surveyed[0]), fixes)
        print(f"robot {r}: start ({poses[0][1]:.3f}, {poses[0][2]:.3f}, {poses[0][3]:.4f}); {used} of {len(meas)} "
              f"sightings used, {len(fixes)} fixes, {resets} resets")
        with open(os.path.join(a.out, f"Robot{r}_Groundtruth.dat"), "w", encoding="utf-8") as f:
            f.write("# NOT Vicon: localisation against the surveyed landmarks, smoothed "
                    "(mrclam_heldout.py prepare); about 0.2 m RMS off Vicon on dataset6\n")
            for tm, x, y, th in poses:
                f.write(f"{tm:.3f} {x:.6f} {y:.6f} {th:.6f}\n")
    return 0


def aligned(a):
    import csv
    est, true = [], []
    try:
        with open(a.map_csv, encoding="utf-8") as f:
            rd = csv.DictReader(f)
            if not {"id", "est_x", "est_y", "true_x", "true_y"} <= set(rd.fieldnames or []):
                raise DataError(f"{a.map_csv}: not a run's map.csv (id, est_x, est_y, true_x, true_y)")
            for row in rd:
                try:
                    v = [float(row[k]) for k in ("est_x", "est_y", "true_x", "true_y")]
                except (TypeError, ValueError):
                    continue  # not mapped
                if row.get("id", "").strip() in ("1", "2", "3", "4", "5"):
                    continue  # subjects 1-5 are the robots: no surveyed position
                if all(math.isfinite(x) for x in v):
                    est.append((v[0], v[1]))
                    true.append((v[2], v[3]))
    except OSError as e:
        raise DataError(f"{a.map_csv}: {e.strerror}") from None
    if len(est) < 3:
        raise DataError(f"{a.map_csv}: {len(est)} mapped landmarks, 3 needed")
    t = rigid_fit(est, true)
    rms = math.sqrt(sum(math.dist(apply(t, e), g) ** 2 for e, g in zip(est, true)) / len(est))
    print(f"aligned RMS {rms:.3f} m over {len(est)} landmarks (rotation {t[0]:+.3f} rad)")
    return 0


def subject_pair(text):
    try:
        p, q = (int(x) for x in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"two subject numbers A,B expected, not '{text}'") from None
    if p == q:
        raise argparse.ArgumentTypeError(f"two different subjects expected, not '{text}'")
    return p, q


def main():
    run_in_venv()
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    add_version(ap)
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("prepare", help="copy a recording and write stand-in robot ground truth (localisation)")
    p.add_argument("src")
    p.add_argument("out")
    p.add_argument("--swap-landmarks", metavar="A,B", type=subject_pair,
                   help="exchange two subjects' surveyed positions")
    q = sub.add_parser("aligned", help="a map's RMS error after the best rigid alignment")
    q.add_argument("map_csv")
    a = parse_args(ap)
    try:
        return prepare(a) if a.cmd == "prepare" else aligned(a)
    except DataError as e:
        print(f"mrclam_heldout: {e}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())

# SPDX-License-Identifier: Apache-2.0
"""Checks of tools/export.py (run by tests/tools/export_check.sh with the .venv's python).

    export_check.py unit   --root SRC --build BUILD --work DIR
    export_check.py system --root SRC --build BUILD --work DIR --log RUN.lcmlog --tum-dir DIR

unit: a recording written here (every exported channel, an undecodable event, stray
bytes, a channel that is not exported) and its bag checked value by value; bad inputs.
system: a live run's bag: per-topic counts equal log_info's per channel, the last pose
of each robot equals the last line of its .tum file (evaluate) to 1e-6.
Both: the bag opens with the mcap reader and with rosbags, which agree on every topic's
count; `ros2 bag info` succeeds when ros2 is on PATH.
"""
import argparse
import json
import math
import os
import shutil
import struct
import subprocess
import sys
from pathlib import Path

FAILS = []


def check(cond, what):
    if not cond:
        FAILS.append(what)
        print(f"FAIL: {what}")
    return cond


def close(a, b, what, tol=1e-6):
    return check(abs(a - b) <= tol, f"{what}: {a} vs {b}")


def run_export(a, *args):
    p = subprocess.run([os.path.join(a.root, "tools", "export.py"), *args], capture_output=True, text=True,
                       timeout=300)
    return p.returncode, p.stdout, p.stderr


def log_counts(a, log):
    """log_info's decoded events per channel (count minus decode_errors)."""
    info = json.loads(subprocess.run([os.path.join(a.build, "bin", "log_info"), "--json", log], check=True,
                                     capture_output=True, text=True).stdout)
    return {c["name"]: c["count"] - (c["decode_errors"] or 0) for c in info["channels"]}


def expected_topics(counts):
    """The bag's topic counts that log_info's channels imply (docs/tools.md "export")."""
    want = {}
    def add(topic, n):
        want[topic] = want.get(topic, 0) + n
    for ch, n in counts.items():
        for prefix, fmt in (("POSE_", "/robot{}/pose"), ("STATUS_ROBOT_", "/robot{}/status")):
            if ch.startswith(prefix) and ch[len(prefix):].isdigit():
                add(fmt.format(int(ch[len(prefix):])), n)
                if prefix == "POSE_":
                    add("/tf", n)
        fixed = {"GLOBAL_MAP": ["/global_map"], "GROUND_TRUTH": ["/ground_truth/robots", "/ground_truth/landmarks"],
                 "DYNAMIC_NOTICE": ["/moving_landmark_notices"], "STATUS_MAIN": ["/main_robot/status"],
                 "STATUS_SIM": ["/simulator/status"]}
        for topic in fixed.get(ch, []):
            add(topic, n)
    return {t: n for t, n in want.items() if n > 0}


def read_bag(bag):
    """{topic: [messages]} read with rosbags; the mcap reader's per-topic counts and
    schemas must agree."""
    from mcap.reader import make_reader
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore
    mcaps = sorted(Path(bag).glob("*.mcap"))
    if not check(len(mcaps) == 1, f"{bag}: one .mcap file, found {mcaps}"):
        return {}
    by_mcap = {}
    with open(mcaps[0], "rb") as f:
        reader = make_reader(f)
        for schema, channel, message in reader.iter_messages():
            check(channel.message_encoding == "cdr" and schema.encoding == "ros2msg",
                  f"mcap: {channel.topic}: encoding {channel.message_encoding}, schema {schema.encoding}")
            by_mcap.setdefault(channel.topic, []).append(schema.name)
    msgs = {}
    with AnyReader([Path(bag)], default_typestore=get_typestore(Stores.ROS2_JAZZY)) as reader:
        for conn, _, raw in reader.messages():
            msgs.setdefault(conn.topic, []).append(reader.deserialize(raw, conn.msgtype))
    check({t: len(v) for t, v in by_mcap.items()} == {t: len(v) for t, v in msgs.items()},
          "the mcap and rosbags readers disagree on the topics' counts")
    if shutil.which("ros2"):
        p = subprocess.run(["ros2", "bag", "info", bag], capture_output=True, text=True, timeout=120)
        check(p.returncode == 0, f"ros2 bag info {bag}: exit {p.returncode}: {p.stderr[-500:]}")
        print("ros2 bag info: ok")
    else:
        print("ros2 not on PATH: `ros2 bag info` not tried")
    return msgs


def check_counts(msgs, counts):
    got = {t: len(v) for t, v in msgs.items()}
    want = expected_topics(counts)
    for t in sorted(set(got) | set(want)):
        check(got.get(t, 0) == want.get(t, 0), f"{t}: {got.get(t, 0)} messages, log_info implies {want.get(t, 0)}")
    print("counts: " + ", ".join(f"{t} {n}" for t, n in sorted(got.items())))


def ns_of(t):
    return t.sec * 1_000_000_000 + t.nanosec


# ---- system -------------------------------------------------------------------------
def system(a):
    bag = os.path.join(a.work, "bag")
    rc, out, err = run_export(a, a.log, "-o", bag)
    print(out, err, end="")
    if not check(rc == 0, f"export exit {rc}"):
        return
    msgs = read_bag(bag)
    check_counts(msgs, log_counts(a, a.log))
    t0 = ns_of(msgs["/ground_truth/robots"][0].header.stamp)
    for tum in sorted(Path(a.tum_dir).glob("robot*.tum")):
        if tum.name.endswith("_gt.tum"):
            continue
        robot = int(tum.stem[len("robot"):])
        last = [ln for ln in tum.read_text().splitlines() if ln and not ln.startswith("#")][-1].split()
        t, x, y, z, qx, qy, qz, qw = map(float, last)
        p = msgs[f"/robot{robot}/pose"][-1]
        pos, q = p.pose.pose.position, p.pose.pose.orientation
        for name, got, want in (("time", (ns_of(p.header.stamp) - t0) * 1e-9, t), ("x", pos.x, x), ("y", pos.y, y),
                                ("z", pos.z, z), ("qx", q.x, qx), ("qy", q.y, qy), ("qz", q.z, qz), ("qw", q.w, qw)):
            close(got, want, f"robot {robot} last pose {name} against {tum.name}")
        tf = [m.transforms[0] for m in msgs["/tf"] if m.transforms[0].child_frame_id == f"robot{robot}"][-1]
        close(tf.transform.translation.x, x, f"robot {robot} last /tf x")
        print(f"robot {robot}: last pose = {tum.name} last line ({' '.join(last)})")


# ---- unit ---------------------------------------------------------------------------
def load_types(a):
    sys.path.insert(0, os.path.join(a.build, "lcmgen", "python"))
    import elaslam
    return elaslam


def event(num, utime, channel, data):
    ch = channel.encode()
    return struct.pack(">IqqII", 0xEDA1DA01, num, utime, len(ch), len(data)) + ch + data


T0 = 1_700_000_000_000_000  # [us] the made-up run's first frame


def made_up_recording(T):
    """(log bytes, what the checks need): every exported channel with known values."""
    ev = []
    gt = T.ground_truth_t()
    gt.utime, gt.frame, gt.num_robots, gt.robot_ids = T0, 0, 2, [1, 2]
    gt.robots = [T.pose2_t(), T.pose2_t()]
    gt.robots[0].x, gt.robots[0].y, gt.robots[0].theta = 1.0, 2.0, 0.5
    gt.robots[1].x, gt.robots[1].y, gt.robots[1].theta = -1.0, 0.0, -3.0
    gt.landmarks = []
    for i, (x, y, mv) in enumerate(((3.0, 0.0, False), (0.0, 3.0, True), (4.0, 4.0, False))):
        lm = T.landmark_truth_t()
        lm.id, lm.x, lm.y, lm.moving = i, x, y, mv
        gt.landmarks.append(lm)
    gt.num_landmarks = 3
    ev.append((T0 + 100, "GROUND_TRUTH", gt.encode()))
    cov = [[0.04, 0.01, 0.002], [0.01, 0.09, 0.003], [0.002, 0.003, 0.01]]
    for r, (x, y, th) in ((1, (1.1, 2.1, 0.4)), (2, (-0.9, 0.1, 3.1))):
        p = T.pose_estimate_t()
        p.utime, p.frame, p.robot_id, p.source_utime, p.x, p.y, p.theta, p.cov = T0 + 700, 0, r, T0, x, y, th, cov
        ev.append((T0 + 800, f"POSE_{r}", p.encode()))
    ev.append((T0 + 850, "POSE_1", b"\x00" * 40))  # undecodable: counted, not fatal
    ev.append((T0 + 860, "LCM_SELF_TEST", b"hello"))  # not an elaslam channel: not exported

    def gmap(utime, landmarks, moving):
        g = T.global_map_t()
        g.utime, g.frame, g.version, g.chunk, g.num_chunks, g.id_begin, g.id_end = utime, 0, 1, 0, 1, 0, 10
        g.landmarks = []
        for lid, x, y, c in landmarks:
            lm = T.global_landmark_t()
            lm.id, lm.x, lm.y, lm.cov, lm.status, lm.contributors = lid, x, y, c, T.global_landmark_t.STATIC, 1
            g.landmarks.append(lm)
        g.num_landmarks = len(g.landmarks)
        g.moving_ids, g.moving_by = [m[0] for m in moving], [m[1] for m in moving]
        g.moving_frames = [0] * len(moving)
        g.num_moving = len(moving)
        return g.encode()
    c3, c5 = [[0.01, 0.0], [0.0, 0.04]], [[0.02, 0.0], [0.0, 0.02]]
    ev.append((T0 + 900, "GLOBAL_MAP", gmap(T0 + 890, [(3, 3.0, 0.1, c3), (5, 0.1, 3.0, c5)], [])))
    ev.append((T0 + 1000, "GLOBAL_MAP", gmap(T0 + 990, [(3, 3.0, 0.1, c3)], [(5, 2), (7, 0)])))
    ev.append((T0 + 1100, "GLOBAL_MAP", gmap(T0 + 1090, [], [])))
    n = T.dynamic_notice_t()
    n.utime, n.frame, n.incarnation, n.seq, n.landmark_id, n.detected_by = T0 + 950, 0, 42, 1, 5, 2
    ev.append((T0 + 960, "DYNAMIC_NOTICE", n.encode()))
    S = T.node_status_t
    for ch, flags, kind, nid in (("STATUS_ROBOT_1", 0, S.ROBOT, 1), ("STATUS_ROBOT_2", S.FAULT_FRAMES_LOST, S.ROBOT, 2),
                                 ("STATUS_MAIN", S.FAULT_CAPACITY | S.FAULT_FRAMES_LOST, S.MAIN, 0),
                                 ("STATUS_SIM", 0, S.SIMULATOR, 0)):
        s = S()
        s.utime, s.frame, s.node_kind, s.node_id, s.fault_flags, s.frames = T0 + 1200, 0, kind, nid, flags, 7
        s.mode = S.MODE_ELA if kind == S.ROBOT else S.MODE_NONE
        s.refused = [0, 3, 0, 0, 0, 0, 0, 0]
        ev.append((T0 + 1300, ch, s.encode()))
    data = b""
    for i, (t, ch, d) in enumerate(ev):
        data += event(i, t, ch, d)
        if ch == "LCM_SELF_TEST":
            data += b"stray bytes"  # between events: skipped, counted
    return data


def unit(a):
    T = load_types(a)
    w = Path(a.work)
    log = w / "made_up.lcmlog"
    log.write_bytes(made_up_recording(T))
    bag = str(w / "bag")
    rc, out, err = run_export(a, str(log), "-o", bag)
    print(out, err, end="")
    if not check(rc == 0, f"export exit {rc}"):
        return
    check("1 event did not decode" in err and "POSE_1 (1)" in err, f"the undecodable POSE_1 is reported: {err!r}")
    check("11 bytes between events skipped" in out, "the stray bytes are reported")
    msgs = read_bag(bag)
    check_counts(msgs, log_counts(a, str(log)))
    # POSE: stamp = source_utime, (x, y, theta) covariance at rows/columns 0, 1, 5.
    p = msgs["/robot1/pose"][0]
    check(ns_of(p.header.stamp) == T0 * 1000 and p.header.frame_id == "map", "pose stamp and frame")
    close(p.pose.pose.position.x, 1.1, "pose x")
    close(p.pose.pose.orientation.z, math.sin(0.2), "pose qz")
    close(p.pose.pose.orientation.w, math.cos(0.2), "pose qw")
    c = p.pose.covariance
    for (i, j), v in {(0, 0): 0.04, (0, 1): 0.01, (1, 1): 0.09, (0, 5): 0.002, (5, 1): 0.003, (5, 5): 0.01,
                      (2, 2): 0.0, (3, 3): 0.0, (4, 4): 0.0}.items():
        close(c[6 * i + j], v, f"pose covariance [{i}][{j}]")
    tfs = [m.transforms[0] for m in msgs["/tf"]]
    check([(t.header.frame_id, t.child_frame_id) for t in tfs] == [("map", "robot1"), ("map", "robot2")], "tf frames")
    close(tfs[1].transform.translation.x, -0.9, "tf x")
    # Ground truth.
    r = msgs["/ground_truth/robots"][0]
    check(len(r.poses) == 2 and ns_of(r.header.stamp) == T0 * 1000, "truth robots")
    close(r.poses[1].orientation.z, math.sin(-1.5), "truth robot 2 qz")
    lms = msgs["/ground_truth/landmarks"][0].markers
    check([len(m.points) for m in lms] == [2, 1], "truth landmarks: 2 static, 1 moving")
    # Global map: spheres and ellipses; moving drawn where last mapped; deletions.
    def marks(k):
        return {(m.ns, m.id): m for m in msgs["/global_map"][k].markers}
    m0, m1, m2 = marks(0), marks(1), marks(2)
    check(set(m0) == {("landmarks", 3), ("ellipses", 3), ("landmarks", 5), ("ellipses", 5)}, f"map 0: {sorted(m0)}")
    e3 = m0[("ellipses", 3)]
    close(e3.scale.x, 6 * 0.2, "ellipse 3 major diameter (3 sigma)")
    close(e3.scale.y, 6 * 0.1, "ellipse 3 minor diameter")
    close(e3.pose.orientation.z, math.sin(math.pi / 4), "ellipse 3 major axis along y")
    check(m0[("landmarks", 3)].color.g > 0.5 and m0[("landmarks", 3)].action == 0, "static: green")
    s5 = m1[("landmarks", 5)]
    check(s5.color.r > 0.8 and s5.color.g < 0.2 and s5.action == 0, "moving (noticed): red")
    close(s5.pose.position.y, 3.0, "moving landmark at its last mapped position")
    check(m1[("ellipses", 5)].action == 2, "a moving landmark's ellipse is deleted")
    check(("landmarks", 7) not in m1, "a moving landmark never mapped has no marker")
    check({k for k, m in m2.items() if m.action == 2} == {("landmarks", 3), ("ellipses", 3), ("landmarks", 5)},
          f"an empty chunk deletes its range: {sorted(m2)}")
    check(ns_of(msgs["/global_map"][0].markers[0].header.stamp) == (T0 + 890) * 1000, "map stamp = utime")
    # Notices: JSON.
    note = json.loads(msgs["/moving_landmark_notices"][0].data)
    check(note == {"utime": T0 + 950, "frame": 0, "landmark_id": 5, "detected_by": 2, "seq": 1, "incarnation": 42},
          f"notice {note}")
    # Status: levels from the faults; the counters as key-values.
    def status(topic):
        s = msgs[topic][0].status[0]
        return s.level, s.message, {kv.key: kv.value for kv in s.values}
    lvl, text, kv = status("/robot1/status")
    check(lvl == 0 and text == "OK" and kv["frames"] == "7" and kv["mode"] == "ela" and kv["refused.implausible"] == "3",
          f"robot 1 status: {lvl} {text} {kv}")
    lvl, text, _ = status("/robot2/status")
    check(lvl == 1 and text == "frames lost", f"robot 2 status: WARN frames lost, got {lvl} {text}")
    lvl, text, _ = status("/main_robot/status")
    check(lvl == 2 and text == "capacity, frames lost", f"main status: ERROR, got {lvl} {text}")
    check(status("/simulator/status")[0] == 0, "simulator status OK")
    bad_inputs(a, log, bag, w)


def bad_inputs(a, log, bag, w):
    """Each exits as docs/tools.md says, naming the problem, without a traceback."""
    (w / "notlcm.txt").write_text("hello world\n")
    (w / "empty.lcmlog").write_bytes(b"")
    (w / "notabag").mkdir()
    data = log.read_bytes()
    (w / "truncated.lcmlog").write_bytes(data[:-7])
    cases = [
        ([str(w / "missing.lcmlog"), "-o", str(w / "o1")], 2, "no such recording"),
        ([str(w), "-o", str(w / "o2")], 2, "is a directory"),
        ([str(w / "notlcm.txt"), "-o", str(w / "o3")], 2, "is not an LCM log"),
        (["/dev/null", "-o", str(w / "o3")], 2, "is not a regular file"),
        ([str(w / "empty.lcmlog"), "-o", str(w / "o4")], 2, "nothing to export"),
        ([str(log), "-o", bag], 2, "exists already"),
        ([str(log), "-o", str(w / "notabag"), "--force"], 2, "replaces only a bag"),
        ([str(log), "-o", str(w / "nodir" / "o5")], 2, "does not exist"),
        ([str(log)], 2, "-o/--out"),
        ([str(log), "-o", str(w / "o6"), "--bogus"], 2, "unrecognized argument: --bogus"),
        ([str(log), "-o", str(w / "o7"), "--build-dir", str(w / "nobuild")], 2, "no generated Python message types"),
        ([str(w / "truncated.lcmlog"), "-o", str(w / "o8")], 0, "is truncated"),
        ([str(log), "-o", bag, "--force"], 0, ""),
    ]
    for args, want_rc, text in cases:
        rc, out, err = run_export(a, *args)
        check(rc == want_rc and text in err and "Traceback" not in err,
              f"export {' '.join(args)}: exit {rc} (want {want_rc}), stderr {err.strip()!r} (want {text!r})")
    for o in ("o1", "o2", "o3", "o4", "o5", "o6", "o7"):
        check(not (w / o).exists(), f"no output left behind for a refused input ({o})")
    check(not any(p.name.startswith(".") for p in w.iterdir()), "no temporary directory left behind")
    check_counts(read_bag(str(w / "o8")), log_counts(a, str(w / "truncated.lcmlog")))
    print(f"bad inputs: {len(cases)} cases")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mode", choices=["unit", "system"])
    ap.add_argument("--root", required=True)
    ap.add_argument("--build", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--log")
    ap.add_argument("--tum-dir")
    a = ap.parse_args()
    (unit if a.mode == "unit" else system)(a)
    if FAILS:
        print(f"export_check {a.mode}: {len(FAILS)} failures")
        return 1
    print(f"export_check {a.mode}: ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The table of tools/fault_test.sh: fault runs against the lossless run of their seed.

    fault_summary.py --out DIR --build-dir BUILD [--kill-robot R] NAME...

Each NAME is a run directory DIR/NAME of tools/run_team.sh (metrics.json, map.csv,
run.lcmlog; loss.csv with --loss; faults.log with --kill-robot), named
seed<S>_lossless, seed<S>_loss<P>, seed<S>_loss<P>all (the robots' SENSOR frames lost
too: run_team.sh --loss-scope all) or seed<S>_kill<R>. Writes DIR/summary.md (also on
stdout) and DIR/summary.csv. Needs the PyPI `lcm` (the project's .venv) and the
generated Python types (BUILD/lcmgen/python) to read the recordings.

Targets (every fault row; docs/faults.md): final global map's static landmarks
within 2 of the lossless run's, its landmark error within 1.2x, every truly moving
landmark whose latest word from the robots is MOVING (LMAP_EVENT(S): no later ADD or
RETURN of it by any robot) absent from the last GLOBAL_MAP's static landmarks (but
for those reported in the last --repair-window frames, 20 by default: "pending",
their repair may be under way when the run ends); a kill row also: robot R's mean pose error within 1.5x. (A landmark a robot flagged and
later re-added, e.g. one that stopped at the end of its path, is the robots' call,
not the protocol's: the CSV has the raw counts too, moving_ever_flagged[_in_map].)
"""
import argparse
import csv
import json
import os
import re
import sys

_here = os.path.dirname(os.path.realpath(__file__))
sys.path[:0] = [_here, os.path.join(_here, "..", "share", "elaslam", "tools")]
from elaslam_tool import add_version, parse_args  # noqa: E402  (standard library only)

STATIC_TOL = 2
ERROR_FACTOR = 1.2
# A lost MOVING event is repaired when main_robot's resync request (every
# main.resync_interval_frames = 5 while a gap is open) and the robot's answer get
# through: at 30 % loss each try succeeds with about 0.7 x 0.7 = 0.49, so 4 tries
# (20 frames) repair 93 % of losses. A mover reported in the run's last 20 frames and
# still in the final map is "pending", not a failure.
REPAIR_WINDOW = 20
ROBOT_FACTOR = 1.5


def read_recording(path, types, kill_robot, restart_time):
    """From a recording (lcm-logger's: complete, whatever the hosts lost): ids some
    robot reported MOVING; of those, the ids whose latest word from the robots (by
    frame, over ADD, MOVING and RETURN events of every robot) is MOVING; the last
    complete GLOBAL_MAP publication's static ids and frame (its chunks); robot kill_robot's POSEs received after
    restart_time (Unix seconds; None: not counted)."""
    import lcm
    E = types.landmark_event_t
    moving, static, last_map_frame, poses_after = set(), None, -1, 0
    building_key, building = None, {}
    word = {}  # id -> (frame, kind): the robots' latest word on the landmark
    pose_channel = f"POSE_{kill_robot}"
    for ev in lcm.EventLog(path, "r"):
        if ev.channel in ("LMAP_EVENT", "LMAP_EVENTS"):  # one event, or a frame's events
            try:
                events = [E.decode(ev.data)] if ev.channel == "LMAP_EVENT" else types.lmap_events_t.decode(ev.data).events
            except Exception:  # noqa: BLE001 (counted by evaluate's decode_errors)
                continue
            for m in events:
                if m.kind == E.MOVING:
                    moving.add(m.landmark_id)
                if m.kind in (E.ADD, E.MOVING, E.RETURN) and m.frame >= word.get(m.landmark_id, (-1, 0))[0]:
                    word[m.landmark_id] = (m.frame, m.kind)
        elif ev.channel == "GLOBAL_MAP":
            try:
                m = types.global_map_t.decode(ev.data)
            except Exception:  # noqa: BLE001
                continue
            # The chunks of one publication share (utime, incarnation, version, frame):
            # the map is the last publication whose chunks all arrived.
            key = (m.utime, m.incarnation, m.version, m.frame, m.num_chunks)
            if key != building_key:
                building_key, building = key, {}
            building[m.chunk] = {m.landmarks[i].id for i in range(m.num_landmarks)}
            if len(building) == m.num_chunks:
                static = set().union(*building.values())
                last_map_frame = m.frame
        elif ev.channel == pose_channel and restart_time is not None and ev.timestamp / 1e6 > restart_time:
            poses_after += 1
    still_moving = {i: word[i][0] for i in moving if word[i][1] == E.MOVING}  # id -> frame of that MOVING
    return moving, still_moving, static or set(), last_map_frame, poses_after


def parse_name(name):
    m = re.fullmatch(r"seed(\d+)_(lossless|loss([0-9.]+)(all)?|kill(\d+))", name)
    if not m:
        raise SystemExit(f"fault_summary: run name '{name}' is not seed<S>_lossless|loss<P>|loss<P>all|kill<R>")
    seed = int(m.group(1))
    if m.group(2) == "lossless":
        return seed, "lossless", None
    if m.group(3) is not None:
        if m.group(4):
            return seed, f"loss {m.group(3)} %, SENSOR too", ("loss", float(m.group(3)))
        return seed, f"loss {m.group(3)} %", ("loss", float(m.group(3)))
    return seed, f"robot {m.group(5)} killed", ("kill", int(m.group(5)))


def fault_times(path):
    """(kill time, restart time) in Unix seconds from faults.log, None when absent."""
    kill = restart = None
    if os.path.isfile(path):
        for line in open(path):
            t, _, what = line.partition(" ")
            if what.startswith("killed") and kill is None:
                kill = float(t)
            elif what.startswith("restarted") and restart is None:
                restart = float(t)
    return kill, restart


def measured_loss(path):
    if not os.path.isfile(path):
        return None, 0, 0
    n = d = 0
    for row in csv.DictReader(open(path)):
        n += int(row["packets"]); d += int(row["dropped"])
    return (100.0 * d / n if n else 0.0), n, d


def analyse(run_dir, types, kill_robot, repair_window):
    metrics = json.load(open(os.path.join(run_dir, "metrics.json")))
    truly_moving = set()
    with open(os.path.join(run_dir, "map.csv")) as f:
        for row in csv.DictReader(f):
            if row["truly_moving"] == "1":
                truly_moving.add(int(row["id"]))
    kill_t, restart_t = fault_times(os.path.join(run_dir, "faults.log"))
    flagged, still_moving, static, map_frame, poses_after = read_recording(os.path.join(run_dir, "run.lcmlog"), types,
                                                               kill_robot, restart_t)
    detected = set(still_moving) & truly_moving
    # Reported MOVING within the last repair_window frames before the last map: a
    # lost MOVING may still be under repair when the run ends (not a failure).
    recent = {i for i in detected if still_moving[i] > map_frame - repair_window}
    ever = flagged & truly_moving
    loss, packets, dropped = measured_loss(os.path.join(run_dir, "loss.csv"))
    robots = {r["id"]: r for r in metrics["robots"]}
    return {
        "static": metrics["final_map"]["static"],
        "error": metrics["landmark_error"]["mean_euclidean"],
        "moving_detected": len(detected),
        "moving_deleted": len(detected - static),
        "moving_left": sorted((detected - recent) & static),
        "moving_pending": sorted(recent & static),
        "false_flags": len(flagged - truly_moving),
        "moving_ever_flagged": len(ever),
        "moving_ever_flagged_in_map": len(ever & static),
        "last_map_frame": map_frame,
        "robot_error": {rid: r["error_mean"] for rid, r in robots.items()},
        "robot_dropped": {rid: r.get("frames_dropped", 0) for rid, r in robots.items()},
        "restarts": {rid: r.get("restarts", 0) for rid, r in robots.items()},
        "frames_dropped": metrics.get("frames_dropped", 0),
        "loss": loss, "packets": packets, "dropped": dropped,
        "killed": kill_t is not None, "restarted": restart_t is not None,
        "poses_after_restart": poses_after,
    }


def judge(row, ref, fault):
    """Failed targets of a fault row against the lossless run ([] = pass)."""
    fails = []
    # A pending mover is still among the map's static landmarks: not counted twice.
    static = row["static"] - len(row["moving_pending"])
    if abs(static - ref["static"]) > STATIC_TOL:
        fails.append(f"static {static} vs {ref['static']}" + (" (pending movers left out)" if row["moving_pending"] else ""))
    if row["error"] > ERROR_FACTOR * ref["error"]:
        fails.append(f"map error x{row['error'] / ref['error']:.2f}")
    if row["moving_left"]:
        fails.append(f"moving still in map: {','.join(map(str, row['moving_left']))}")
    if fault[0] == "kill":
        r = fault[1]
        if r not in row["robot_error"]:
            fails.append(f"no robot {r}")
        elif row["robot_error"][r] > ROBOT_FACTOR * ref["robot_error"][r]:
            fails.append(f"robot {r} error x{row['robot_error'][r] / ref['robot_error'][r]:.2f}")
        if not row["killed"]:
            fails.append("not killed")
    return fails


def main():
    ap = argparse.ArgumentParser(prog="fault_summary.py", description=__doc__.split("\n\n")[0])
    add_version(ap)
    ap.add_argument("--out", required=True)
    ap.add_argument("--build-dir", required=True)
    ap.add_argument("--kill-robot", type=int, default=2)
    ap.add_argument("--repair-window", type=int, default=REPAIR_WINDOW, metavar="FRAMES",
                    help="a mover reported MOVING less than FRAMES frames before the last map and still in it is "
                         f"pending (its repair may be under way), not a failure (default {REPAIR_WINDOW})")
    ap.add_argument("names", nargs="+")
    args = parse_args(ap)
    sys.path.insert(0, os.path.join(args.build_dir, "lcmgen", "python"))
    import elaslam as types

    rows = []
    for name in args.names:
        seed, label, fault = parse_name(name)
        d = os.path.join(args.out, name)
        if not os.path.isfile(os.path.join(d, "metrics.json")):
            rows.append((name, seed, label, fault, None))
            continue
        rows.append((name, seed, label, fault, analyse(d, types, args.kill_robot, args.repair_window)))
    refs = {seed: a for name, seed, label, fault, a in rows if fault is None and a is not None}
    robot_ids = sorted({rid for *_, a in rows if a for rid in a["robot_error"]})

    head = (["run", "seed", "fault", "loss measured %", "map static", "vs lossless", "map error m", "vs lossless",
             "moving detected / deleted"] + [f"robot {r} error m" for r in robot_ids] +
            [f"robot {args.kill_robot} vs lossless", "frames dropped", "result"])
    md = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    csv_rows = []
    for name, seed, label, fault, a in rows:
        if a is None:
            md.append(f"| {name} | {seed} | {label} | | | | | | | " + "| " * len(robot_ids) + "| | did not run |")
            csv_rows.append({"run": name, "seed": seed, "fault": label, "result": "did not run"})
            continue
        ref = refs.get(seed)
        kr = args.kill_robot
        if fault is None:
            result, fails = "reference", []
        elif ref is None:
            result, fails = "no lossless run", []
        else:
            fails = judge(a, ref, fault)
            result = "pass" if not fails else "FAIL: " + "; ".join(fails)
        rel = (lambda x, y: f"x{x / y:.2f}" if ref and y else "")
        static_rel = f"{a['static'] - ref['static']:+d}" if ref else ""
        loss = f"{a['loss']:.1f}" if a["loss"] is not None else "-"
        r_err = [f"{a['robot_error'].get(r, float('nan')):.3f}" for r in robot_ids]
        pending = f" ({len(a['moving_pending'])} pending)" if a["moving_pending"] else ""
        md.append(f"| {name} | {seed} | {label} | {loss} | {a['static']} | {static_rel} | {a['error']:.3f} | "
                  f"{rel(a['error'], ref['error']) if ref else ''} | {a['moving_detected']} / {a['moving_deleted']}"
                  f"{pending} | "
                  + " | ".join(r_err) +
                  f" | {rel(a['robot_error'].get(kr, 0), ref['robot_error'].get(kr, 0)) if ref else ''} | "
                  f"{a['frames_dropped']} | {result} |")
        c = {"run": name, "seed": seed, "fault": label, "loss_measured_percent": loss,
             "map_static": a["static"], "map_static_vs_lossless": static_rel, "map_error_m": f"{a['error']:.4f}",
             "map_error_vs_lossless": f"{a['error'] / ref['error']:.3f}" if ref else "",
             "moving_detected": a["moving_detected"], "moving_deleted": a["moving_deleted"],
             "moving_pending": len(a["moving_pending"]),
             "moving_ever_flagged": a["moving_ever_flagged"],
             "moving_ever_flagged_in_map": a["moving_ever_flagged_in_map"],
             "false_moving_flags": a["false_flags"], "last_map_frame": a["last_map_frame"]}
        for r in robot_ids:
            c[f"robot{r}_error_m"] = f"{a['robot_error'].get(r, float('nan')):.4f}"
            c[f"robot{r}_frames_dropped"] = a["robot_dropped"].get(r, "")
        c[f"robot{kr}_error_vs_lossless"] = (f"{a['robot_error'][kr] / ref['robot_error'][kr]:.3f}"
                                             if ref and kr in a["robot_error"] else "")
        c[f"robot{kr}_restarts"] = a["restarts"].get(kr, "")
        c["killed"] = int(a["killed"]); c["restarted"] = int(a["restarted"])
        c[f"robot{kr}_poses_after_restart"] = a["poses_after_restart"]
        c["frames_dropped"] = a["frames_dropped"]
        c["udp_packets"] = a["packets"]; c["udp_dropped"] = a["dropped"]
        c["result"] = "reference" if fault is None else ("pass" if not fails else "fail")
        c["failed_targets"] = "; ".join(fails)
        csv_rows.append(c)
    # Per fault over the seeds: means of the relative figures, rows that passed.
    by_fault = {}
    for c in csv_rows:
        if c.get("result") in ("pass", "fail"):
            by_fault.setdefault(c["fault"], []).append(c)
    if by_fault:
        md += ["", "| fault | runs | loss measured % | map static vs lossless | map error vs lossless | "
               f"moving detected / deleted | robot {args.kill_robot} error vs lossless | frames dropped | passed |",
               "|---|---|---|---|---|---|---|---|---|"]
        mean = lambda v: sum(v) / len(v)
        for fault, cs in by_fault.items():
            loss = [float(c["loss_measured_percent"]) for c in cs if c["loss_measured_percent"] != "-"]
            md.append(f"| {fault} | {len(cs)} | {f'{mean(loss):.1f}' if loss else '-'} | "
                      f"{mean([int(c['map_static_vs_lossless']) for c in cs]):+.1f} | "
                      f"x{mean([float(c['map_error_vs_lossless']) for c in cs]):.2f} | "
                      f"{sum(c['moving_detected'] for c in cs)} / {sum(c['moving_deleted'] for c in cs)} | "
                      f"x{mean([float(c[f'robot{args.kill_robot}_error_vs_lossless']) for c in cs]):.2f} | "
                      f"{mean([c['frames_dropped'] for c in cs]):.0f} | "
                      f"{sum(c['result'] == 'pass' for c in cs)} of {len(cs)} |")
    text = "\n".join(md) + "\n"
    sys.stdout.write(text)
    open(os.path.join(args.out, "summary.md"), "w").write(text)
    keys = list(dict.fromkeys(k for c in csv_rows for k in c))
    with open(os.path.join(args.out, "summary.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(csv_rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())

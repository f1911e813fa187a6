#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# System test `system_duplicate_sender`: a second live robot_node with a robot id
# that is already in use (a mis-typed --robot on a second computer, or an old process
# that was never stopped) is reported loudly, within a few frames, by both copies and
# by main_robot.
# The live team in a private namespace (100 frames at 20 Hz): main_robot, robots 1,
# 2, 3, and, once robot 2 has published its pose of frame DUP_FRAME (default 30), a
# second `robot_node --robot 2` with the same command. Then, from the recording:
#   - STATUS_MAIN says FAULT_DUPLICATE_SENDER with bit 1 (robot 2) of
#     duplicate_robots, and no other robot's bit, at a frame at most WITHIN (default
#     30: detection takes a few frames, STATUS comes once a second, 20 frames) after
#     the second process's first pose;
#   - STATUS_ROBOT_2 of both processes (two incarnations) says FAULT_DUPLICATE_SENDER;
#     robots 1 and 3 never do;
#   - main_robot's and both robot 2 processes' output say FAULT ... on stderr.
# Needs root and ip netns (exit 77 otherwise) and the Python venv (the recording is
# read with the PyPI lcm and the generated types).
#   [DUP_FRAME=30] [WITHIN=30] tests/system/duplicate_sender.sh BUILD_DIR
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
CONFIG="$ROOT/config/paper.yaml"
DUP_FRAME=${DUP_FRAME:-30}
WITHIN=${WITHIN:-30}
PY="$ROOT/.venv/bin/python"
# shellcheck source=tests/system/lib.sh
. "$ROOT/tests/system/lib.sh"

if [ "${1:-}" = "--inner" ]; then  # inside the namespace: --inner BUILD OUT
  unkeyed_inner "$2" "$3"
  robot() { "$BUILD/bin/robot_node" --config "$CONFIG" --robot "$1" > "$OUT/logs/$2.log" 2>&1 & PIDS+=($!); }
  robot 1 robot_node_1; robot 2 robot_node_2; robot 3 robot_node_3
  "$PY" "$ROOT/tests/system/lcm_check.py" --build-dir "$BUILD" wait-frame POSE_2 "$DUP_FRAME" --timeout 60 \
    > "$OUT/logs/watch.log" 2>&1 &
  WATCH=$!
  "$BUILD/bin/simulator" --config "$CONFIG" --seed 1 --rate 20 --frames 100 --wait-for-nodes 4 \
    > "$OUT/logs/simulator.log" 2>&1 &
  SIM=$!
  wait "$WATCH" || { echo "duplicate_sender: robot 2 never reached frame $DUP_FRAME"; exit 1; }
  robot 2 robot_node_2b  # the same command again, while the first one runs
  rc=0
  wait "$SIM" || { echo "duplicate_sender: simulator failed"; rc=1; }
  # Before the logger stops: it has recorded main_robot's GLOBAL_MAP of the last
  # frame, which goes out once every robot's POSE and events of that frame are in (so
  # the logger got those first: one host, datagrams in send order) and again on
  # main's timer (one lost datagram does not stall the wait).
  wait_for 30 "the recording of main_robot's GLOBAL_MAP of the last frame (99)" \
    "$PY" "$ROOT/tests/system/lcm_check.py" --build-dir "$BUILD" logged "$OUT/run.lcmlog" --frame 99 GLOBAL_MAP || rc=1
  for p in "${PIDS[@]}"; do kill -INT "$p" 2>/dev/null || true; done
  for p in "${PIDS[@]}"; do wait "$p" || { echo "duplicate_sender: process $p exited with an error"; rc=1; }; done
  PIDS=()
  exit $rc
fi

BUILD="$(cd "${1:?usage: duplicate_sender.sh BUILD_DIR}" && pwd)"
needs_netns duplicate_sender --venv
command -v lcm-logger > /dev/null || { echo "duplicate_sender: skipped (no lcm-logger)"; exit 77; }
make_out duplicate_sender
"$ROOT/tools/netns_run.sh" --port 7714 -- "$0" --inner "$BUILD" "$OUT" > "$OUT/run.txt" 2>&1 ||
  { cat "$OUT/run.txt"; tail -n 3 "$OUT"/logs/*.log; exit 1; }

rc=0
for f in main_robot robot_node_2 robot_node_2b; do
  line="$(grep -m1 "FAULT:" "$OUT/logs/$f.log" || true)"
  [ -n "$line" ] || { echo "duplicate_sender: $f said nothing about the duplicate"; tail -n 5 "$OUT/logs/$f.log"; rc=1; }
  echo "duplicate_sender: $f: $line"
done
for f in robot_node_1 robot_node_3; do
  if grep -q "FAULT:" "$OUT/logs/$f.log"; then echo "duplicate_sender: $f reported a fault"; rc=1; fi
done

"$PY" - "$BUILD" "$OUT/run.lcmlog" "$WITHIN" <<'PY' || rc=1
import sys
sys.path.insert(0, sys.argv[1] + "/lcmgen/python")
import lcm
from elaslam import node_status_t, pose_estimate_t
within = int(sys.argv[3])
DUP = node_status_t.FAULT_DUPLICATE_SENDER
incarnations = []          # robot 2's, in order of their first pose
second_first_frame = None  # the frame of the second process's first pose
main_first = None          # the first STATUS_MAIN frame that flags robot 2
main_other_bits = 0
robot_flagged = {}         # (robot, incarnation) -> flagged at least once
for ev in lcm.EventLog(sys.argv[2], "r"):
    if ev.channel == "POSE_2":
        p = pose_estimate_t.decode(ev.data)
        if p.incarnation not in incarnations:
            incarnations.append(p.incarnation)
            if len(incarnations) == 2:
                second_first_frame = p.frame
    elif ev.channel == "STATUS_MAIN":
        s = node_status_t.decode(ev.data)
        main_other_bits |= s.duplicate_robots & ~2
        if main_first is None and s.fault_flags & DUP and s.duplicate_robots & 2:
            main_first = s.frame
    elif ev.channel.startswith("STATUS_ROBOT_"):
        s = node_status_t.decode(ev.data)
        key = (s.node_id, s.incarnation)
        robot_flagged[key] = robot_flagged.get(key, False) or bool(s.fault_flags & DUP)
fails = []
if len(incarnations) != 2:
    fails.append(f"robot 2 published with {len(incarnations)} incarnations, expected 2")
if main_first is None:
    fails.append("STATUS_MAIN never flagged robot 2")
elif second_first_frame is not None and main_first - second_first_frame > within:
    fails.append(f"STATUS_MAIN flagged robot 2 at frame {main_first}, {main_first - second_first_frame} frames "
                 f"after the second process's first pose (at most {within})")
if main_other_bits:
    fails.append(f"STATUS_MAIN flagged other robots too (bits {main_other_bits:#x})")
for inc in incarnations:
    if not robot_flagged.get((2, inc)):
        fails.append(f"robot 2's process of incarnation {inc} never flagged the duplicate in its STATUS")
for (rid, inc), flagged in robot_flagged.items():
    if rid != 2 and flagged:
        fails.append(f"robot {rid} flagged a duplicate")
print(f"duplicate_sender: second robot 2 from frame {second_first_frame}; STATUS_MAIN flags it at frame "
      f"{main_first}; robot 2's STATUS flags: "
      + ", ".join(f"incarnation {inc}: {robot_flagged.get((2, inc), False)}" for inc in incarnations))
if fails:
    print("duplicate_sender: " + "; ".join(fails))
    sys.exit(1)
PY
[ "$rc" -eq 0 ] && echo "duplicate_sender: pass"
exit $rc

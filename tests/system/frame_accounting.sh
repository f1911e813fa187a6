#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# System test `system_frame_accounting`: "frames dropped" means what it says.
# A live team in a private namespace (80 frames at 20 Hz) where robot 3 starts when
# robot 1 has done frame 15 (it joins late), and robot 2 is killed (SIGKILL) after
# frame 40 and started again after frame 50. evaluate and log_info must say:
#   robot 1: every frame logged or missing from the log, none dropped or not started;
#   robot 2: no frame "not started", about 10 dropped (it was down), 1 restart;
#   robot 3: about 15 frames "not yet started", none dropped;
# and for every robot poses + not started + dropped + missing from the log = 80.
#   tests/system/frame_accounting.sh BUILD_DIR
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
CONFIG="$ROOT/config/paper.yaml"
PY="$ROOT/.venv/bin/python"
CHECK="$ROOT/tests/system/lcm_check.py"
# shellcheck source=tests/system/lib.sh
. "$ROOT/tests/system/lib.sh"

if [ "${1:-}" = "--inner" ]; then  # inside the namespace: --inner BUILD OUT
  unkeyed_inner "$2" "$3"
  robot() { "$BUILD/bin/robot_node" --config "$CONFIG" --robot "$1" >> "$OUT/logs/robot_node_$1.log" 2>&1 & }
  robot 1; PIDS+=($!)
  robot 2; R2=$!
  "$BUILD/bin/simulator" --config "$CONFIG" --frames 80 --rate 20 --wait-for-nodes 3 > "$OUT/logs/simulator.log" 2>&1 &
  SIM=$!
  "$PY" "$CHECK" --build-dir "$BUILD" wait-frame POSE_1 15 --timeout 60 > /dev/null
  robot 3; PIDS+=($!)
  "$PY" "$CHECK" --build-dir "$BUILD" wait-frame POSE_1 40 --timeout 60 > /dev/null
  kill -KILL "$R2"; wait "$R2" 2>/dev/null || true
  "$PY" "$CHECK" --build-dir "$BUILD" wait-frame POSE_1 50 --timeout 60 > /dev/null
  robot 2; PIDS+=($!)
  wait "$SIM"
  rc=0
  # Before the logger stops: it has recorded main_robot's GLOBAL_MAP of the last
  # frame, which goes out once every robot's POSE and events of that frame are in (so
  # the logger got those first: one host, datagrams in send order) and again on
  # main's timer (one lost datagram does not stall the wait).
  wait_for 30 "the recording of main_robot's GLOBAL_MAP of the last frame (79)" \
    "$PY" "$CHECK" --build-dir "$BUILD" logged "$OUT/run.lcmlog" --frame 79 GLOBAL_MAP || rc=1
  stop_pids || rc=1
  exit $rc
fi

BUILD="$(cd "${1:?usage: frame_accounting.sh BUILD_DIR}" && pwd)"
needs_netns frame_accounting --venv
make_out frame_accounting
"$ROOT/tools/netns_run.sh" --port 7705 -- "$0" --inner "$BUILD" "$OUT" || { tail -n 3 "$OUT"/logs/*.log; exit 1; }
"$BUILD/bin/evaluate" --log "$OUT/run.lcmlog" --out "$OUT/eval" > "$OUT/eval.txt"
"$BUILD/bin/log_info" --json "$OUT/run.lcmlog" > "$OUT/log_info.json"
grep -E "frames dropped|robot [0-9]:" "$OUT/eval.txt"
python3 - "$OUT/eval/metrics.json" "$OUT/log_info.json" <<'PY'
import json, sys
m, info = (json.load(open(p)) for p in sys.argv[1:3])
fails = []
robots = {r["id"]: r for r in m["robots"]}
logged = {r["robot_id"]: r for r in info["robots"]}
for rid, r in robots.items():
    total = r["frames"] + r["frames_not_started"] + r["frames_dropped"] + r["poses_missing_from_log"]
    if total != 80:
        fails.append(f"robot {rid}: {total} frames accounted for, not 80")
    l = logged[rid]  # log_info tells the same story
    for a, b in (("frames_not_started", "not_started"), ("frames_dropped", "dropped"),
                 ("poses_missing_from_log", "missing_from_log"), ("restarts", "restarts")):
        if r[a] != l[b]:
            fails.append(f"robot {rid}: evaluate {a} {r[a]}, log_info {b} {l[b]}")
def want(rid, key, lo, hi):
    if not lo <= robots[rid][key] <= hi:
        fails.append(f"robot {rid}: {key} = {robots[rid][key]}, expected {lo}..{hi}")
want(1, "frames_dropped", 0, 0); want(1, "frames_not_started", 0, 0); want(1, "restarts", 0, 0)
want(2, "frames_not_started", 0, 0); want(2, "restarts", 1, 1); want(2, "frames_dropped", 5, 15)
want(3, "frames_not_started", 12, 22); want(3, "frames_dropped", 0, 0); want(3, "restarts", 0, 0)
if m["frames_dropped"] != robots[2]["frames_dropped"]:
    fails.append(f"frames_dropped {m['frames_dropped']} is not robot 2's alone")
print("frame_accounting:", {rid: (r["frames"], r["frames_not_started"], r["frames_dropped"], r["poses_missing_from_log"],
                                 r["restarts"]) for rid, r in robots.items()}, "(logged, not started, dropped, missing, restarts)")
if fails:
    print("\n".join(fails)); sys.exit(1)
PY

# A damaged copy of the recording: 1000 random bytes between two events in the
# middle, and the file cut inside its last event. evaluate reads every whole event,
# says what it skipped, and gives the figures of the recording without its last event.
python3 - "$OUT/run.lcmlog" "$OUT/damaged.lcmlog" "$OUT/without_last.lcmlog" <<'PY'
import random, sys
data = open(sys.argv[1], "rb").read()
marker = b"\xed\xa1\xda\x01"
at = data.index(marker, len(data) // 2)   # an event boundary in the middle
last = data.rindex(marker)                # where the last event starts
junk = random.Random(7).randbytes(1000).replace(b"\xed\xa1", b"\x00\x00")
open(sys.argv[2], "wb").write(data[:at] + junk + data[at:-10])
open(sys.argv[3], "wb").write(data[:last])
PY
"$BUILD/bin/evaluate" --log "$OUT/damaged.lcmlog" --out "$OUT/eval_damaged" > "$OUT/damaged.txt"
"$BUILD/bin/evaluate" --log "$OUT/without_last.lcmlog" --out "$OUT/eval_without_last" --quiet
grep -q "damaged log: 1000 bytes between events skipped, the last event truncated" "$OUT/damaged.txt" ||
  { cat "$OUT/damaged.txt"; echo "frame_accounting: the damage was not reported"; exit 1; }
python3 - "$OUT/eval_without_last/metrics.json" "$OUT/eval_damaged/metrics.json" <<'PY'
import json, sys
want, damaged = (json.load(open(p)) for p in sys.argv[1:3])
assert damaged["log_bytes_skipped"] == 1000 and damaged["log_complete"] is False
assert want["log_bytes_skipped"] == 0 and want["log_complete"] is True
for key in ("log_bytes_skipped", "log_complete", "command_line", "source", "timing"):
    want.pop(key), damaged.pop(key)
assert damaged == want, [k for k in want if want[k] != damaged.get(k)]
print("frame_accounting: a damaged copy (1000 stray bytes, a truncated last event) gives the figures of its whole events")
PY

#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# System test `system_faults` (docs/faults.md, "Faults an operator sees"): conditions
# that used to leave every STATUS at faults=0 are flagged and said, over LCM in a
# private namespace, with the team's keys:
#   - main_robot down until both robots have said it is silent (node.main_silent_s
#     after their start) and sent a STATUS since: the robots flag FAULT_MAIN_SILENT
#     and say so; main started late: "heard again" and FAULT_PARTITION_HEALED;
#   - robot 1's state file cannot be saved (its directory does not exist):
#     FAULT_SAVE_FAILED and one "cannot save its state" line;
#   - malformed and unsigned datagrams sent to the team (raw_datagrams.py):
#     FAULT_INPUT_REFUSED in the robots' and main's STATUS.
# The flags are read from the recorded STATUS messages (verified with the roster).
# Needs root and ip netns (exit 77 otherwise) and the .venv (tools/setup.sh).
#   tests/system/faults_visible.sh BUILD_DIR
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
HERE="$ROOT/tests/system"
PY="$ROOT/.venv/bin/python"
CONFIG="$ROOT/config/paper.yaml"
FRAMES=150
# shellcheck source=tests/system/lib.sh
. "$HERE/lib.sh"
# Both robots have said that main_robot is silent (node.main_silent_s after their start).
said_silent() { grep -q "FAULT: robot 1 has not heard main_robot" "$1/robot_1.log" &&
                grep -q "FAULT: robot 2 has not heard main_robot" "$1/robot_2.log"; }

if [ "${1:-}" = "--inner" ]; then  # inside the namespace: --inner BUILD OUT KEYS
  keyed_inner "$2" "$3" "$4"
  "$B/robot_node" "${K[@]}" --key-file "$KEYS/robot_1.key" --robot 1 --state "$OUT/no/such/dir/robot1.json" \
    > "$OUT/robot_1.log" 2>&1 & PIDS+=($!)
  "$B/robot_node" "${K[@]}" --key-file "$KEYS/robot_2.key" --robot 2 > "$OUT/robot_2.log" 2>&1 & PIDS+=($!)
  python3 "$HERE/raw_datagrams.py" --rounds 1000 --period 2 > "$OUT/attacker.txt" 2>&1 &
  ATTACKER=$!
  rc=0
  "$B/simulator" "${K[@]}" --key-file "$KEYS/simulator.key" --frames $FRAMES --wait-for-nodes 2 \
    > "$OUT/simulator.log" 2>&1 &
  SIM=$!
  # The robots run without main_robot until both have said so and the recording holds
  # a STATUS of each sent after that (FAULT_MAIN_SILENT in it: main is still down).
  wait_for 60 "both robots' 'has not heard main_robot' line" said_silent "$OUT" || exit 1
  since=${EPOCHREALTIME//[.,]/}
  wait_for 10 "the recording of a STATUS of robots 1 and 2 after they said main_robot was silent" \
    "$PY" "$HERE/lcm_check.py" --build-dir "$BUILD" logged "$OUT/run.lcmlog" --since "$since" --frame 0 \
    STATUS_ROBOT_1 STATUS_ROBOT_2 || exit 1
  "$B/main_robot" "${K[@]}" --key-file "$KEYS/main.key" > "$OUT/main_robot.log" 2>&1 & PIDS+=($!)
  wait $SIM || rc=$?
  # A last STATUS of everyone, recorded after the run's last frame.
  since=${EPOCHREALTIME//[.,]/}
  wait_for 10 "the recording of a STATUS of robots 1, 2 and main_robot after the last frame" \
    "$PY" "$HERE/lcm_check.py" --build-dir "$BUILD" logged "$OUT/run.lcmlog" --since "$since" --frame 0 \
    STATUS_ROBOT_1 STATUS_ROBOT_2 STATUS_MAIN || rc=1
  kill -TERM $ATTACKER 2>/dev/null || true  # (a background job ignores SIGINT)
  for p in "${PIDS[@]}"; do kill -INT "$p" 2>/dev/null || true; done
  wait $ATTACKER || true
  for p in "${PIDS[@]}"; do wait "$p" || true; done
  PIDS=()
  exit $rc
fi

BUILD="$(cd "${1:?usage: faults_visible.sh BUILD_DIR}" && pwd)"
needs_netns faults --venv
make_out faults
fail() { echo "faults: $*"; for f in "$OUT"/*.log; do echo "== $f"; tail -n 6 "$f"; done; exit 1; }
"$BUILD/bin/keys" team "$OUT/keys" --robots 1,2 > /dev/null
"$ROOT/tools/netns_run.sh" --port 7726 -- "$0" --inner "$BUILD" "$OUT" "$OUT/keys" > "$OUT/inner.txt" 2>&1 ||
  { cat "$OUT/inner.txt"; fail "the team did not run"; }

for r in 1 2; do
  grep -q "FAULT: robot $r has not heard main_robot for" "$OUT/robot_$r.log" || fail "robot $r did not say main was silent"
  grep -q "robot $r: main_robot heard again after" "$OUT/robot_$r.log" || fail "robot $r did not say main was back"
done
[ "$(grep -c "FAULT: robot 1 cannot save its state" "$OUT/robot_1.log")" -eq 1 ] || fail "robot 1: not one 'cannot save' line"
grep -q "FAULT: [0-9]* messages refused by the transport" "$OUT/robot_2.log" || fail "robot 2 did not say it refused input"
"$PY" - "$BUILD" "$OUT/run.lcmlog" <<'PY' || fail "the STATUS flags"
import os, sys
sys.path.insert(0, os.path.join(sys.argv[1], "lcmgen", "python"))
import lcm, elaslam
T = elaslam.node_status_t
seen = {}
for ev in lcm.EventLog(sys.argv[2], "r"):
    # Only what the team signed (the attacker's datagrams are in the recording too).
    if ev.channel in ("STATUS_ROBOT_1", "STATUS_ROBOT_2", "STATUS_MAIN") and ev.data[-98:-94] == b"ELA2":
        seen[ev.channel] = seen.get(ev.channel, 0) | T.decode(ev.data).fault_flags
want = {
    "STATUS_ROBOT_1": T.FAULT_MAIN_SILENT | T.FAULT_PARTITION_HEALED | T.FAULT_SAVE_FAILED | T.FAULT_INPUT_REFUSED,
    "STATUS_ROBOT_2": T.FAULT_MAIN_SILENT | T.FAULT_PARTITION_HEALED | T.FAULT_INPUT_REFUSED,
    "STATUS_MAIN": T.FAULT_INPUT_REFUSED,
}
bad = {ch: (seen.get(ch, 0), w) for ch, w in want.items() if seen.get(ch, 0) & w != w}
print("faults: flags seen in the recorded STATUS:", {ch: hex(f) for ch, f in sorted(seen.items())})
sys.exit(1 if bad else 0)
PY
! grep -q "FAULT_SAVE_FAILED\|cannot save" "$OUT/robot_2.log" || fail "robot 2 (no --state) said a save failed"
echo "faults: main's absence, its return, a failed save and refused input are flagged and said"

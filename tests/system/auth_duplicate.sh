#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# System test `system_auth_duplicate` (docs/security.md): with the team's keys, two
# live processes that use one robot id and its key (robot_node --robot 2, twice: a
# copied computer) still both get through authentication (each its own incarnation,
# each its own replay window), so the duplicate-sender detection still sees them:
# main_robot says "FAULT: two live senders use robot id 2" and a robot node says
# another process publishes POSE_2. And a node without keys is deaf to the team: its
# messages are refused as unauthenticated (auth_unauthenticated on the keyed nodes' STATUS).
# Needs root and ip netns (exit 77 otherwise) and the .venv (tools/setup.sh).
#   tests/system/auth_duplicate.sh BUILD_DIR
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
PY="$ROOT/.venv/bin/python"
CONFIG="$ROOT/config/paper.yaml"
FRAMES=60
# shellcheck source=tests/system/lib.sh
. "$ROOT/tests/system/lib.sh"

if [ "${1:-}" = "--inner" ]; then  # inside the namespace: --inner BUILD OUT KEYS
  keyed_inner "$2" "$3" "$4"
  "$B/main_robot" "${K[@]}" --key-file "$KEYS/main.key" > "$OUT/main_robot.log" 2>&1 & PIDS+=($!)
  "$B/robot_node" "${K[@]}" --key-file "$KEYS/robot_1.key" --robot 1 > "$OUT/robot_1.log" 2>&1 & PIDS+=($!)
  "$B/robot_node" "${K[@]}" --key-file "$KEYS/robot_2.key" --robot 2 > "$OUT/robot_2a.log" 2>&1 & PIDS+=($!)
  "$B/robot_node" "${K[@]}" --key-file "$KEYS/robot_3.key" --robot 3 > "$OUT/robot_3.log" 2>&1 & PIDS+=($!)
  # A robot 3 without keys (a team member started without them).
  "$B/robot_node" --config "$CONFIG" --robot 3 > "$OUT/robot_3_unkeyed.log" 2>&1 & PIDS+=($!)
  rc=0
  "$B/simulator" "${K[@]}" --key-file "$KEYS/simulator.key" --frames $FRAMES --wait-for-nodes 4 \
    > "$OUT/simulator.log" 2>&1 &
  SIM=$!
  # The second robot 2 joins at frame 10: main_robot has followed the first, takes the
  # second for a restart, then hears the first again (main_node.cpp's detection).
  "$PY" "$ROOT/tests/system/lcm_check.py" --build-dir "$BUILD" wait-frame POSE_2 10 > /dev/null
  "$B/robot_node" "${K[@]}" --key-file "$KEYS/robot_2.key" --robot 2 > "$OUT/robot_2b.log" 2>&1 & PIDS+=($!)
  wait $SIM || rc=$?
  # Before the recorder stops: it has recorded main_robot's GLOBAL_MAP of the last
  # frame, which goes out once every robot's POSE and events of that frame are in (so
  # the recorder got those first: one host, datagrams in send order) and again on
  # main's timer (one lost datagram does not stall the wait).
  wait_for 30 "the recording of main_robot's GLOBAL_MAP of the last frame ($((FRAMES - 1)))" \
    "$PY" "$ROOT/tests/system/lcm_check.py" --build-dir "$BUILD" logged "$OUT/run.lcmlog" --frame $((FRAMES - 1)) GLOBAL_MAP ||
    rc=1
  stop_pids || true
  exit $rc
fi

BUILD="$(cd "${1:?usage: auth_duplicate.sh BUILD_DIR}" && pwd)"
needs_netns auth_duplicate --venv
make_out auth_duplicate
"$BUILD/bin/keys" team "$OUT/keys" --robots 1,2,3 > /dev/null
fail() { echo "auth_duplicate: $*"; for f in "$OUT"/*.log; do echo "== $f"; tail -n 4 "$f"; done; exit 1; }
"$ROOT/tools/netns_run.sh" --port 7723 -- "$0" --inner "$BUILD" "$OUT" "$OUT/keys" > "$OUT/inner.txt" 2>&1 ||
  { cat "$OUT/inner.txt"; fail "the team did not run"; }
grep -h "FAULT: two live senders use robot id 2" "$OUT/main_robot.log" | head -n 1 ||
  fail "main_robot did not see two live senders with robot id 2"
grep -h "FAULT: another process publishes POSE_2" "$OUT/robot_2a.log" "$OUT/robot_2b.log" | head -n 1 ||
  fail "neither robot 2 saw the other"
grep -q "^robot_node 2: frames=$FRAMES " "$OUT/robot_2a.log" || fail "robot 2 did not process the $FRAMES frames"
grep -q "^robot_node 2: frames=" "$OUT/robot_2b.log" || fail "the second robot 2 processed nothing"
# The unkeyed robot 3 (authentication off: it reads the signed SENSOR_3 and works)
# is refused by every keyed node: main_robot (its events and snapshots) and the keyed
# robot 3 (its POSE_3, so no false duplicate-sender alarm there).
! grep -q "FAULT: another process" "$OUT/robot_3.log" || fail "the keyed robot 3 took the unkeyed one's POSE_3 for its own"
"$PY" - "$BUILD" "$OUT/run.lcmlog" <<'PY' || fail "the keyed nodes did not count the unkeyed node's messages"
import os, sys
sys.path.insert(0, os.path.join(sys.argv[1], "lcmgen", "python"))
import lcm, elaslam
best = {}
for ev in lcm.EventLog(sys.argv[2], "r"):
    if ev.channel in ("STATUS_MAIN", "STATUS_ROBOT_3") and ev.data[-98:-94] == b"ELA2":
        m = elaslam.node_status_t.decode(ev.data)
        best[ev.channel] = max(best.get(ev.channel, 0), m.auth_unauthenticated)
print("auth_duplicate: auth_unauthenticated (the unkeyed robot 3's messages):", best)
sys.exit(0 if best.get("STATUS_MAIN", 0) > 0 and best.get("STATUS_ROBOT_3", 0) > 0 else 1)
PY
echo "auth_duplicate: ok"

#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# A short live team from an unpacked package root (`dpkg -x` of the five .debs):
# elaslam-main-robot, one elaslam-robot-node per robot of the scenario and
# elaslam-simulator --frames 30, as separate processes over LCM. Run it inside a
# private network namespace (tools/netns_run.sh, which sets LCM_DEFAULT_URL).
# Checks that every process exits cleanly, that every robot node processed the 30
# frames, and that main_robot saved its state. The messages are signed with a team's
# keys made by the root's elaslam-keys (as the package's postinst does).
#   team_from_root.sh ROOT OUT_DIR
set -euo pipefail
ROOT="$(cd "${1:?usage: team_from_root.sh ROOT OUT_DIR}" && pwd)"
OUT="${2:?OUT_DIR}"
FRAMES=30
B="$ROOT/usr/bin"
mkdir -p "$OUT"
export ELASLAM_CONFIG="$ROOT/etc/elaslam/elaslam.yaml"
[ -n "${LCM_DEFAULT_URL:-}" ] || { echo "team_from_root: run me under tools/netns_run.sh" >&2; exit 2; }

PIDS=()
cleanup() {
  local p
  for p in "${PIDS[@]}"; do kill -KILL "$p" 2>/dev/null || true; done
}
trap cleanup EXIT
fail() { echo "FAIL: team from the package root: $*" >&2; for f in "$OUT"/*.log; do echo "== $f"; cat "$f"; done >&2; exit 1; }

read -r -a ROBOTS <<< "$("$B/elaslam-simulator" --list-robots)"
[ "${#ROBOTS[@]}" -ge 1 ] || fail "the scenario lists no robots"

# The installed config names /etc/elaslam/keys/{sender}.key and the roster
# /etc/elaslam/team.yaml (authentication on by default): a team's keys for this root,
# made with the package's own tool, each process given its own key and the roster.
"$B/elaslam-keys" team "$OUT/keys" --robots "$(IFS=,; echo "${ROBOTS[*]}")" > /dev/null || fail "elaslam-keys team"
KEY=(--roster "$OUT/keys/team.yaml")

"$B/elaslam-main-robot" --state "$OUT/global_map.json" "${KEY[@]}" --key-file "$OUT/keys/main.key" > "$OUT/main.log" 2>&1 &
MAIN=$!; PIDS+=("$MAIN")
declare -A NODE
for r in "${ROBOTS[@]}"; do
  "$B/elaslam-robot-node" --robot "$r" "${KEY[@]}" --key-file "$OUT/keys/robot_$r.key" > "$OUT/robot_$r.log" 2>&1 &
  NODE[$r]=$!; PIDS+=("${NODE[$r]}")
done
# The simulator starts once every node announced itself (robots + main).
rc=0
timeout 60 "$B/elaslam-simulator" --frames "$FRAMES" --wait-for-nodes $(( ${#ROBOTS[@]} + 1 )) "${KEY[@]}" \
  --key-file "$OUT/keys/simulator.key" \
  > "$OUT/simulator.log" 2>&1 || rc=$?
[ "$rc" -eq 0 ] || fail "elaslam-simulator exit $rc"
# Let the last frame through, then stop the nodes as systemd would (SIGTERM) and
# as a terminal would (SIGINT).
sleep 1
for r in "${ROBOTS[@]}"; do kill -INT "${NODE[$r]}"; done
kill -TERM "$MAIN"
for r in "${ROBOTS[@]}"; do
  rc=0; wait "${NODE[$r]}" || rc=$?
  [ "$rc" -eq 0 ] || fail "elaslam-robot-node --robot $r exit $rc"
  grep -q "^robot_node $r: frames=$FRAMES " "$OUT/robot_$r.log" || fail "robot $r did not process $FRAMES frames"
  grep -q "config $ELASLAM_CONFIG" "$OUT/robot_$r.log" || fail "robot $r did not read $ELASLAM_CONFIG"
  grep -q "authentication on: .*signing as robot_$r" "$OUT/robot_$r.log" || fail "robot $r did not sign"
done
rc=0; wait "$MAIN" || rc=$?
[ "$rc" -eq 0 ] || fail "elaslam-main-robot exit $rc"
PIDS=()
python3 - "$OUT/global_map.json" <<'PY' || fail "main_robot's state"
import json, sys
j = json.load(open(sys.argv[1]))
assert isinstance(j, dict) and j, "empty state"
PY
echo "-- live team from the package root: ${#ROBOTS[@]} robots x $FRAMES frames, main_robot state saved, all exited 0"
grep -h "^robot_node [0-9]*: frames=" "$OUT"/robot_*.log | cut -c1-100

#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# System test (system_main_restart): killing main_robot (SIGKILL) mid-run and
# restarting it ends with the same global map as an uninterrupted run.
#   1. reference: the live team, uninterrupted (tools/run_team.sh in a namespace);
#   2. twice more, each in its own namespace: the same team, but when robot 1 has
#      published the pose of frame KILL_FRAME (40 % of the run) main_robot gets
#      SIGKILL and is started again:
#      - with its --state file (saved at most once a second, so up to a second
#        stale), started again when robot 1 has published the pose of frame
#        KILL_FRAME + DOWN_FRAMES (events and notices of those frames lost);
#      - without a state file (an empty map), at once (as a supervisor would). An
#        empty main_robot cannot tell a robot's fresh "moving" from a stale one (a
#        robot lists a landmark as moving until it sees it again, also after another
#        robot took it back; snapshots carry no frame per moving id), so it trusts a
#        robot's static holding; a MOVING lost while it was down would then be
#        missed: README.md;
#      main_robot rebuilds from the robots' periodic LMAP_SNAPSHOT and the events
#      that follow;
#   3. (a) the last GLOBAL_MAP equals that of a main_robot that was never down and
#      got the same robot output (the run's own LMAP_EVENTS / LMAP_SNAPSHOT / POSE,
#      replayed): same static and moving ids, positions within 1e-6 m;
#      (b) against the uninterrupted live run: where every robot's poses are the same
#      in both runs, the same ids and positions within TOL metres; robots that got
#      different notices (lost while main_robot was down, or notice timing) may
#      differ, which is reported; every robot has a pose for every frame.
# Exit 77 (skip) without root / ip netns / the Python venv.
# Every wait is for a condition with a deadline (tests/system/wait_for.sh): a frame's
# POSE seen live, the recording holding the last frame's messages before the
# recorder stops; a deadline passed fails naming what did not happen.
#   [KILL_FRAME=60] [DOWN_FRAMES=10] tests/system/main_restart.sh BUILD_DIR [scenario args...]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
HERE="$ROOT/tests/system"
CONFIG="$ROOT/config/paper.yaml"
PY="$ROOT/.venv/bin/python"
KILL_FRAME=${KILL_FRAME:-60}   # of 150
DOWN_FRAMES=${DOWN_FRAMES:-10}  # main_robot down while the team does this many frames (1 s at 10 Hz)
TOL=0.05        # [m]
# shellcheck source=tests/system/lib.sh
. "$HERE/lib.sh"
# The run's last frame: --frames N among the scenario arguments, else the config's.
last_frame() {
  local n=""
  while [ $# -gt 0 ]; do [ "$1" = --frames ] && n="$2"; shift; done
  [ -n "$n" ] || n=$(awk '/^scenario:/ {s = 1; next} /^[^ #]/ {s = 0} s && $1 == "frames:" {print $2; exit}' "$CONFIG")
  echo $((n - 1))
}

# --- step 2, inside a namespace: main_restart.sh --inner BUILD OUT state|nostate ARGS...
if [ "${1:-}" = "--inner" ]; then
  BUILD="$2" OUT="$3" VARIANT="$4"
  shift 4
  ROBOTS=($("$BUILD/bin/simulator" --config "$CONFIG" --list-robots))
  LAST=$(last_frame "$@")
  mkdir -p "$OUT/logs"
  PIDS=()
  MAIN=""
  trap 'for p in "${PIDS[@]}" $MAIN; do kill -KILL "$p" 2>/dev/null || true; done' EXIT
  STATE=(--state "$OUT/main_state.json")
  start_main() {
    "$BUILD/bin/main_robot" --config "$CONFIG" "${STATE[@]}" >> "$OUT/logs/main_robot.log" 2>&1 &
    MAIN=$!
  }
  lcm-logger -f -q "$OUT/run.lcmlog" > "$OUT/logs/logger.log" 2>&1 & PIDS+=($!)
  start_main
  for r in "${ROBOTS[@]}"; do
    "$BUILD/bin/robot_node" --config "$CONFIG" --robot "$r" > "$OUT/logs/robot_node_$r.log" 2>&1 & PIDS+=($!)
  done
  "$BUILD/bin/simulator" --config "$CONFIG" --wait-for-nodes $((${#ROBOTS[@]} + 1)) "$@" \
    > "$OUT/logs/simulator.log" 2>&1 &
  SIM=$!
  "$PY" "$HERE/lcm_check.py" --build-dir "$BUILD" wait-frame "POSE_${ROBOTS[0]}" "$KILL_FRAME" --timeout 60 > /dev/null
  kill -KILL "$MAIN"
  wait "$MAIN" 2>/dev/null || true
  echo "main_restart: main_robot killed (SIGKILL) after frame $KILL_FRAME; $([ "$VARIANT" = nostate ] && echo "restarted at once" || echo "down for $DOWN_FRAMES frames")"
  if [ "$VARIANT" = nostate ]; then
    rm -f "$OUT/main_state.json"
    STATE=()
  else
    "$PY" "$HERE/lcm_check.py" --build-dir "$BUILD" wait-frame "POSE_${ROBOTS[0]}" $((KILL_FRAME + DOWN_FRAMES)) \
      --timeout 60 > /dev/null || { echo "main_restart: FAIL robot ${ROBOTS[0]} did not reach frame $((KILL_FRAME + DOWN_FRAMES)) while main_robot was down"; exit 1; }
  fi
  start_main
  echo "main_robot restarted ($VARIANT)" >> "$OUT/logs/main_robot.log"
  rc=0
  wait "$SIM" || { echo "main_restart: simulator failed"; tail -n 5 "$OUT/logs/simulator.log"; rc=1; }
  # Before the recorder stops: it has recorded main_robot's GLOBAL_MAP of the last
  # frame. main_robot sends it once every robot's POSE and events of that frame are
  # in, so the recorder got those before it (one host: datagrams in send order); its
  # timer sends the map again, so one lost datagram does not stall the wait.
  wait_for 30 "the recording of main_robot's GLOBAL_MAP of the last frame ($LAST)" \
    "$PY" "$HERE/lcm_check.py" --build-dir "$BUILD" logged "$OUT/run.lcmlog" --frame "$LAST" GLOBAL_MAP || rc=1
  for p in $MAIN "${PIDS[@]}"; do kill -INT "$p" 2>/dev/null || true; done
  for p in $MAIN "${PIDS[@]}"; do wait "$p" || { echo "main_restart: process $p exited with an error"; rc=1; }; done
  PIDS=(); MAIN=""
  grep -h "resumed\|restarted\|events=" "$OUT/logs/main_robot.log" || true
  exit $rc
fi

# --- inside a namespace: main_restart.sh --main-replay BUILD LOG OUT LAST
# A fresh main_robot, never interrupted, gets the robots' LMAP_EVENTS, LMAP_SNAPSHOT
# and POSE_<r> of a recorded run, in their recorded order (4x speed).
if [ "${1:-}" = "--main-replay" ]; then
  BUILD="$2" LOG="$3" OUT="$4" LAST="$5"
  mkdir -p "$OUT/logs"
  kill_pids_at_exit
  lcm-logger -f -q -c 'GLOBAL_MAP' "$OUT/run.lcmlog" > "$OUT/logs/logger.log" 2>&1 & PIDS+=($!)
  "$BUILD/bin/main_robot" --config "$CONFIG" > "$OUT/logs/main_robot.log" 2>&1 & PIDS+=($!)
  "$PY" "$HERE/lcm_check.py" --build-dir "$BUILD" wait-nodes 1 --timeout 20
  # The recorder listens: it has recorded main_robot's map (its timer sends one).
  wait_for 20 "the recording of main_robot's first GLOBAL_MAP" \
    "$PY" "$HERE/lcm_check.py" --build-dir "$BUILD" logged "$OUT/run.lcmlog" GLOBAL_MAP || exit 1
  lcm-logplayer -s 4 -e '^(LMAP_EVENTS?|LMAP_SNAPSHOT|POSE_[0-9]+)$' "$LOG" > "$OUT/logs/logplayer.log" 2>&1
  rc=0
  wait_for 30 "the recording of main_robot's GLOBAL_MAP of the last frame ($LAST)" \
    "$PY" "$HERE/lcm_check.py" --build-dir "$BUILD" logged "$OUT/run.lcmlog" --frame "$LAST" GLOBAL_MAP || rc=1
  stop_pids || rc=1
  tail -n 1 "$OUT/logs/main_robot.log"
  exit $rc
fi

BUILD="$(cd "${1:?usage: main_restart.sh BUILD_DIR [scenario args]}" && pwd)"
shift
ARGS=("$@")
[ ${#ARGS[@]} -gt 0 ] || ARGS=(--dynamism 50 --speed 0.5 --seed 3)
needs_netns main_restart --venv
make_out main_restart
ROBOTS=($("$BUILD/bin/simulator" --config "$CONFIG" --list-robots))
FRAMES=$(($(last_frame "${ARGS[@]}") + 1))

"$ROOT/tools/netns_run.sh" --port 7696 -- "$ROOT/tools/run_team.sh" --inside --build-dir "$BUILD" \
  --out "$OUT/ref" "${ARGS[@]}" > "$OUT/ref.txt" 2>&1 || { cat "$OUT/ref.txt"; exit 1; }
echo "main_restart: uninterrupted reference recorded"
rc=0
port=7697
for variant in state nostate; do
  echo "--- restart, $( [ $variant = state ] && echo with || echo without ) the state file"
  if ! "$ROOT/tools/netns_run.sh" --port $port -- "$0" --inner "$BUILD" "$OUT/$variant" "$variant" "${ARGS[@]}" \
      > "$OUT/$variant.txt" 2>&1; then
    cat "$OUT/$variant.txt"; rc=1; port=$((port + 1)); continue
  fi
  cat "$OUT/$variant.txt"
  # (a) Against a main_robot that was never down, fed the same robot output: this
  # isolates main_robot's recovery from what the robots did differently (they got
  # no notices while main_robot was down). Same ids, positions within 1e-6 m.
  "$ROOT/tools/netns_run.sh" --port $port -- "$0" --main-replay "$BUILD" "$OUT/$variant/run.lcmlog" \
    "$OUT/$variant.main" "$((FRAMES - 1))" > "$OUT/$variant.main.txt" 2>&1 || { cat "$OUT/$variant.main.txt"; rc=1; continue; }
  echo -n "vs the same robot output into a main_robot never down: "
  "$PY" "$HERE/lcm_check.py" --build-dir "$BUILD" compare-maps "$OUT/$variant.main/run.lcmlog" \
    "$OUT/$variant/run.lcmlog" --tol 1e-6 || rc=1
  # (b) Against the uninterrupted live run. Every frame has a pose (the robots do not
  # depend on main_robot); where the robots' poses are the same in both runs, so
  # must the maps be (within TOL); where a robot's poses differ, its map may too
  # (notices lost while main_robot was down, or notice timing: README.md).
  poses=0
  "$PY" "$HERE/lcm_check.py" --build-dir "$BUILD" compare-poses "$OUT/ref/run.lcmlog" "$OUT/$variant/run.lcmlog" \
    --robots "${ROBOTS[@]}" --frames "$FRAMES" --tol 1e-9 > "$OUT/$variant.poses.txt" || poses=$?
  if grep -q "frames without a pose" "$OUT/$variant.poses.txt"; then cat "$OUT/$variant.poses.txt"; rc=1; fi
  echo -n "vs the uninterrupted live run: "
  if ! "$PY" "$HERE/lcm_check.py" --build-dir "$BUILD" compare-maps "$OUT/ref/run.lcmlog" "$OUT/$variant/run.lcmlog" \
      --tol "$TOL"; then
    if [ "$poses" -eq 0 ]; then
      echo "main_restart: the robots' poses are the same as uninterrupted, the map is not"; rc=1
    else
      echo "main_restart: (not a failure) the robots themselves diverged from the uninterrupted run:"
      grep "differ" "$OUT/$variant.poses.txt" | head -n 3
    fi
  fi
  port=$((port + 1))
done
exit $rc

# SPDX-License-Identifier: Apache-2.0
# Sourced by the system tests (tests/system/*.sh) after they set ROOT and PY: the
# preamble and the process handling they share, and wait_for (wait_for.sh).
#
#   needs_netns NAME [--venv]  exit 77 (ctest: skipped), saying why, unless this is
#                              root with `ip netns`, and with --venv the project's
#                              .venv (tools/setup.sh makes it) is there
#   make_out NAME              OUT: a fresh folder, removed at exit unless KEEP_OUT
#                              is set (then its path is printed)
#   kill_pids_at_exit          PIDS=(), and every process put in PIDS is killed at exit
#   stop_pids                  SIGINT to every process in PIDS, then wait for each;
#                              returns 1 when one exited with an error; PIDS=()
#   keyed_inner BUILD OUT KEYS inside the namespace of a team with keys (keys team
#                              KEYS): sets BUILD, OUT, KEYS, B (BUILD/bin) and K (the
#                              options --config CONFIG --roster KEYS/team.yaml), PIDS as
#                              kill_pids_at_exit, and starts the recorder (record:
#                              OUT/run.lcmlog, its output in OUT/logger.log) into PIDS
#   unkeyed_inner BUILD OUT    inside the namespace of a team without keys: sets BUILD
#                              and OUT, makes OUT/logs, PIDS as kill_pids_at_exit, and
#                              starts lcm-logger (OUT/run.lcmlog) and main_robot
#                              (--config CONFIG) into PIDS, their output in OUT/logs/
#   run_team_attacked LOG CMD... -- TEAM_ARGS...
#                              inside a namespace: the attacking process CMD in the
#                              background (its output in LOG) while tools/run_team.sh
#                              --inside TEAM_ARGS runs; then CMD is stopped (SIGTERM);
#                              exits with run_team.sh's status
#   compare_attacked NAME      the recordings OUT/ref (unattacked) and OUT/attacked of
#                              ROBOTS over FRAMES frames: the same poses frame by frame
#                              and the same final global map (the script's check:
#                              lcm_check.py), or a difference that notice timing
#                              explains (noted); fail otherwise. Sets poses (the
#                              exit status of compare-poses)

# shellcheck source=tests/system/wait_for.sh
. "$(dirname "${BASH_SOURCE[0]}")/wait_for.sh"

needs_netns() {
  local name="$1"
  [ "$(id -u)" -eq 0 ] || { echo "$name: skipped (needs root for network namespaces)"; exit 77; }
  ip netns list >/dev/null 2>&1 || { echo "$name: skipped (no ip netns)"; exit 77; }
  if [ "${2:-}" = "--venv" ] && [ ! -x "$PY" ]; then
    echo "$name: skipped (no .venv with the Python lcm; tools/setup.sh makes it)"
    exit 77
  fi
}

make_out() {
  OUT="$(mktemp -d)"
  if [ -n "${KEEP_OUT:-}" ]; then
    echo "$1: output in $OUT"
  else
    trap 'rm -rf "$OUT"' EXIT
  fi
}

kill_pids_at_exit() {
  PIDS=()
  trap 'for p in "${PIDS[@]}"; do kill -KILL "$p" 2>/dev/null || true; done' EXIT
}

keyed_inner() {
  BUILD="$1" OUT="$2" KEYS="$3"
  B="$BUILD/bin"
  kill_pids_at_exit
  K=(--config "$CONFIG" --roster "$KEYS/team.yaml")
  "$B/record" -f -q "$OUT/run.lcmlog" > "$OUT/logger.log" 2>&1 & PIDS+=($!)
}

unkeyed_inner() {
  BUILD="$1" OUT="$2"
  mkdir -p "$OUT/logs"
  kill_pids_at_exit
  lcm-logger -f -q "$OUT/run.lcmlog" > "$OUT/logs/logger.log" 2>&1 & PIDS+=($!)
  "$BUILD/bin/main_robot" --config "$CONFIG" > "$OUT/logs/main_robot.log" 2>&1 & PIDS+=($!)
}

run_team_attacked() {
  local log="$1" attacker=() rc=0
  shift
  while [ "$1" != "--" ]; do attacker+=("$1"); shift; done
  shift
  "${attacker[@]}" > "$log" 2>&1 &
  ATTACKER=$!
  trap 'kill -TERM $ATTACKER 2>/dev/null || true' EXIT
  "$ROOT/tools/run_team.sh" --inside "$@" < /dev/null || rc=$?
  kill -TERM $ATTACKER 2>/dev/null || true
  wait $ATTACKER || true
  trap - EXIT
  exit $rc
}

compare_attacked() {
  local name="$1"
  poses=0
  check compare-poses "$OUT/ref/run.lcmlog" "$OUT/attacked/run.lcmlog" --robots "${ROBOTS[@]}" --frames "$FRAMES" \
    --tol 1e-9 --allow-missing 5 || poses=$?
  case $poses in
    0) echo "$name: the attacked team's poses are the unattacked team's, frame by frame" ;;
    3) echo "$name: (not a failure) notice timing differed between the two live runs" ;;
    *) fail "the attacked team's poses differ from the unattacked team's" ;;
  esac
  echo -n "$name: final global map, attacked vs unattacked: "
  if ! check compare-maps "$OUT/ref/run.lcmlog" "$OUT/attacked/run.lcmlog" --tol 1e-6; then
    [ "$poses" -ne 0 ] || fail "the same poses, but the attacked team's map differs"
    echo "$name: (not a failure) the robots' inputs differed by notice timing"
  fi
}

stop_pids() {
  local p rc=0
  for p in "${PIDS[@]}"; do kill -INT "$p" 2>/dev/null || true; done
  for p in "${PIDS[@]}"; do wait "$p" || rc=1; done
  PIDS=()
  return $rc
}

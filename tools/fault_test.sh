#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Fault injection against the lossless run: the live team (tools/run_team.sh --hosts,
# one network namespace per process) with packet loss and with a robot killed and
# restarted, each beside the lossless run of the same seed, and a table of what the
# faults cost (docs/faults.md).
#
#   tools/fault_test.sh [--seeds "1 2 3"] [--losses "5 20 30"] [--frames N]
#                       [--dynamism P] [--speed V] [--kill-robot R] [--kill-at-frame F]
#                       [--restart-after S] [--no-kill] [--sensor-losses "30"] [--out DIR] [--port P]
#                       [--build-dir DIR] [--config FILE]
#
# - Per seed (default 1 2 3): the lossless run, one run per loss (default 5, 20 and
#   30 %: run_team.sh --loss, the radio's loss: SENSOR frames arrive, as from a
#   robot's own drivers), one run per --sensor-losses value (default 30; "" for
#   none: run_team.sh --loss P --loss-scope all, the robots' SENSOR frames lost too,
#   named seed<S>_loss<P>all) and one run with robot R (default 2) killed (SIGKILL)
#   when it has published its pose of frame F (default 60) and restarted S seconds
#   later (default 1.0; -1 never), with --robot-state when robot_node accepts
#   --state (probed: robot_node --help). --no-kill: no kill run. All with
#   --dynamism 50 --speed 0.5 --frames 150 (the defaults here) --no-progress
#   --no-baseline, each into DIR/<name>/ (default DIR: runs/fault; names
#   seed<S>_lossless, seed<S>_loss<P>, seed<S>_kill<R>), run_team.sh's output in
#   DIR/<name>/run_team.txt.
# - Then the table (tools/fault_summary.py): markdown on stdout and DIR/summary.md,
#   CSV DIR/summary.csv. Per run: the measured loss (nftables counters), the final
#   global map's static landmarks and its landmark error (metrics.json
#   final_map.static, landmark_error.mean_euclidean), both relative to the lossless
#   run of the seed, the truly moving landmarks that robots reported MOVING
#   (LMAP_EVENT(S)) and how many of them are absent from the last GLOBAL_MAP's static
#   landmarks, per-robot mean pose error, frames dropped, and pass/fail against the
#   targets: static landmarks within 2 of the lossless run's, error within 1.2x,
#   every moving landmark the robots detected deleted from the map; for the kill run
#   also robot R's mean error within 1.5x of the lossless run's.
# - --port P: LCM port of the first run, +1 per run (default 7711). --build-dir DIR:
#   the programs of DIR as they are (no set-up, no build: tests); without it, the
#   set-up and build happen once (tools/setup.sh, cmake --build build).
# - Needs root (network namespaces) and nft (Debian nftables). Ctrl-C stops the run
#   in progress (run_team.sh removes its namespaces and nftables) and exits 130.
# Exit status: 0 every run ran (the table says pass/fail per row), 1 a run failed
# to run, 2 bad arguments, 130 interrupted.
set -euo pipefail
ROOT="$(cd "$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")/.." && pwd)"
SEEDS="1 2 3"
LOSSES="5 20 30"
SENSOR_LOSSES="30"
FRAMES=150
DYNAMISM=50
SPEED=0.5
KILL_ROBOT=2
KILL_FRAME=60
RESTART_AFTER=1.0
KILL=1
OUT="$ROOT/runs/fault"
PORT=7711
BUILD_DIR=""
CONFIG=""

usage() { sed -n '3,/^set -e/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit "${1:-0}"; }
die() { echo "fault_test.sh: $*" >&2; exit 2; }
ints() {  # ints NAME LIST: a list of non-negative integers (spaces or commas)
  local v; for v in ${2//,/ }; do [[ "$v" =~ ^[0-9]+$ ]] || die "$1 takes integers, got '$v'"; done
  [ -n "${2//[ ,]/}" ] || die "$1 needs at least one value"
}
num() {  # num VALUE LO HI: VALUE is a number in [LO, HI]
  [[ "$1" =~ ^[0-9]+([.][0-9]*)?$|^[.][0-9]+$ ]] &&
    awk -v v="$1" -v lo="$2" -v hi="$3" 'BEGIN { exit !(v + 0 >= lo + 0 && v + 0 <= hi + 0) }'
}
while [ $# -gt 0 ]; do
  case "$1" in
    --seeds|--losses|--sensor-losses|--frames|--dynamism|--speed|--kill-robot|--kill-at-frame|--restart-after|--out|--port|--build-dir|--config)
      [ $# -ge 2 ] || die "$1 needs a value (see --help)" ;;&
    --seeds) ints --seeds "$2"; SEEDS="${2//,/ }"; shift 2 ;;
    --losses) for v in ${2//,/ }; do
                if ! [[ "$v" =~ ^[0-9]+([.][0-9])?$ ]] || ! num "$v" 0 100; then
                  die "--losses: percentages in [0, 100] with at most one decimal, got '$v'"
                fi
              done
              LOSSES="${2//,/ }"; shift 2 ;;
    --sensor-losses) for v in ${2//,/ }; do
                       if ! [[ "$v" =~ ^[0-9]+([.][0-9])?$ ]] || ! num "$v" 0 100; then
                         die "--sensor-losses: percentages in [0, 100] with at most one decimal, got '$v'"
                       fi
                     done
                     SENSOR_LOSSES="${2//,/ }"; shift 2 ;;
    --frames) ints --frames "$2"; FRAMES="$2"; shift 2 ;;
    --dynamism) num "$2" 0 100 || die "--dynamism must be in [0, 100], got '$2'"; DYNAMISM="$2"; shift 2 ;;
    --speed) num "$2" 0 100 || die "--speed must be in [0, 100], got '$2'"; SPEED="$2"; shift 2 ;;
    --kill-robot) ints --kill-robot "$2"; KILL_ROBOT="$2"; shift 2 ;;
    --kill-at-frame) ints --kill-at-frame "$2"; KILL_FRAME="$2"; shift 2 ;;
    --restart-after) [ "$2" = -1 ] || num "$2" 0 3600 || die "--restart-after must be -1 or in [0, 3600], got '$2'"
                     RESTART_AFTER="$2"; shift 2 ;;
    --no-kill) KILL=0; shift ;;
    --out) OUT="$2"; shift 2 ;;
    --port) ints --port "$2"; PORT="$2"; shift 2 ;;
    --build-dir) BUILD_DIR="$2"; shift 2 ;;
    --config) CONFIG="$2"; shift 2 ;;
    -h|--help) usage 0 ;;
    *) echo "fault_test.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[ "$KILL" -eq 0 ] || [ "$KILL_FRAME" -lt "$FRAMES" ] || die "--kill-at-frame must be below --frames ($FRAMES)"
[ "$(id -u)" -eq 0 ] || die "needs root (network namespaces, nftables)"
command -v nft >/dev/null || die "needs nft (Debian package nftables)"
[ -z "$CONFIG" ] || [ -f "$CONFIG" ] || die "no such config file: $CONFIG"

if [ -z "$BUILD_DIR" ]; then  # set-up and build once, then every run uses the build as it is
  BUILD_DIR="$ROOT/build"
  "$ROOT/tools/setup.sh" --build-dir "$BUILD_DIR" >&2
  cmake --build "$BUILD_DIR" --target simulator robot_node main_robot evaluate monitor elaslam_lcmtypes_py \
    -j "$(nproc)" >/dev/null || { echo "fault_test.sh: the build failed" >&2; exit 1; }
fi
[ -x "$BUILD_DIR/bin/robot_node" ] || die "no programs in $BUILD_DIR/bin"
BUILD_DIR="$(cd "$BUILD_DIR" && pwd)"
PY="$ROOT/.venv/bin/python"
[ -x "$PY" ] || die "no Python venv (.venv): tools/setup.sh makes it"
mkdir -p "$OUT" || die "cannot create $OUT"
OUT="$(cd "$OUT" && pwd)"

STATE_ARGS=()
if "$BUILD_DIR/bin/robot_node" --help 2>/dev/null | grep -q -- '--state'; then STATE_ARGS=(--robot-state); fi

CHILD=""
interrupted() {
  trap - INT TERM
  if [ -n "$CHILD" ]; then kill -TERM "$CHILD" 2>/dev/null || true; wait "$CHILD" 2>/dev/null || true; fi
  echo -e "\nfault_test.sh: interrupted (runs so far in $OUT)" >&2
  exit 130
}
trap interrupted INT TERM

COMMON=(--inside --hosts --build-dir "$BUILD_DIR" --dynamism "$DYNAMISM" --speed "$SPEED" --frames "$FRAMES"
        --no-progress --no-baseline ${CONFIG:+--config "$CONFIG"})
failed=0
# run NAME ARGS...: one run_team.sh run into OUT/NAME (in the background: Ctrl-C reaches us).
run() {
  local name="$1" rc=0 t0=$SECONDS; shift
  rm -rf "${OUT:?}/$name"; mkdir -p "$OUT/$name"
  echo "fault_test.sh: $name ($*)" >&2
  ELASLAM_RUN_TEAM_NESTED=1 "$ROOT/tools/run_team.sh" "${COMMON[@]}" --port "$PORT" --out "$OUT/$name" "$@" \
    >"$OUT/$name/run_team.txt" 2>&1 &
  CHILD=$!
  wait "$CHILD" || rc=$?
  CHILD=""
  PORT=$((PORT + 1))
  [ "$rc" -ne 130 ] || interrupted
  if [ "$rc" -ne 0 ] || [ ! -f "$OUT/$name/metrics.json" ]; then
    echo "fault_test.sh: $name failed to run (exit status $rc; $OUT/$name/run_team.txt):" >&2
    tail -n 5 "$OUT/$name/run_team.txt" | sed 's/^/  /' >&2
    failed=1
  else
    echo "fault_test.sh: $name done in $((SECONDS - t0)) s" >&2
  fi
}

NAMES=()
for s in $SEEDS; do
  run "seed${s}_lossless" --seed "$s"; NAMES+=("seed${s}_lossless")
  for p in $LOSSES; do run "seed${s}_loss$p" --seed "$s" --loss "$p"; NAMES+=("seed${s}_loss$p"); done
  for p in $SENSOR_LOSSES; do
    run "seed${s}_loss${p}all" --seed "$s" --loss "$p" --loss-scope all; NAMES+=("seed${s}_loss${p}all")
  done
  if [ "$KILL" -eq 1 ]; then
    run "seed${s}_kill$KILL_ROBOT" --seed "$s" --kill-robot "$KILL_ROBOT" --kill-at-frame "$KILL_FRAME" \
      --restart-after "$RESTART_AFTER" "${STATE_ARGS[@]}"
    NAMES+=("seed${s}_kill$KILL_ROBOT")
  fi
done

"$PY" "$ROOT/tools/fault_summary.py" --build-dir "$BUILD_DIR" --out "$OUT" --kill-robot "$KILL_ROBOT" "${NAMES[@]}" ||
  { echo "fault_test.sh: the summary failed" >&2; exit 1; }
[ "$failed" -eq 0 ] || { echo "fault_test.sh: at least one run failed to run (see above)" >&2; exit 1; }

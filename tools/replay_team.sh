#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Replay a recorded log into a fresh team, live over LCM, optionally with the viewer:
# a run's run.lcmlog (tools/run_team.sh) or a real recording made by mrclam_import.
#
#   tools/replay_team.sh LOG [--config FILE] [--mode M] [--speed S] [--view [PORT]]
#                            [--out DIR] [--port P] [--build-dir DIR] [--robots "1 2 3"]
#                            [--channel-groups]
#
# - Starts the recorder (record: DIR/run.lcmlog), main_robot and one robot_node per robot of
#   the log (its SENSOR_<r> channels, or --robots), waits until each has announced
#   itself, then plays the log's inputs only (SENSOR_<r>, GROUND_TRUTH, RUN_INFO)
#   with lcm-logplayer at S times the recorded speed (default 1): the nodes compute
#   everything else again. Then the summary against the log's ground truth
#   (evaluate, DIR/metrics.json).
# - Defaults: config/paper.yaml; for an mrclam_import log give config/mrclam.yaml.
# - --view [PORT] (default 8765; 0: any free port): the viewer with the team (its URL is printed); on a
#   terminal it stays up after the summary until Enter is pressed.
# - As root the team runs in a private network namespace (tools/netns_run.sh; LCM
#   port P, default 7667) and the viewer's page is served on the host's loopback.
#   Not as root: LCM_DEFAULT_URL (multicast on loopback must be enabled, docs/usage.md).
# - --channel-groups (or the config's team.channel_groups: true): the nodes open one
#   LCM port per channel group (tools/lcm_groups.sh); the log is played by one
#   lcm-logplayer per group (started together: each keeps the log's timing) and
#   recorded by one recorder per group, merged by log_merge into DIR/run.lcmlog.
# - To watch a recorded run as it was (no nodes): `viewer` and
#   `lcm-logplayer run.lcmlog` on the same LCM URL (docs/tools.md).
# Exit status: 0 done, 1 a node or the replay failed, 2 bad arguments, 130 interrupted.
set -euo pipefail
ROOT="$(cd "$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")/.." && pwd)"
BUILD_DIR="${ELASLAM_BUILD_DIR:-$ROOT/build}"
CONFIG="$ROOT/config/paper.yaml"
LOG="" MODE="" SPEED=1 VIEW_PORT="" VIEW_NS="" OUT="" PORT=7667 ROBOTS="" INSIDE=0 GROUPED=0
die() { echo "replay_team.sh: $*" >&2; exit 2; }
usage() { sed -n '3,/^set -e/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit "${1:-0}"; }
while [ $# -gt 0 ]; do
  case "$1" in
    --config|--mode|--speed|--out|--port|--build-dir|--robots|--view-ns)
      [ $# -ge 2 ] || die "$1 needs a value (see --help)" ;;&
    --config) CONFIG="$2"; shift 2 ;;
    --mode) case "$2" in ekf|gated|ela|consensus) MODE="$2" ;; *) die "--mode must be ekf, gated, ela or consensus, got '$2'" ;; esac
            shift 2 ;;
    --speed) [[ "$2" =~ ^[0-9]+([.][0-9]+)?$ ]] && awk -v s="$2" 'BEGIN { exit !(s >= 0.01 && s <= 100) }' ||
               die "--speed must be a number in [0.01, 100], got '$2'"
             SPEED="$2"; shift 2 ;;
    --out) OUT="$2"; shift 2 ;;
    --port) [[ "$2" =~ ^[0-9]+$ ]] && [ "$2" -ge 1 ] && [ "$2" -le 65535 ] || die "--port must be in [1, 65535], got '$2'"
            PORT="$2"; shift 2 ;;
    --build-dir) BUILD_DIR="$2"; shift 2 ;;
    --robots) [[ "$2" =~ ^([1-9]|1[0-6])( ([1-9]|1[0-6]))*$ ]] ||
                die "--robots must be robot ids 1-16 separated by spaces, got '$2'"
              ROBOTS="$2"; shift 2 ;;
    --view) VIEW_PORT=8765; shift
            if [ $# -gt 0 ] && [[ "$1" =~ ^[0-9]+$ ]]; then
              [ "$1" -le 65535 ] || die "--view port must be in [0, 65535] (0: any free port), got '$1'"
              VIEW_PORT="$1"; shift
            fi ;;
    --view-ns) VIEW_NS="$2"; shift 2 ;;  # internal
    --channel-groups) GROUPED=1; shift ;;
    --inside) INSIDE=1; shift ;;         # internal: inside the namespace
    -h|--help) usage 0 ;;
    -*) die "unknown argument '$1' (see --help)" ;;
    *) [ -z "$LOG" ] || die "one log only (got '$LOG' and '$1')"; LOG="$1"; shift ;;
  esac
done
[ -n "$LOG" ] || die "which log? (see --help)"
[ -f "$LOG" ] || die "no such log: $LOG"
[ -f "$CONFIG" ] || die "no such config file: $CONFIG"
LOG="$(cd "$(dirname "$LOG")" && pwd)/$(basename "$LOG")"
CONFIG="$(cd "$(dirname "$CONFIG")" && pwd)/$(basename "$CONFIG")"
BIN="$BUILD_DIR/bin"
for p in main_robot robot_node evaluate log_info log_merge record ${VIEW_PORT:+viewer}; do
  [ -x "$BIN/$p" ] || die "no $BIN/$p (build it: cmake --build $BUILD_DIR --target $p)"
done
command -v lcm-logplayer >/dev/null || die "needs lcm-logplayer (liblcm-bin)"
PY="$ROOT/.venv/bin/python"
[ -x "$PY" ] || die "needs the Python venv (tools/setup.sh)"
[ -n "$OUT" ] || OUT="$ROOT/runs/replay_$(date +%Y%m%d_%H%M%S)"
mkdir -p "$OUT/logs" || die "cannot create $OUT"
OUT="$(cd "$OUT" && pwd)"
if [ -z "$ROBOTS" ]; then
  ROBOTS=$("$BIN/log_info" "$LOG" | awk '$1 ~ /^SENSOR_[0-9]+$/ { sub("SENSOR_", "", $1); print $1 }' | sort -n | tr '\n' ' ')
  ROBOTS="${ROBOTS% }"
  [ -n "$ROBOTS" ] || die "$LOG has no SENSOR_<r> channel: nothing to replay"
fi
[ "$INSIDE" -eq 1 ] || { [ -t 0 ] && export ELASLAM_VIEW_HOLD=1; } || export ELASLAM_VIEW_HOLD=0

if [ "$INSIDE" -eq 0 ] && [ "$(id -u)" -eq 0 ] && ip netns list >/dev/null 2>&1; then
  rc=0
  "$ROOT/tools/netns_run.sh" --port "$PORT" -- "$0" "$LOG" --inside --config "$CONFIG" ${MODE:+--mode "$MODE"} \
    --speed "$SPEED" --out "$OUT" --build-dir "$BUILD_DIR" --robots "$ROBOTS" $([ "$GROUPED" -eq 1 ] && echo --channel-groups) \
    ${VIEW_PORT:+--view "$VIEW_PORT" --view-ns "/proc/$$/ns/net"} || rc=$?
  exit $rc
fi

PIDS=() VIEWER_PID=""
cleanup() {
  trap '' INT TERM
  for p in "${PIDS[@]}" $VIEWER_PID; do kill -TERM "$p" 2>/dev/null || true; done
  for p in "${PIDS[@]}" $VIEWER_PID; do wait "$p" 2>/dev/null || true; done
}
trap cleanup EXIT
trap 'echo "replay_team.sh: interrupted" >&2; exit 130' INT TERM
read -r -a R <<<"$ROBOTS"
# shellcheck source=tools/lcm_groups.sh
. "$ROOT/tools/lcm_groups.sh"
# shellcheck source=tools/viewer_url.sh
. "$ROOT/tools/viewer_url.sh"
# Channel groups as the nodes will open them (the config may ask for them).
G_ARGS=()
[ "$GROUPED" -eq 0 ] || G_ARGS=(--channel-groups)
"$BIN/main_robot" --config "$CONFIG" "${G_ARGS[@]}" --check >"$OUT/logs/check.log" 2>&1 ||
  { cat "$OUT/logs/check.log" >&2; echo "replay_team.sh: the configuration is not valid" >&2; exit 2; }
GROUPED=$(lcm_groups_in_check "$OUT/logs/check.log")
[ "$GROUPED" -eq 0 ] || G_ARGS=(--channel-groups)
if [ "$GROUPED" -eq 0 ]; then
  "$BIN/record" -f -q "$OUT/run.lcmlog" >"$OUT/logs/logger.log" 2>&1 & PIDS+=($!)
else
  mkdir -p "$OUT/groups"
  for g in $(lcm_team_groups "${R[@]}"); do
    "$BIN/record" -f -q --lcm-url="$(lcm_group_url "$g")" "$OUT/groups/g$g.lcmlog" >"$OUT/logs/logger_g$g.log" 2>&1 &
    PIDS+=($!)
  done
fi
"$BIN/main_robot" --config "$CONFIG" "${G_ARGS[@]}" >"$OUT/logs/main_robot.log" 2>&1 & PIDS+=($!)
for r in "${R[@]}"; do
  "$BIN/robot_node" --config "$CONFIG" --robot "$r" ${MODE:+--mode "$MODE"} "${G_ARGS[@]}" >"$OUT/logs/robot_node_$r.log" 2>&1 &
  PIDS+=($!)
done
if [ -n "$VIEW_PORT" ]; then
  "$BIN/viewer" --config "$CONFIG" --port "$VIEW_PORT" ${VIEW_NS:+--http-netns "$VIEW_NS"} "${G_ARGS[@]}" \
    >"$OUT/logs/viewer.log" 2>&1 &
  VIEWER_PID=$!
  url=$(wait_viewer_url "$OUT/logs/viewer.log" "$VIEWER_PID")
  [ -n "$url" ] && echo "replay_team.sh: the viewer: $url" >&2 ||
    { echo "replay_team.sh: the viewer did not start: $(tail -n 1 "$OUT/logs/viewer.log")" >&2; VIEWER_PID=""; }
fi
"$PY" "$ROOT/tests/system/lcm_check.py" --build-dir "$BUILD_DIR" wait-nodes $((${#R[@]} + 1)) --timeout 30 ||
  { echo "replay_team.sh: the nodes did not all start (logs in $OUT/logs)" >&2; exit 1; }
echo "replay_team.sh: robots ${R[*]}, main_robot; playing $LOG at ${SPEED}x" >&2
if [ "$GROUPED" -eq 0 ]; then
  lcm-logplayer -s "$SPEED" -e '^(SENSOR_[0-9]+|GROUND_TRUTH|RUN_INFO)$' "$LOG" >"$OUT/logs/logplayer.log" 2>&1 ||
    { echo "replay_team.sh: lcm-logplayer failed (log: $OUT/logs/logplayer.log)" >&2; exit 1; }
else  # one player per group, started together (each sleeps through the others' events)
  PLAYERS=()
  for ch in RUN_INFO GROUND_TRUTH "${R[@]/#/SENSOR_}"; do
    lcm-logplayer -s "$SPEED" -e "^$ch\$" --lcm-url="$(lcm_group_url "$(lcm_group_of "$ch")")" "$LOG" \
      >"$OUT/logs/logplayer_$ch.log" 2>&1 &
    PLAYERS+=($!)
  done
  for p in "${PLAYERS[@]}"; do
    wait "$p" || { echo "replay_team.sh: an lcm-logplayer failed (logs: $OUT/logs/logplayer_*.log)" >&2; exit 1; }
  done
fi
sleep 0.5  # the last frame's messages reach the logger
rc=0
for p in "${PIDS[@]}"; do kill -INT "$p" 2>/dev/null || true; done
for i in "${!PIDS[@]}"; do
  wait "${PIDS[$i]}" || { echo "replay_team.sh: a node exited with an error (logs in $OUT/logs)" >&2; rc=1; }
done
PIDS=()
if [ "$GROUPED" -eq 1 ]; then
  "$BIN/log_merge" -f "$OUT/run.lcmlog" "$OUT"/groups/g*.lcmlog >"$OUT/logs/log_merge.log" 2>&1 ||
    { cat "$OUT/logs/log_merge.log" >&2; echo "replay_team.sh: merging the groups' recordings failed" >&2; exit 1; }
fi
"$BIN/evaluate" --log "$OUT/run.lcmlog" --out "$OUT" ${MODE:+--mode "$MODE"} || rc=1
echo "replay_team.sh: results in $OUT (metrics.json, run.lcmlog, logs/)"
if [ -n "$VIEWER_PID" ] && [ "${ELASLAM_VIEW_HOLD:-0}" = 1 ] && { exec 3</dev/tty; } 2>/dev/null; then
  echo "replay_team.sh: the viewer still shows the replay at $url; press Enter to stop it" >&2
  read -r -u 3 _ || true
fi
exit $rc

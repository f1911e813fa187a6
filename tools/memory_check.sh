#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Memory of the live team over a long run: does any node grow?
#
#   tools/memory_check.sh [--duration S] [--interval S] [--config FILE] [--out DIR]
#                         [--build-dir DIR] [--port P] [--log]
#                         [--dynamism P] [--speed V] [--seed S] [-- SIMULATOR ARGS...]
#
# - Runs the team free-running (no lockstep) at the scenario's rate (config/paper.yaml:
#   10 Hz) for S seconds (default 600): the simulator gets --frames S * rate; main_robot
#   and one robot_node per robot as in tools/run_team.sh (main_robot with --state).
#   --dynamism, --speed, --seed and any SIMULATOR ARGS after -- go to the simulator
#   (default: --dynamism 50 --speed 0.5 --seed 3, so that landmarks keep moving and
#   events, notices and snapshots keep flowing; the robots stop at the end of their
#   semicircles after 15 s and keep observing).
# - Every S seconds (default 5) samples VmRSS and VmHWM (/proc/PID/status) of every
#   robot_node, main_robot and the simulator into DIR/rss.csv
#   (t_s,process,pid,rss_kb,hwm_kb).
# - At the end prints per process: RSS at the first sample, at 60 s (after warm-up),
#   the maximum and the last, and the least-squares slope of RSS after 60 s [KiB/min].
# - --log also records the run with the recorder (record: DIR/run.lcmlog; ~10 MB a minute).
# - As root the team runs in a private network namespace (tools/netns_run.sh);
#   otherwise on LCM_DEFAULT_URL (multicast on loopback must be enabled).
set -euo pipefail
# The real source tree, also when started through a symbolic link (a scratch copy).
ROOT="$(cd "$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")/.." && pwd)"
BUILD_DIR="${ELASLAM_BUILD_DIR:-$ROOT/build}"
CONFIG="$ROOT/config/paper.yaml"
DURATION=600
INTERVAL=5
OUT=""
PORT=7760
LOG=0
INSIDE=0
SIM_ARGS=()
ORIG_ARGS=("$@")
usage() { sed -n '3,/^set -e/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit "${1:-0}"; }
usage_error() { echo "memory_check: $1 (see --help)" >&2; exit 2; }
number() { [[ "$2" =~ ^[0-9]+([.][0-9]+)?$ ]] && [[ ! "$2" =~ ^0+([.]0*)?$ ]] || usage_error "$1 must be a positive number, got '$2'"; }
while [ $# -gt 0 ]; do
  case "$1" in
    --duration|--interval|--config|--out|--build-dir|--port|--dynamism|--speed|--seed)
      [ $# -ge 2 ] || usage_error "$1 needs a value" ;;&
    --duration) number "$1" "$2"; DURATION="$2"; shift 2 ;;
    --interval) number "$1" "$2"; INTERVAL="$2"; shift 2 ;;
    --config) CONFIG="$2"; shift 2 ;;
    --out) OUT="$2"; shift 2 ;;
    --build-dir) BUILD_DIR="$2"; shift 2 ;;
    --port) PORT="$2"; shift 2 ;;
    --log) LOG=1; shift ;;
    --inside) INSIDE=1; shift ;;  # internal: already in the namespace
    --dynamism|--speed|--seed) SIM_ARGS+=("$1" "$2"); shift 2 ;;
    --) shift; SIM_ARGS+=("$@"); break ;;
    -h|--help) usage 0 ;;
    *) usage_error "unknown argument '$1'" ;;
  esac
done
[ -f "$CONFIG" ] || usage_error "no such config file: $CONFIG"
[ -d "$BUILD_DIR" ] || usage_error "no such build directory: $BUILD_DIR"
[ ${#SIM_ARGS[@]} -gt 0 ] || SIM_ARGS=(--dynamism 50 --speed 0.5 --seed 3)
BUILD_DIR="$(cd "$BUILD_DIR" && pwd)"
BIN="$BUILD_DIR/bin"
CONFIG="$(cd "$(dirname "$CONFIG")" && pwd)/$(basename "$CONFIG")"
[ -n "$OUT" ] || OUT="$ROOT/runs/memory_$(date +%Y%m%d_%H%M%S)"
mkdir -p "$OUT/logs"
OUT="$(cd "$OUT" && pwd)"

if [ "$INSIDE" -eq 0 ] && [ "$(id -u)" -eq 0 ] && ip netns list >/dev/null 2>&1; then
  exec "$ROOT/tools/netns_run.sh" --port "$PORT" -- "$0" --inside --out "$OUT" --build-dir "$BUILD_DIR" "${ORIG_ARGS[@]}"
fi

RATE=$(awk '/^scenario:/ {s = 1; next} /^[^ #]/ {s = 0} s && $1 == "rate_hz:" {print $2; exit}' "$CONFIG")
FRAMES=$(python3 -c "import math; print(int(math.ceil($DURATION * $RATE)))")
ROBOTS=($("$BIN/simulator" --config "$CONFIG" --list-robots))
PIDS=()
NAMES=()
cleanup() { for p in "${PIDS[@]}"; do kill -KILL "$p" 2>/dev/null || true; done; }
trap cleanup EXIT
trap 'exit 130' INT TERM
start() {
  local name="$1"; shift
  "$@" > "$OUT/logs/$name.log" 2>&1 &
  PIDS+=($!); NAMES+=("$name")
}
[ "$LOG" -eq 1 ] && start logger "$BIN/record" -f -q "$OUT/run.lcmlog"
start main_robot "$BIN/main_robot" --config "$CONFIG" --state "$OUT/main_state.json"
for r in "${ROBOTS[@]}"; do start "robot_node_$r" "$BIN/robot_node" --config "$CONFIG" --robot "$r"; done
start simulator "$BIN/simulator" --config "$CONFIG" --wait-for-nodes $((${#ROBOTS[@]} + 1)) --frames "$FRAMES" "${SIM_ARGS[@]}"
SIM="${PIDS[-1]}"
echo "memory_check: $FRAMES frames at $RATE Hz (${DURATION} s), ${#ROBOTS[@]} robots, sampling every ${INTERVAL} s into $OUT/rss.csv"

echo "t_s,process,pid,rss_kb,hwm_kb" > "$OUT/rss.csv"
T0=$(date +%s.%N)
sample() {
  local t i
  t=$(python3 -c "import time; print(f'{time.time() - $T0:.1f}')")
  for i in "${!PIDS[@]}"; do
    [ "${NAMES[$i]}" = logger ] && continue
    [ -r "/proc/${PIDS[$i]}/status" ] || continue
    awk -v t="$t" -v n="${NAMES[$i]}" -v p="${PIDS[$i]}" \
      '/^VmRSS:/ {r = $2} /^VmHWM:/ {h = $2} END {if (r != "") print t "," n "," p "," r "," h}' \
      "/proc/${PIDS[$i]}/status" >> "$OUT/rss.csv"
  done
}
while kill -0 "$SIM" 2>/dev/null; do
  sample
  sleep "$INTERVAL" &
  wait $! || true
done
sim_rc=0; wait "$SIM" || sim_rc=$?
sample_rc=0
# Stop the nodes (clean exit with their final status line).
sleep 0.3
for p in "${PIDS[@]}"; do kill -INT "$p" 2>/dev/null || true; done
for i in "${!PIDS[@]}"; do wait "${PIDS[$i]}" || { echo "memory_check: ${NAMES[$i]} exited with an error" >&2; sample_rc=1; }; done
PIDS=()
tail -q -n 1 "$OUT"/logs/robot_node_*.log "$OUT/logs/main_robot.log" "$OUT/logs/simulator.log"
python3 - "$OUT/rss.csv" <<'PY'
import csv, collections, sys
rows = collections.defaultdict(list)
for r in csv.DictReader(open(sys.argv[1])):
    rows[(r["process"], r["pid"])].append((float(r["t_s"]), int(r["rss_kb"]), int(r["hwm_kb"])))
print(f"{'process':14s} {'samples':>7s} {'start':>8s} {'at 60 s':>8s} {'max':>8s} {'end':>8s} {'HWM':>8s} {'slope after 60 s':>18s}")
for (name, pid), s in sorted(rows.items()):
    warm = [x for x in s if x[0] >= 60.0] or s
    n = len(warm)
    mt = sum(x[0] for x in warm) / n
    mr = sum(x[1] for x in warm) / n
    var = sum((x[0] - mt) ** 2 for x in warm)
    slope = sum((x[0] - mt) * (x[1] - mr) for x in warm) / var * 60.0 if var > 0 else 0.0
    print(f"{name:14s} {len(s):7d} {s[0][1]:7d}K {warm[0][1]:7d}K {max(x[1] for x in s):7d}K {s[-1][1]:7d}K "
          f"{s[-1][2]:7d}K {slope:+14.2f} KiB/min")
PY
echo "memory_check: samples in $OUT/rss.csv, process logs in $OUT/logs"
[ "$sim_rc" -eq 0 ] && [ "$sample_rc" -eq 0 ]

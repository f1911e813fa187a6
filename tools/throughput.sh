#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Throughput of the live team (separate processes over LCM, in a private network
# namespace; needs root):
#   1. lockstep: the simulator publishes frame k+1 as soon as every robot's POSE for
#      frame k arrived: the frames per second the whole team sustains;
#   2. free running at each rate of --rates: frames lost by any robot node (gaps,
#      from the nodes' final status lines), to find the highest F with no loss.
#   3. robot_node resident memory (VmRSS) sampled during the lockstep run.
#
#   tools/throughput.sh [--config FILE] [--frames N] [--rates "100 200 500 1000 2000"]
#                       [--mode M] [--channel-groups] [--build-dir DIR]
#
# Defaults: config/paper.yaml, 5000 frames per run, rates 100 200 500 1000 2000 Hz,
# mode ela, one LCM port for every channel (--channel-groups: one port per channel
# group, grouped_lcm_transport.hpp), the programs of DIR/bin (default $ELASLAM_BUILD_DIR, else build/; the
# script runs tools/setup.sh and builds them first). Not as root: exits 77 (no
# namespace).
set -euo pipefail
# The real source tree, also when started through a symbolic link (a scratch copy).
ROOT="$(cd "$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")/.." && pwd)"
BUILD_DIR="${ELASLAM_BUILD_DIR:-$ROOT/build}"
CONFIG="$ROOT/config/paper.yaml"
FRAMES=5000
RATES="100 200 500 1000 2000"
MODE=ela
GROUPED=()
INSIDE=0
PHASE=""
usage_error() { echo "throughput.sh: $1 (see --help)" >&2; exit 2; }
while [ $# -gt 0 ]; do
  case "$1" in
    --config|--frames|--rates|--mode|--build-dir|--inside) [ $# -ge 2 ] || usage_error "$1 needs a value" ;;&
    --config) CONFIG="$2"; shift 2 ;;
    --frames) FRAMES="$2"; shift 2 ;;
    --rates) RATES="$2"; shift 2 ;;
    --mode) MODE="$2"; shift 2 ;;
    --build-dir) BUILD_DIR="$2"; shift 2 ;;
    --channel-groups) GROUPED=(--channel-groups); shift ;;
    --inside) INSIDE=1; PHASE="$2"; shift 2 ;;  # internal: one run, inside the namespace
    -h|--help) sed -n '3,/^set -e/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) usage_error "unknown argument '$1'" ;;
  esac
done
[[ "$FRAMES" =~ ^[1-9][0-9]*$ ]] || usage_error "--frames must be a positive integer, got '$FRAMES'"
for f in $RATES; do [[ "$f" =~ ^[0-9]+([.][0-9]+)?$ ]] && [[ ! "$f" =~ ^0+([.]0*)?$ ]] || usage_error "--rates: not a rate: '$f'"; done
case "$MODE" in ekf|gated|ela|consensus) ;; *) usage_error "--mode must be ekf, gated, ela or consensus, got '$MODE'" ;; esac
[ -f "$CONFIG" ] || usage_error "no such config file: $CONFIG"
[ -d "$BUILD_DIR" ] || usage_error "no such build directory: $BUILD_DIR"
BUILD_DIR="$(cd "$BUILD_DIR" && pwd)"
BIN="$BUILD_DIR/bin"

if [ "$INSIDE" -eq 0 ]; then
  "$ROOT/tools/setup.sh" >/dev/null
  cmake --build "$BUILD_DIR" --target simulator robot_node main_robot -j "$(nproc)" >/dev/null
  echo "# throughput of the live team: $(nproc) CPUs, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
  echo "# config $CONFIG, mode $MODE, $FRAMES frames per run${GROUPED:+, channel groups}"
  "$ROOT/tools/netns_run.sh" --port 7690 -- "$0" --inside lockstep --config "$CONFIG" --frames "$FRAMES" --mode "$MODE" \
    --build-dir "$BUILD_DIR" "${GROUPED[@]}"
  for f in $RATES; do
    "$ROOT/tools/netns_run.sh" --port 7690 -- "$0" --inside "$f" --config "$CONFIG" --frames "$FRAMES" --mode "$MODE" \
      --build-dir "$BUILD_DIR" "${GROUPED[@]}"
  done
  exit 0
fi

LOGS="$(mktemp -d)"
trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$LOGS"' EXIT
ROBOTS=($("$BIN/simulator" --config "$CONFIG" --list-robots))
"$BIN/main_robot" --config "$CONFIG" "${GROUPED[@]}" 2>"$LOGS/main.log" &
PIDS=()
for r in "${ROBOTS[@]}"; do
  "$BIN/robot_node" --config "$CONFIG" --robot "$r" --mode "$MODE" "${GROUPED[@]}" 2>"$LOGS/robot$r.log" &
  PIDS+=($!)
done
SIM=(--config "$CONFIG" "${GROUPED[@]}" --frames "$FRAMES" --wait-for-nodes $((${#ROBOTS[@]} + 1)))
if [ "$PHASE" = lockstep ]; then
  SIM+=(--lockstep --rate 100000 --lockstep-timeout-ms 1000)  # deadlines always past: as fast as the team answers
else
  SIM+=(--rate "$PHASE")
fi
"$BIN/simulator" "${SIM[@]}" 2>"$LOGS/sim.log" &
SIMPID=$!
max_rss=0
while kill -0 $SIMPID 2>/dev/null; do
  for p in "${PIDS[@]}"; do
    rss=$(awk '/VmRSS/ {print $2}' /proc/$p/status 2>/dev/null || echo 0)
    [ "${rss:-0}" -gt "$max_rss" ] && max_rss=$rss
  done
  sleep 0.2
done
sim_rc=0; wait $SIMPID || sim_rc=$?
[ "$sim_rc" -eq 0 ] || { echo "throughput.sh: simulator failed ($sim_rc):" >&2; tail -n 3 "$LOGS/sim.log" >&2; exit 1; }
sleep 0.3
kill -INT "${PIDS[@]}" $(jobs -p) 2>/dev/null || true
wait 2>/dev/null || true
rate=$(grep -o "achieved [0-9.]* Hz" "$LOGS/sim.log" | awk "{print \$2}" || true)
timeouts=$(grep -o 'lockstep timeouts [0-9]*' "$LOGS/sim.log" | awk '{print $3}' || true)
gaps=0; frames=0
for r in "${ROBOTS[@]}"; do
  g=$(grep -o 'gaps=[0-9]*' "$LOGS/robot$r.log" | cut -d= -f2 || true); gaps=$((gaps + ${g:-0}))
  n=$(grep -o 'frames=[0-9]*' "$LOGS/robot$r.log" | head -1 | cut -d= -f2 || true); frames=$((frames + ${n:-0}))
done
expected=$((FRAMES * ${#ROBOTS[@]}))
if [ "$PHASE" = lockstep ]; then
  echo "lockstep: ${rate} frames/s sustained by the team, lockstep timeouts ${timeouts}, frames processed ${frames}/${expected}, robot_node max RSS $((max_rss / 1024)) MiB"
else
  echo "free-running F=${PHASE} Hz: achieved ${rate} Hz, frames processed ${frames}/${expected}, gaps ${gaps}"
fi

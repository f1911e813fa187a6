#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Latency of the live team at several frame rates: runs tools/run_team.sh (separate
# processes over LCM, recorded by lcm-logger) at each rate and prints, from the
# evaluated log, sensor-to-pose latency (p50/p99/max over every robot) and
# sensor-to-global-map latency (the GLOBAL_MAP that includes the frame).
#   tools/latency.sh [--config FILE] [--rates "10 30 100"] [--seconds S] [--mode M]
#                    [--no-realtime] [--channel-groups] [--out DIR] [--build-dir DIR]
# Each rate runs S seconds (default 30). As root the team runs with real-time
# scheduling (run_team.sh --realtime) unless --no-realtime. Pose latency is sensor
# publish to the robot's POSE publish (the POSE utime); "at logger" adds the hop to
# lcm-logger's receipt. --out DIR (default results/latency_<time>) gets each rate's
# run (F<rate>/) and output (F<rate>.txt). --build-dir DIR (default
# $ELASLAM_BUILD_DIR, else build/) and --channel-groups (one LCM port per channel
# group) go to run_team.sh. Before each rate it measures LCM's own one-way latency at
# that rate between two processes (lcm_floor, 10 s in a namespace of its own): the
# floor under a message's hop (last column; docs/benchmarks.md).
set -euo pipefail
# The real source tree, also when started through a symbolic link (a scratch copy).
ROOT="$(cd "$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")/.." && pwd)"
CONFIG="$ROOT/config/paper.yaml"
RATES="10 30 100"
SECONDS_PER_RUN=30
MODE=ela
RT=(--realtime)
OUT="$ROOT/results/latency_$(date +%Y%m%d_%H%M%S)"
BUILD_ARGS=()
BUILD_DIR="${ELASLAM_BUILD_DIR:-$ROOT/build}"
GROUPED=()
usage_error() { echo "latency.sh: $1 (see --help)" >&2; exit 2; }
while [ $# -gt 0 ]; do
  case "$1" in
    --config|--rates|--seconds|--mode|--out|--build-dir) [ $# -ge 2 ] || usage_error "$1 needs a value" ;;&
    --config) CONFIG="$2"; shift 2 ;;
    --rates) RATES="$2"; shift 2 ;;
    --seconds) SECONDS_PER_RUN="$2"; shift 2 ;;
    --mode) MODE="$2"; shift 2 ;;
    --no-realtime) RT=(); shift ;;
    --channel-groups) GROUPED=(--channel-groups); shift ;;
    --out) OUT="$2"; shift 2 ;;
    --build-dir) BUILD_ARGS=(--build-dir "$2"); BUILD_DIR="$2"; shift 2 ;;
    -h|--help) sed -n '3,/^set -e/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) usage_error "unknown argument '$1'" ;;
  esac
done
positive() { [[ "$1" =~ ^[0-9]+([.][0-9]+)?$ ]] && [[ ! "$1" =~ ^0+([.]0*)?$ ]]; }
positive "$SECONDS_PER_RUN" || usage_error "--seconds must be a positive number, got '$SECONDS_PER_RUN'"
for f in $RATES; do positive "$f" || usage_error "--rates: not a rate: '$f'"; done
[ -n "${RATES// /}" ] || usage_error "--rates is empty"
case "$MODE" in ekf|gated|ela|consensus) ;; *) usage_error "--mode must be ekf, gated, ela or consensus, got '$MODE'" ;; esac
[ -f "$CONFIG" ] || usage_error "no such config file: $CONFIG"
mkdir -p "$OUT"
[ "$(id -u)" -eq 0 ] || RT=()
printf '%-8s %-8s %-30s %-30s %-30s %-15s %s\n' "F [Hz]" frames "pose latency p50/p99/max [us]" "at logger p50/p99/max [us]" \
  "map latency p50/p99/max [us]" "frames dropped" "LCM floor p50/p99 [us]"
for f in $RATES; do
  frames=$(awk -v f="$f" -v s="$SECONDS_PER_RUN" 'BEGIN { printf "%d", f * s }')
  floor_n=$(awk -v f="$f" 'BEGIN { n = int(f * 10); printf "%d", n < 100 ? 100 : (n > 2000 ? 2000 : n) }')
  "$ROOT/tools/netns_run.sh" -- "$BUILD_DIR/bin/lcm_floor" --rate "$f" --count "$floor_n" >"$OUT/F$f.floor.txt" 2>&1 ||
    echo "latency.sh: lcm_floor at $f Hz failed, see $OUT/F$f.floor.txt" >&2
  floor=$(sed -n 's|.*p50 / p90 / p99 / max \([0-9]*\) / [0-9]* / \([0-9]*\) / .*|\1 / \2|p' "$OUT/F$f.floor.txt")
  "$ROOT/tools/run_team.sh" --no-progress --no-baseline --config "$CONFIG" --mode "$MODE" --rate "$f" --frames "$frames" "${RT[@]}" "${GROUPED[@]}" "${BUILD_ARGS[@]}" --out "$OUT/F$f" >"$OUT/F$f.txt" 2>&1 ||
    { echo "latency.sh: run at $f Hz failed, see $OUT/F$f.txt" >&2; exit 1; }
  "$ROOT/.venv/bin/python" - "$OUT/F$f/metrics.json" "$f" "$frames" "${floor:-?}" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))
p, l, g = m["pose_publish_latency_us"], m["latency_us"], m["global_map_latency_us"]
print(f"{sys.argv[2]:<8} {sys.argv[3]:<8} {p['p50']:>8} / {p['p99']:>6} / {p['max']:>8}      "
      f"{l['p50']:>8} / {l['p99']:>6} / {l['max']:>8}      "
      f"{g['p50']:>8} / {g['p99']:>6} / {g['max']:>8}      {m['frames_dropped']:<15} {sys.argv[4]}")
PY
done
echo "(logs and metrics in $OUT)"

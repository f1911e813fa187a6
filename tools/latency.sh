#!/usr/bin/env bash
# Latency of the live team at several frame rates: runs tools/run_team.sh (separate
# processes over LCM, recorded by lcm-logger) at each rate and prints, from the
# evaluated log, sensor-to-pose latency (p50/p99/max over every robot) and
# sensor-to-global-map latency (the GLOBAL_MAP that includes the frame).
#   tools/latency.sh [--config FILE] [--rates "10 30 100"] [--seconds S] [--mode M] [--out DIR]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
CONFIG="$ROOT/config/paper.yaml"
RATES="10 30 100"
SECONDS_PER_RUN=30
MODE=ela
OUT="$ROOT/results/latency_$(date +%Y%m%d_%H%M%S)"
while [ $# -gt 0 ]; do
  case "$1" in
    --config) CONFIG="$2"; shift 2 ;;
    --rates) RATES="$2"; shift 2 ;;
    --seconds) SECONDS_PER_RUN="$2"; shift 2 ;;
    --mode) MODE="$2"; shift 2 ;;
    --out) OUT="$2"; shift 2 ;;
    -h|--help) sed -n '2,6p' "$0"; exit 0 ;;
    *) echo "latency.sh: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
mkdir -p "$OUT"
printf '%-8s %-8s %-30s %-30s %s\n' "F [Hz]" frames "pose latency p50/p99/max [us]" "map latency p50/p99/max [us]" "frames dropped"
for f in $RATES; do
  frames=$(awk -v f="$f" -v s="$SECONDS_PER_RUN" 'BEGIN { printf "%d", f * s }')
  "$ROOT/tools/run_team.sh" --config "$CONFIG" --mode "$MODE" --rate "$f" --frames "$frames" --out "$OUT/F$f" >"$OUT/F$f.txt" 2>&1 ||
    { echo "latency.sh: run at $f Hz failed, see $OUT/F$f.txt" >&2; exit 1; }
  "$ROOT/.venv/bin/python" - "$OUT/F$f/metrics.json" "$f" "$frames" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))
l, g = m["latency_us"], m["global_map_latency_us"]
print(f"{sys.argv[2]:<8} {sys.argv[3]:<8} {l['p50']:>8} / {l['p99']:>6} / {l['max']:>8}      "
      f"{g['p50']:>8} / {g['p99']:>6} / {g['max']:>8}      {m['frames_dropped']}")
PY
done
echo "(logs and metrics in $OUT)"

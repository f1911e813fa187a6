#!/usr/bin/env bash
# Run the team on a scenario and show the result. Does the set-up if needed
# (tools/setup.sh), builds, runs, and prints the summary.
#   tools/run_team.sh [--config FILE] [--mode M] [--dynamism P] [--speed V] [--seed S] [--out DIR]
# Today this runs the whole team in one process, in lockstep (build/bin/run_scenario);
# the live multi-process launch over LCM comes with its own issue.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
CONFIG="$ROOT/config/paper.yaml"
OUT="$ROOT/runs/team_$(date +%Y%m%d_%H%M%S)"
ARGS=()
while [ $# -gt 0 ]; do
  case "$1" in
    --config) CONFIG="$2"; shift 2 ;;
    --out) OUT="$2"; shift 2 ;;
    --mode|--dynamism|--speed|--seed) ARGS+=("$1" "$2"); shift 2 ;;
    -h|--help) sed -n '2,7p' "$0"; exit 0 ;;
    *) echo "run_team.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
"$ROOT/tools/setup.sh" >/dev/null
cmake --build "$ROOT/build" --target run_scenario simulator robot_node main_robot -j "$(nproc)" >/dev/null
"$ROOT/build/bin/run_scenario" --config "$CONFIG" --out "$OUT" "${ARGS[@]}"

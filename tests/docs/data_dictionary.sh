#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Test `data_dictionary`: every output file the programs write (metrics.json of
# run_scenario with a baseline, of evaluate on a recording, of run_dataset; frames.csv,
# map.csv; the sweep's runs.csv and frames.csv; log_info --json; mrclam_stats --json)
# has every key and column documented in docs/data_dictionary.md.
#   tests/docs/data_dictionary.sh BUILD_DIR
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BIN="$(cd "${1:?usage: data_dictionary.sh BUILD_DIR}" && pwd)/bin"
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
DATA="$ROOT/data/mrclam/dataset6"
TINY="$ROOT/tests/dataset/data/tiny"
"$BIN/run_scenario" --config "$ROOT/config/paper.yaml" --frames 40 --baseline ekf --out "$OUT/scenario" > /dev/null
"$BIN/sweep" --config "$ROOT/config/paper.yaml" --modes ela --dynamism 50 --speed 0.5 --runs 1 --no-plots \
  --out "$OUT/sweep" > /dev/null 2>&1
# A recording without the robots' outputs still has every key of evaluate's file.
"$BIN/mrclam_import" --dataset "$TINY" --config "$ROOT/config/mrclam.yaml" --robots 1,2 --out "$OUT/tiny.lcmlog" > /dev/null
"$BIN/evaluate" --log "$OUT/tiny.lcmlog" --out "$OUT/evaluate" --quiet
"$BIN/log_info" --json "$OUT/tiny.lcmlog" > "$OUT/log_info.json"
FILES=("$OUT/scenario/metrics.json" "$OUT/scenario/frames.csv" "$OUT/scenario/map.csv"
       "$OUT/sweep/runs.csv" "$OUT/sweep/frames.csv" "$OUT/evaluate/metrics.json" "$OUT/log_info.json")
if [ -d "$DATA" ]; then  # the real recording (in the repository: tools/get_mrclam.sh)
  "$BIN/run_dataset" --dataset "$DATA" --config "$ROOT/config/mrclam.yaml" --duration 20 --report --modes ela \
    --no-plots --out "$OUT/dataset" > /dev/null
  "$BIN/mrclam_stats" --dataset "$DATA" --json "$OUT/mrclam_stats.json" > /dev/null
  FILES+=("$OUT/dataset/report.json" "$OUT/dataset/ela/metrics.json" "$OUT/mrclam_stats.json")
else
  echo "data_dictionary: no $DATA: run_dataset and mrclam_stats outputs not checked"
fi
python3 "$ROOT/tests/docs/data_dictionary_check.py" "$ROOT/docs/data_dictionary.md" "${FILES[@]}"

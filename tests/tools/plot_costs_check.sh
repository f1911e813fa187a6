#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tools/plot_costs.py on short runs of bench_ekf and bench_main (the cost
# curves, docs/benchmarks.md): both PNGs written; a file without the benchmarks and
# a missing file are refused with exit 1 naming them. Timings are not checked.
#   tests/tools/plot_costs_check.sh BUILD_DIR
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BIN="${1:?usage: plot_costs_check.sh BUILD_DIR}/bin"
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
"$ROOT/.venv/bin/python" -c "import matplotlib" 2>/dev/null || { echo "no .venv with matplotlib (tools/setup.sh)"; exit 77; }
"$BIN/bench_ekf" --benchmark_filter='BM_EkfSlamFrame(JosephForm)?/landmarks:(16|72)$' --benchmark_min_time=0.01 \
  --benchmark_format=json >"$OUT/ekf.json" 2>/dev/null
"$BIN/bench_main" --benchmark_filter='robots:(1|16)/landmarks:(72|1024)$' --benchmark_min_time=0.01 \
  --benchmark_format=json >"$OUT/main.json" 2>/dev/null
"$ROOT/tools/plot_costs.py" --ekf "$OUT/ekf.json" --main "$OUT/main.json" --out "$OUT/png" >"$OUT/log" 2>&1 \
  || { echo "plot_costs.py failed:"; cat "$OUT/log"; exit 1; }
for f in cost_ekf_frame cost_main_frame; do
  [ "$(head -c 4 "$OUT/png/$f.png" | od -An -c | tr -d ' ')" = "211PNG" ] || { echo "no $f.png"; cat "$OUT/log"; exit 1; }
done
echo '{"benchmarks": []}' >"$OUT/empty.json"
set +e
"$ROOT/tools/plot_costs.py" --ekf "$OUT/empty.json" --main "$OUT/main.json" --out "$OUT/x" >"$OUT/e1" 2>&1; rc1=$?
"$ROOT/tools/plot_costs.py" --ekf "$OUT/nope.json" --main "$OUT/main.json" --out "$OUT/x" >"$OUT/e2" 2>&1; rc2=$?
set -e
[ $rc1 -eq 1 ] && grep -q "empty.json: no benchmarks" "$OUT/e1" || { echo "empty file: exit $rc1"; cat "$OUT/e1"; exit 1; }
[ $rc2 -eq 1 ] && grep -q "nope.json" "$OUT/e2" || { echo "missing file: exit $rc2"; cat "$OUT/e2"; exit 1; }
echo "plot_costs_check: ok"

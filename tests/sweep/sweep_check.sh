#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The sweep on a reduced grid (2 cells x 2 runs, 2 modes): its files and columns,
# tables.md against runs.csv, and identical runs.csv for --jobs 1 and --jobs 2.
#   tests/sweep/sweep_check.sh BUILD_DIR
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BIN="${1:?usage: sweep_check.sh BUILD_DIR}/bin"
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
ARGS=(--config "$ROOT/config/paper.yaml" --modes ekf,ela --dynamism 20,80 --speed 0.5 --runs 2 --no-plots)
"$BIN/sweep" "${ARGS[@]}" --jobs 1 --out "$OUT/j1" >/dev/null 2>&1
"$BIN/sweep" "${ARGS[@]}" --jobs 2 --out "$OUT/j2" >/dev/null 2>&1
cmp "$OUT/j1/runs.csv" "$OUT/j2/runs.csv" || { echo "runs.csv differs between --jobs 1 and --jobs 2"; exit 1; }
for f in runs.csv frames.csv tables.md maps/ela/metrics.json maps/ela/map.csv; do
  [ -s "$OUT/j1/$f" ] || { echo "missing $f"; exit 1; }
done
python3 - "$OUT/j1" <<'PY'
import csv, re, statistics, sys
d = sys.argv[1]
header = open(f"{d}/runs.csv").readline().strip()
want = ("mode,dynamism,speed,run,seed,landmark_error,landmark_rms,robot1_error,robot1_rms,robot1_uncertainty,"
        "robot2_error,robot2_rms,robot2_uncertainty,robot3_error,robot3_rms,robot3_uncertainty,precision,recall")
assert header.startswith(want), header
rows = list(csv.DictReader(open(f"{d}/runs.csv")))
assert len(rows) == 8, len(rows)
assert [r["seed"] for r in rows[:2]] == ["1", "2"]
tables = open(f"{d}/tables.md").read()
t1 = tables.split("### Table 1")[1].split("###")[0]
for line in t1.splitlines():
    m = re.match(r"\| (\d+) \| ([\d.]+) ± [\d.]+ \| ([\d.]+) ± [\d.]+ \|", line)
    if not m:
        continue
    for mode, shown in (("ekf", m.group(2)), ("ela", m.group(3))):
        vals = [float(r["landmark_error"]) for r in rows if r["mode"] == mode and float(r["dynamism"]) == float(m.group(1))]
        assert abs(statistics.mean(vals) - float(shown)) < 0.0006, (mode, m.group(1), shown, vals)
print("sweep files consistent")
PY
# tools/plot_sweep.py on the reduced grid: every figure written, each a PNG.
PY="$ROOT/.venv/bin/python"
if [ -x "$PY" ]; then
  "$PY" "$ROOT/tools/plot_sweep.py" "$OUT/j1" --out "$OUT/plots" >"$OUT/plot.log" 2>&1 \
    || { echo "plot_sweep.py failed:"; cat "$OUT/plot.log"; exit 1; }
  for f in fig4_map fig5_landmark_error fig6_robot_error fig6b_error_vs_speed fig7_error_over_time fig8_uncertainty detection; do
    png="$OUT/plots/$f.png"
    [ -s "$png" ] || { echo "plot_sweep.py did not write $f.png"; cat "$OUT/plot.log"; exit 1; }
    [ "$(head -c 8 "$png" | od -An -tx1 | tr -d ' \n')" = "89504e470d0a1a0a" ] || { echo "$f.png is not a PNG"; exit 1; }
  done
  # A missing input column is an error that names the column.
  sed '1s/,recall,/,recal,/' "$OUT/j1/runs.csv" >"$OUT/bad.csv" && mkdir -p "$OUT/bad" && mv "$OUT/bad.csv" "$OUT/bad/runs.csv"
  cp "$OUT/j1/frames.csv" "$OUT/bad/"
  if "$PY" "$ROOT/tools/plot_sweep.py" "$OUT/bad" >"$OUT/bad.log" 2>&1; then echo "plot_sweep.py accepted a runs.csv without recall"; exit 1; fi
  grep -q "recall" "$OUT/bad.log" || { echo "plot_sweep.py error does not name the missing column:"; cat "$OUT/bad.log"; exit 1; }
  echo "plots written: $(ls "$OUT/plots" | tr '\n' ' ')"
else
  echo "plot check skipped: no $PY (tools/setup.sh makes it)"
fi

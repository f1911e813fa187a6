#!/bin/bash
# SPDX-License-Identifier: Apache-2.0
# tools/paired_cells.py on a made-up runs.csv whose answer is known: per cell, ela
# always 0.010 m below ekf (a significant win), 0.001 m above on average with
# 0.010 m of scatter (a loss that is noise), always 0.010 m above (a significant
# loss); two halves of it pooled give the same answer; then bad inputs exit
# non-zero with a message.
set -euo pipefail
src=$(cd "$(dirname "$0")/../.." && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
python3 - "$tmp/grid" <<'PY'
import os, sys
out = sys.argv[1]
os.makedirs(out)
scatter = [0.010, -0.010, 0.012, -0.008, 0.009, -0.011, 0.010, -0.010, 0.011, -0.009]
with open(f"{out}/runs.csv", "w") as f:
    f.write("mode,dynamism,speed,run,seed,landmark_error,robot1_error\n")
    for run in range(10):
        seed = 100 + run
        base = 0.05 + 0.002 * run
        # cell 5 %/0.1: landmark error a sure win, robot 1 a loss within noise
        f.write(f"ekf,5,0.1,{run},{seed},{base:.6f},{base:.6f}\n")
        f.write(f"ela,5,0.1,{run},{seed},{base - 0.010:.6f},{base + 0.001 + scatter[run]:.6f}\n")
        # cell 80 %/0.3: landmark error a sure loss, robot 1 a sure win
        f.write(f"ekf,80,0.3,{run},{seed},{base:.6f},{base:.6f}\n")
        f.write(f"ela,80,0.3,{run},{seed},{base + 0.010:.6f},{base - 0.020:.6f}\n")
PY
out=$("$src/tools/paired_cells.py" "$tmp/grid")
echo "$out"
grep -q "ela below ekf in 2 of 4 cell-metrics (2 significant); lost 2 (1 significant)" <<<"$out"
grep -Eq "lost +5 % 0.1 m/s robot1_error +\+0\.0014 m +t \+0\.[0-9]+$" <<<"$out"
grep -Eq "lost +80 % 0.3 m/s landmark_error +\+0\.0100 m .*significant" <<<"$out"
# Two sweeps pooled: the same runs split by seed into two directories give the same
# answer as one; the same directory twice (every seed twice) is refused.
mkdir "$tmp/half1" "$tmp/half2"
head -1 "$tmp/grid/runs.csv" | tee "$tmp/half1/runs.csv" >"$tmp/half2/runs.csv"
awk -F, 'NR > 1 && $5 < 105' "$tmp/grid/runs.csv" >>"$tmp/half1/runs.csv"
awk -F, 'NR > 1 && $5 >= 105' "$tmp/grid/runs.csv" >>"$tmp/half2/runs.csv"
pooled=$("$src/tools/paired_cells.py" "$tmp/half1" "$tmp/half2")
[ "$pooled" = "$out" ] || { echo "pooled halves differ from the whole: $pooled"; exit 1; }
half=$("$src/tools/paired_cells.py" "$tmp/half1")
[ "$half" != "$out" ] || { echo "one half alone gave the whole's answer: the split tests nothing"; exit 1; }
if "$src/tools/paired_cells.py" "$tmp/grid" "$tmp/grid" 2>"$tmp/err"; then echo "a seed twice accepted"; exit 1; fi
grep -q "seed 100 of mode ekf at 5 % / 0.1 m/s is already in" "$tmp/err"
# Bad inputs: a missing directory, a file that is not a sweep's, no common mode.
if "$src/tools/paired_cells.py" "$tmp/none" 2>"$tmp/err"; then echo "missing dir accepted"; exit 1; fi
grep -q "cannot read" "$tmp/err"
mkdir "$tmp/bad" && printf 'a,b\n1,2\n' >"$tmp/bad/runs.csv"
if "$src/tools/paired_cells.py" "$tmp/bad" 2>"$tmp/err"; then echo "bad csv accepted"; exit 1; fi
grep -q "not a sweep's runs.csv row" "$tmp/err"
if "$src/tools/paired_cells.py" "$tmp/grid" --a consensus 2>"$tmp/err"; then echo "absent mode accepted"; exit 1; fi
grep -q "no seed run in both consensus and ekf" "$tmp/err"
echo "paired_cells_check: ok"

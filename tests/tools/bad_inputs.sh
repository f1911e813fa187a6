#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Bad configurations and bad command-line numbers against every program
# (docs/security.md): each must exit 2 with a message on stderr that names the
# problem (the key path, the option or the file), and none may die by a signal.
#   tests/tools/bad_inputs.sh BUILD_DIR
# The corpus is made here from config/paper.yaml and config/mrclam.yaml: a
# non-scalar key, duplicate keys (nested and top level), a second document, nan
# and inf values, /dev/zero, a directory, a FIFO, a missing file, a file over the
# size limit, binary garbage, invalid UTF-8; then nan, inf and out-of-range
# numbers for the numeric options. `timeout` only guards against a hang (a FIFO
# read that blocks): a run that needs it fails.
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BIN="${1:?usage: bad_inputs.sh BUILD_DIR}/bin"
T="$(mktemp -d)"
trap 'rm -rf "$T"' EXIT
TINY="$ROOT/tests/dataset/data/tiny"
PAPER="$ROOT/config/paper.yaml"
MRCLAM="$ROOT/config/mrclam.yaml"
failures=0 checks=0

# expect NAME WANT... -- CMD ARGS...: CMD exits 2 and its stderr holds every WANT.
expect() {
  local name=$1 rc=0
  shift
  local want=()
  while [ "$1" != "--" ]; do want+=("$1"); shift; done
  shift
  checks=$((checks + 1))
  timeout 60 "$@" </dev/null >"$T/stdout" 2>"$T/stderr" || rc=$?
  local why=""
  if [ $rc -eq 124 ]; then why="hung (killed after 60 s)"
  elif [ $rc -gt 128 ]; then why="died by signal $((rc - 128))"
  elif [ $rc -ne 2 ]; then why="exit $rc, expected 2"
  else
    for w in "${want[@]}"; do
      grep -qF -- "$w" "$T/stderr" || why="${why:+$why; }stderr does not name '$w'"
    done
  fi
  if [ -n "$why" ]; then
    failures=$((failures + 1))
    echo "FAIL $name: $why"
    echo "  command: $*"
    sed 's/^/  stderr: /' "$T/stderr" | head -8
  fi
}

# The programs that read a config, each with its cheapest run and the base config
# whose sections it reads.
"$BIN/mrclam_import" --dataset "$TINY" --config "$MRCLAM" --robots 1,2 --out "$T/tiny.lcmlog" >/dev/null 2>&1 \
  || { echo "cannot make the test log with mrclam_import"; exit 1; }
declare -A BASE ARGS
for p in simulator scenario_dump robot_node main_robot run_scenario sweep evaluate; do BASE[$p]=$PAPER; done
for p in run_dataset mrclam_import mrclam_stats; do BASE[$p]=$MRCLAM; done
ARGS[simulator]="--check"
ARGS[scenario_dump]="--check --out $T/dump.csv"
ARGS[robot_node]="--robot 1 --check"
ARGS[main_robot]="--check"
ARGS[run_scenario]="--check"
ARGS[sweep]="--check --out $T/sweep"
ARGS[evaluate]="--log $T/tiny.lcmlog --quiet"
ARGS[run_dataset]="--dataset $TINY --check --out $T/ds"
ARGS[mrclam_import]="--dataset $TINY --check --out $T/x.lcmlog"
ARGS[mrclam_stats]="--dataset $TINY --check"
PROGRAMS="simulator scenario_dump robot_node main_robot run_scenario sweep evaluate run_dataset mrclam_import mrclam_stats"

# A non-finite value in the section each program reads: the key it must name.
declare -A NAN_KEY=([simulator]=scenario.rate_hz [scenario_dump]=scenario.rate_hz [run_scenario]=scenario.rate_hz
  [sweep]=scenario.rate_hz [evaluate]=scenario.rate_hz [robot_node]=robot.filter.gate_probability
  [main_robot]=main.publish_rate_hz [run_dataset]=dataset.rate_hz [mrclam_import]=dataset.rate_hz
  [mrclam_stats]=dataset.rate_hz)

# The corpus, one file per base.
for b in paper mrclam; do
  src=$ROOT/config/$b.yaml
  { cat "$src"; printf '? [a, b]\n: 1\n'; } >"$T/nonscalar_$b.yaml"
  sed '0,/^robot:/s//robot:\n  {x: 1}: 2/' "$src" >"$T/nonscalar_nested_$b.yaml"
  sed '0,/^  \(rate_hz: .*\)/s//  \1\n  rate_hz: 20.0/' "$src" >"$T/duplicate_$b.yaml"
  { cat "$src"; printf 'main:\n  fusion: information\n'; } >"$T/duplicate_top_$b.yaml"
  { cat "$src"; printf -- '---\nmain: {}\n'; } >"$T/second_doc_$b.yaml"
  sed -e 's/^  rate_hz: .*/  rate_hz: .nan/' -e 's/^    gate_probability: .*/    gate_probability: nan/' \
      -e 's/^  publish_rate_hz: .*/  publish_rate_hz: .NaN/' "$src" >"$T/nan_$b.yaml"
  sed -e 's/^  rate_hz: .*/  rate_hz: .inf/' -e 's/^    gate_probability: .*/    gate_probability: -.inf/' \
      -e 's/^  publish_rate_hz: .*/  publish_rate_hz: +.Inf/' "$src" >"$T/inf_$b.yaml"
  { cat "$src"; head -c 1100000 /dev/zero | tr '\0' '#'; echo; } >"$T/huge_$b.yaml"
done
printf 'scenario:\n  frames: 1\x00\x01\x02\xfe\xff garbage\n' >"$T/garbage.yaml"
printf 'scenario:\n  frames: \xc3\x28\n' >"$T/bad_utf8.yaml"
mkdir "$T/a_directory"
mkfifo "$T/a_fifo"

for p in $PROGRAMS; do
  b=$(basename "${BASE[$p]}" .yaml)
  # shellcheck disable=SC2086  # ARGS are word lists without spaces in the paths
  run=("$BIN/$p" ${ARGS[$p]})
  expect "$p non-scalar key" "non-scalar key" -- "${run[@]}" --config "$T/nonscalar_$b.yaml"
  expect "$p nested non-scalar key" "robot: a non-scalar key" -- "${run[@]}" --config "$T/nonscalar_nested_$b.yaml"
  dup_key=scenario.rate_hz
  [ "$b" = mrclam ] && dup_key=dataset.rate_hz
  expect "$p duplicate key" "$dup_key: duplicate key" -- "${run[@]}" --config "$T/duplicate_$b.yaml"
  expect "$p duplicate section" "main: duplicate key" -- "${run[@]}" --config "$T/duplicate_top_$b.yaml"
  expect "$p second document" "a second YAML document" -- "${run[@]}" --config "$T/second_doc_$b.yaml"
  expect "$p nan" "${NAN_KEY[$p]}: not a finite number" -- "${run[@]}" --config "$T/nan_$b.yaml"
  expect "$p inf" "${NAN_KEY[$p]}: not a finite number" -- "${run[@]}" --config "$T/inf_$b.yaml"
  expect "$p huge file" "huge_$b.yaml" "larger than" -- "${run[@]}" --config "$T/huge_$b.yaml"
  expect "$p garbage" "garbage.yaml" "NUL byte" -- "${run[@]}" --config "$T/garbage.yaml"
  expect "$p invalid UTF-8" "bad_utf8.yaml" "not valid UTF-8" -- "${run[@]}" --config "$T/bad_utf8.yaml"
  expect "$p /dev/zero" "/dev/zero" "not a regular file" -- "${run[@]}" --config /dev/zero
  expect "$p directory" "a_directory" "not a regular file" -- "${run[@]}" --config "$T/a_directory"
  expect "$p FIFO" "a_fifo" "not a regular file" -- "${run[@]}" --config "$T/a_fifo"
  expect "$p missing file" "$T/missing.yaml" "no such file" -- "${run[@]}" --config "$T/missing.yaml"
done

# Numeric options: nan and inf are not numbers; out-of-range values name the range.
opt() {  # opt PROGRAM OPTION VALUE WANT [ARGS...]
  local p=$1 o=$2 v=$3 w=$4
  shift 4
  expect "$p $o $v" "$o" "$w" -- "$BIN/$p" "$@" "$o" "$v"
}
P=(--config "$PAPER")
M=(--config "$MRCLAM" --dataset "$TINY")
for v in nan inf -inf NaN; do
  opt simulator --speed "$v" "not a finite number" "${P[@]}" --check --dynamism 50
  opt simulator --rate "$v" "not a finite number" "${P[@]}" --check
  opt scenario_dump --speed "$v" "not a finite number" "${P[@]}" --check --out "$T/d.csv"
  opt run_scenario --speed "$v" "not a finite number" "${P[@]}" --check
  opt run_scenario --dynamism "$v" "not a finite number" "${P[@]}" --check
  opt robot_node --status-period "$v" "not a finite number" "${P[@]}" --robot 1 --check
  opt evaluate --speed "$v" "not a finite number" --log "$T/tiny.lcmlog" --quiet
  opt run_dataset --rate "$v" "not a finite number" "${M[@]}" --check --out "$T/ds"
  opt mrclam_import --start "$v" "not a finite number" "${M[@]}" --check --out "$T/x.lcmlog"
  opt mrclam_stats --detect-range "$v" "not a finite number" "${M[@]}" --check
  opt monitor --interval "$v" "not a finite number"
  opt viewer --rate "$v" "not a finite number" "${P[@]}"
  opt sweep --speed "0.5,$v" "not a finite number" "${P[@]}" --check --out "$T/sweep"
done
opt simulator --speed -5 "out of range" "${P[@]}" --check
opt scenario_dump --speed -5 "out of range" "${P[@]}" --check --out "$T/d.csv"
opt scenario_dump --speed 1001 "out of range" "${P[@]}" --check --out "$T/d.csv"
opt scenario_dump --dynamism 101 "out of range" "${P[@]}" --check --out "$T/d.csv"
opt scenario_dump --seed -1 "out of range" "${P[@]}" --check --out "$T/d.csv"
opt run_scenario --speed -0.5 "out of range" "${P[@]}" --check
opt run_scenario --frames 0 "out of range" "${P[@]}" --check
opt sweep --dynamism 5,-20 "out of range" "${P[@]}" --check --out "$T/sweep"
opt sweep --runs 0 "out of range" "${P[@]}" --check --out "$T/sweep"
opt evaluate --dynamism 150 "out of range" --log "$T/tiny.lcmlog" --quiet
opt evaluate --seed -2 "out of range" --log "$T/tiny.lcmlog" --quiet
opt robot_node --status-period 0 "out of range" "${P[@]}" --robot 1 --check
opt robot_node --robot 17 "out of range" "${P[@]}" --check
opt robot_node --robot 9 "not in robot.limits.team" "${P[@]}" --check
opt main_robot --event-queue 0 "out of range" "${P[@]}" --check
opt run_dataset --start -1 "out of range" "${M[@]}" --check --out "$T/ds"
opt mrclam_import --rate 0 "out of range" "${M[@]}" --check --out "$T/x.lcmlog"
opt mrclam_stats --rate 1e9 "out of range" "${M[@]}" --check
opt monitor --interval -1 "out of range"
opt viewer --port 70000 "out of range" "${P[@]}"
opt viewer --rate 0 "out of range" "${P[@]}"
opt viewer --max-clients 0 "out of range" "${P[@]}"
opt viewer --bind localhost "not an IPv4 or IPv6 address" "${P[@]}"
expect "viewer bad namespace" "viewer: cannot open the network namespace" -- "$BIN/viewer" "${P[@]}" --port 0 \
  --http-netns "$T/no_such_netns"

echo "bad_inputs: $checks checks, $failures failed"
[ "$failures" -eq 0 ]

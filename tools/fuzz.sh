#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Fuzz the inputs from outside with libFuzzer (clang), under AddressSanitizer and
# UndefinedBehaviorSanitizer: every message handler of robot_node and main_robot
# (decode + validate + apply, through the node shell as in the processes), the receive
# path from raw udpm:// datagrams up to those handlers (fuzz_datagrams: reassembly,
# dispatch, authentication), the config loader, the state loaders and the MRCLAM
# parser (fuzz/, docs/security.md).
#
#   tools/fuzz.sh [--seconds S | --runs N] [--targets "fuzz_config fuzz_state ..."]
#                 [--jobs J] [--max-len BYTES] [--build-dir DIR] [--keep-corpus]
#
# - Installs clang and libFuzzer when missing (tools/setup.sh --with-fuzz),
#   configures DIR (default build/fuzz) with clang and ELASLAM_FUZZ=ON, builds the
#   targets.
# - Runs each target for S seconds (default 30) or N executions, from its seed corpus
#   fuzz/corpus/<target>/ (copied: the committed corpus is never changed) plus what
#   earlier runs found (DIR/corpus/<target>/; --keep-corpus keeps it between runs,
#   default: start from the seeds). --max-len bounds a mutated input (default
#   131072: a burst of messages, a config, a state file; tools/fuzz_campaign.sh
#   uses libFuzzer's own default, 4096, for speed). A crash, a leak, a sanitizer report, an escaping
#   exception or an input slower than 10 s fails the target; its input is saved in
#   DIR/artifacts/ (reproduce: DIR/bin/<target> DIR/artifacts/<file>).
# - Prints per target: executions, executions/s, corpus size, result; exit 0 when
#   every target ran clean, 1 otherwise, 2 bad arguments.
set -euo pipefail
ROOT="$(cd "$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")/.." && pwd)"
BUILD_DIR="$ROOT/build/fuzz"
SECONDS_PER_TARGET=30
RUNS=""
TARGETS="fuzz_robot_node fuzz_main_robot fuzz_config fuzz_state fuzz_mrclam fuzz_viewer fuzz_datagrams"
JOBS=1
MAX_LEN=131072
KEEP=0
die() { echo "fuzz.sh: $*" >&2; exit 2; }
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds|--runs|--targets|--jobs|--max-len|--build-dir) [ $# -ge 2 ] || die "$1 needs a value (see --help)" ;;&
    --seconds) [[ "$2" =~ ^[1-9][0-9]*$ ]] || die "--seconds must be a positive integer, got '$2'"
               SECONDS_PER_TARGET="$2"; shift 2 ;;
    --runs) [[ "$2" =~ ^[1-9][0-9]*$ ]] || die "--runs must be a positive integer, got '$2'"; RUNS="$2"; shift 2 ;;
    --targets) TARGETS="$2"; shift 2 ;;
    --max-len) [[ "$2" =~ ^[1-9][0-9]*$ ]] || die "--max-len must be a positive integer, got '$2'"; MAX_LEN="$2"; shift 2 ;;
    --jobs) [[ "$2" =~ ^[1-9][0-9]*$ ]] || die "--jobs must be a positive integer, got '$2'"; JOBS="$2"; shift 2 ;;
    --build-dir) BUILD_DIR="$2"; shift 2 ;;
    --keep-corpus) KEEP=1; shift ;;
    -h|--help) sed -n '3,/^set -e/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) die "unknown argument '$1' (see --help)" ;;
  esac
done
for t in $TARGETS; do
  [ -f "$ROOT/fuzz/$t.cpp" ] || die "no such target: $t (fuzz/*.cpp)"
done

mkdir -p "$BUILD_DIR" || die "cannot create $BUILD_DIR"
BUILD_DIR="$(cd "$BUILD_DIR" && pwd)"
"$ROOT/tools/setup.sh" --with-fuzz --no-python >&2
if [ ! -f "$BUILD_DIR/build.ninja" ]; then
  CC=clang CXX=clang++ cmake -S "$ROOT" -B "$BUILD_DIR" -G Ninja -DELASLAM_FUZZ=ON -DELASLAM_BUILD_TESTS=OFF \
    -DELASLAM_BUILD_BENCH=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
fi
# shellcheck disable=SC2086
cmake --build "$BUILD_DIR" --target $TARGETS -j "$(nproc)" >&2 || { echo "fuzz.sh: the build failed" >&2; exit 1; }

mkdir -p "$BUILD_DIR/artifacts"
failed=0
printf '%-18s %12s %10s %8s  %s\n' target executions "exec/s" corpus result
for t in $TARGETS; do
  corpus="$BUILD_DIR/corpus/$t"
  [ "$KEEP" -eq 1 ] || rm -rf "$corpus"
  mkdir -p "$corpus"
  log="$BUILD_DIR/$t.log"
  limit=(-max_total_time="$SECONDS_PER_TARGET")
  [ -z "$RUNS" ] || limit=(-runs="$RUNS")
  jobs=()
  [ "$JOBS" -eq 1 ] || jobs=(-jobs="$JOBS" -workers="$JOBS")
  rm -f "$BUILD_DIR"/fuzz-*.log
  rc=0
  # -timeout: one input. TMPDIR: fuzz_mrclam writes its five files per input; on
  # tmpfs when there is one (on ext4 the truncations were 60 % of its time).
  tmp="${TMPDIR:-}"
  [ -n "$tmp" ] || { [ -d /dev/shm ] && [ -w /dev/shm ] && tmp=/dev/shm; } || tmp=/tmp
  (cd "$BUILD_DIR" && TMPDIR="$tmp" ASAN_OPTIONS=detect_leaks=1 "$BUILD_DIR/bin/$t" "${limit[@]}" -max_len="$MAX_LEN" -timeout=10 -rss_limit_mb=3072 \
    "${jobs[@]}" -print_final_stats=1 -artifact_prefix="$BUILD_DIR/artifacts/$t-" \
    "$corpus" "$ROOT/fuzz/corpus/$t") >"$log" 2>&1 || rc=$?
  # With --jobs each job writes its own log (fuzz-N.log), which libFuzzer also copies
  # into ours as the job ends: the figures are read from the job logs, once each.
  logs=("$log")
  [ "$JOBS" -eq 1 ] || logs=("$BUILD_DIR"/fuzz-*.log)
  # (0 when a log has no figures, as after a crash: the result below says FAILED.)
  execs=$(cat "${logs[@]}" 2>/dev/null | awk '/stat::number_of_executed_units/ { s += $2 } END { print s + 0 }' || true)
  rate=$(cat "${logs[@]}" 2>/dev/null | awk '/stat::average_exec_per_sec/ { s += $2 } END { print s + 0 }' || true)
  n=$(find "$corpus" -type f | wc -l)
  if [ "$rc" -eq 0 ] && ! cat "$log" "${logs[@]}" 2>/dev/null | grep -q "ERROR: \|SUMMARY: \|escaped\|deadly signal"; then
    result=clean
  else
    result="FAILED (exit $rc; $log)"
    failed=1
  fi
  printf '%-18s %12s %10s %8s  %s\n' "$t" "$execs" "$rate" "$n" "$result"
  if [ "$result" != clean ]; then grep -m5 "ERROR\|SUMMARY\|escaped\|fuzz_" "$log" | sed 's/^/    /' || true; fi
done
exit $failed

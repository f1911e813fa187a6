#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# A long fuzzing campaign, in resumable chunks: runs tools/fuzz.sh on one target at
# a time for CHUNK seconds with the corpus kept (--keep-corpus), and records every
# chunk in a ledger, until each target has run EXECUTIONS executions in total.
# Stopped at any instant (a reboot, a session's end), it loses at most the chunk
# under way and goes on from the ledger and the corpus when started again.
#
#   tools/fuzz_campaign.sh [--executions N] [--chunk SECONDS] [--targets "..."] [--jobs J]
#                          [--max-len BYTES] [--build-dir DIR] [--ledger DIR] [--status]
#
# - --executions: the goal per target (default 10000000).
# - --chunk: seconds per fuzz.sh run (default 600). The next chunk goes to the target
#   with the fewest executions so far, so all targets advance together.
# - --jobs: fuzzing processes per chunk (default 1; fuzz.sh --jobs): J processes on
#   the chunk's target for CHUNK seconds each, their executions summed in its line.
# - --max-len: bound on a mutated input (default 4096, libFuzzer's own default:
#   several times faster than fuzz.sh's 131072; the seeds, real recordings up to
#   130 KB, are read whole).
# - --ledger: where the ledger lives (default fuzz/ledger/, in the repository: a campaign
#   outlives the machine it ran on, and each session's chunks are committed with its
#   work): one line per chunk in <target>.tsv: UTC time, commit, executions, exec/s,
#   corpus, result. A line whose commit is "summary" stands for chunks whose own lines
#   were lost (its result says where the figure was recorded).
# - --status: print the totals and exit.
# To pause it, kill it (it resumes from the ledger and the corpus); do not SIGSTOP a
# chunk (the watchdog then reports a false timeout: mark that line's result "void:...").
# Exit 0 when every target reached the goal clean, 1 when a chunk failed (its
# artefact is in DIR/artifacts/; the campaign stops there, and goes on for that
# target once the commit has changed: the fix), 2 bad arguments. Executions of
# every chunk count, the failed ones' included.
set -euo pipefail
ROOT="$(cd "$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")/.." && pwd)"
GOAL=10000000
CHUNK=600
TARGETS="fuzz_robot_node fuzz_main_robot fuzz_config fuzz_state fuzz_mrclam fuzz_datagrams"
MAX_LEN=4096
JOBS=1
BUILD_DIR="$ROOT/build/fuzz"
LEDGER="$ROOT/fuzz/ledger"
STATUS=0
die() { echo "fuzz_campaign.sh: $*" >&2; exit 2; }
posint() { [[ "$2" =~ ^[1-9][0-9]*$ ]] || die "$1 must be a positive integer, got '$2'"; }
while [ $# -gt 0 ]; do
  case "$1" in
    --executions|--chunk|--targets|--jobs|--max-len|--build-dir|--ledger) [ $# -ge 2 ] || die "$1 needs a value (see --help)" ;;&
    --executions) posint "$1" "$2"; GOAL="$2"; shift 2 ;;
    --chunk) posint "$1" "$2"; CHUNK="$2"; shift 2 ;;
    --targets) TARGETS="$2"; shift 2 ;;
    --max-len) posint "$1" "$2"; MAX_LEN="$2"; shift 2 ;;
    --jobs) posint "$1" "$2"; JOBS="$2"; shift 2 ;;
    --build-dir) BUILD_DIR="$2"; shift 2 ;;
    --ledger) LEDGER="$2"; shift 2 ;;
    --status) STATUS=1; shift ;;
    -h|--help) sed -n '3,/^set -e/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) die "unknown argument '$1' (see --help)" ;;
  esac
done
for t in $TARGETS; do [ -f "$ROOT/fuzz/$t.cpp" ] || die "no such target: $t (fuzz/*.cpp)"; done
mkdir -p "$LEDGER" || die "cannot create $LEDGER"

total() { [ -f "$LEDGER/$1.tsv" ] && awk -F'\t' '{ s += $3 } END { print s + 0 }' "$LEDGER/$1.tsv" || echo 0; }
# A failed chunk stops the campaign for its target until the commit changes (the fix).
# A result beginning with "void" marks a chunk whose failure was not the code's (a
# chunk stopped with SIGSTOP: libFuzzer's watchdog counts wall time and reports the
# input under way as a timeout); its executions still count.
failed_before() { [ -f "$LEDGER/$1.tsv" ] && awk -F'\t' -v c="$commit" '$6 ~ /^FAILED/ && $2 == c { f = 1 } END { exit !f }' "$LEDGER/$1.tsv"; }
failures() { [ -f "$LEDGER/$1.tsv" ] && awk -F'\t' '$6 ~ /^FAILED/ { n++ } END { print n + 0 }' "$LEDGER/$1.tsv" || echo 0; }
report() {
  printf '%-18s %14s %8s  %s\n' target executions chunks result
  for t in $TARGETS; do
    n=0; [ -f "$LEDGER/$t.tsv" ] && n=$(wc -l <"$LEDGER/$t.tsv")
    r="clean"; f=$(failures "$t"); [ "$f" -eq 0 ] || r="clean since the fix of $f failed chunk(s) (see $LEDGER/$t.tsv)"
    failed_before "$t" && r="FAILED at this commit (see $LEDGER/$t.tsv)"
    [ "$n" -gt 0 ] || r="not run"
    printf '%-18s %14s %8s  %s\n' "$t" "$(total "$t")" "$n" "$r"
  done
}
# The commit a chunk's build is made from: each chunk rebuilds the target from the
# tree as it is then, so it is read again before every chunk. The ledger itself is
# not the code under test: appending to it does not make the tree dirty.
code_commit() {
  local c
  c=$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)
  git -C "$ROOT" diff --quiet HEAD -- . ':(exclude)fuzz/ledger' 2>/dev/null || c="$c+dirty"
  echo "$c"
}
commit=$(code_commit)
if [ "$STATUS" -eq 1 ]; then report; exit 0; fi
while :; do
  commit=$(code_commit)
  next=""; least=""
  for t in $TARGETS; do
    failed_before "$t" && { echo "fuzz_campaign.sh: $t failed in an earlier chunk; fix it first" >&2; report; exit 1; }
    n=$(total "$t")
    [ "$n" -lt "$GOAL" ] || continue
    if [ -z "$least" ] || [ "$n" -lt "$least" ]; then next="$t"; least="$n"; fi
  done
  [ -n "$next" ] || break
  echo "fuzz_campaign.sh: $next, $least of $GOAL executions so far; a chunk of ${CHUNK}s" >&2
  out=$("$ROOT/tools/fuzz.sh" --targets "$next" --seconds "$CHUNK" --jobs "$JOBS" --max-len "$MAX_LEN" --keep-corpus \
        --build-dir "$BUILD_DIR") && rc=0 || rc=$?
  line=$(printf '%s\n' "$out" | awk -v t="$next" '$1 == t')
  execs=$(awk '{ print $2 + 0 }' <<<"$line"); rate=$(awk '{ print $3 + 0 }' <<<"$line")
  corpus=$(awk '{ print $4 + 0 }' <<<"$line")
  result=clean; [ "$rc" -eq 0 ] || result="FAILED:exit_$rc"
  printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$(date -u +%FT%TZ)" "$commit" "${execs:-0}" "${rate:-0}" "${corpus:-0}" "$result" \
    >>"$LEDGER/$next.tsv"
  [ "$rc" -eq 0 ] || { printf '%s\n' "$out"; report; exit 1; }
done
report

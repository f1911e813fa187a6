#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tools/lcm_floor (LCM's own one-way latency at a rate): inside a private network
# namespace (port 7850), 200 messages at 1 kHz all arrive and the quantiles it prints
# are ordered and positive; bad numbers on the command line exit 2 naming the option.
#   lcm_floor_check.sh BUILD_DIR
set -uo pipefail
BUILD="$1"
ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
BIN="$BUILD/bin/lcm_floor"
fail() { echo "lcm_floor_check: FAIL: $*" >&2; exit 1; }
[ -x "$BIN" ] || fail "no $BIN"
for bad in "--rate nan" "--rate 0" "--count 5" "--size 8" "--size 1e9" "--rate"; do
  # shellcheck disable=SC2086
  out=$("$BIN" $bad 2>&1); rc=$?
  [ "$rc" -eq 2 ] || fail "'$bad' exited $rc, not 2: $out"
  [[ "$out" == *--* ]] || fail "'$bad' did not name the option: $out"
done
out=$("$ROOT/tools/netns_run.sh" --port 7850 -- "$BIN" --rate 1000 --count 200 2>&1); rc=$?
[ "$rc" -eq 77 ] && { echo "lcm_floor_check: SKIP (no network namespace: $out)"; exit 77; }
[ "$rc" -eq 0 ] || fail "exit $rc: $out"
echo "$out"
re='200 of 200 received, one-way p50 / p90 / p99 / max ([0-9]+) / ([0-9]+) / ([0-9]+) / ([0-9]+) us'
[[ "$out" =~ $re ]] || fail "unexpected output: $out"
p50=${BASH_REMATCH[1]} p90=${BASH_REMATCH[2]} p99=${BASH_REMATCH[3]} max=${BASH_REMATCH[4]}
[ "$p50" -gt 0 ] && [ "$p50" -le "$p90" ] && [ "$p90" -le "$p99" ] && [ "$p99" -le "$max" ] ||
  fail "quantiles out of order: $p50 / $p90 / $p99 / $max"
echo "lcm_floor_check: PASS"

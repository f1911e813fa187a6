# SPDX-License-Identifier: Apache-2.0
# Sourced by the system tests (tests/system/*.sh): wait for a condition with a
# deadline instead of sleeping for a fixed time.
#
#   wait_for DEADLINE_S DESCRIPTION COMMAND [ARGS...]
#
# Runs COMMAND (its output discarded) every 0.1 s until it succeeds, and returns 0
# as soon as it does. When DEADLINE_S seconds (a whole or decimal number) pass
# first, it prints "<caller>: FAIL: DESCRIPTION did not happen within DEADLINE_S s"
# and what COMMAND said on a last try, on stderr, and returns 1. DESCRIPTION names
# the condition ("the recording holds every robot's POSE of frame 149").
# Safe under `set -e` (a caller that wants the failure to end the script writes
# `wait_for ... || exit 1`).

# DEADLINE_S in microseconds (bash arithmetic has no fractions).
_wait_for_us() {
  local s="${1%%.*}" f=""
  [[ "$1" == *.* ]] && f="${1#*.}"
  f="${f}000000"
  echo $((10#${s:-0} * 1000000 + 10#${f:0:6}))
}

wait_for() {
  local deadline="$1" what="$2"
  shift 2
  [[ "$deadline" =~ ^[0-9]+(\.[0-9]+)?$ ]] || { echo "wait_for: bad deadline '$deadline'" >&2; return 2; }
  local end=$((${EPOCHREALTIME//[.,]/} + $(_wait_for_us "$deadline")))
  until "$@" > /dev/null 2>&1; do
    if [ "${EPOCHREALTIME//[.,]/}" -ge "$end" ]; then
      echo "$(basename "${BASH_SOURCE[1]:-$0}" .sh): FAIL: $what did not happen within ${deadline} s" >&2
      echo "  (the check, $*, said on a last try:)" >&2
      "$@" 2>&1 | tail -n 5 | sed 's/^/    /' >&2 || true
      return 1
    fi
    sleep 0.1
  done
}

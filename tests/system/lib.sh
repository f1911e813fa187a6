# SPDX-License-Identifier: Apache-2.0
# Sourced by the system tests (tests/system/*.sh) after they set ROOT and PY: the
# preamble and the process handling they share, and wait_for (wait_for.sh).
#
#   needs_netns NAME [--venv]  exit 77 (ctest: skipped), saying why, unless this is
#                              root with `ip netns`, and with --venv the project's
#                              .venv (tools/setup.sh makes it) is there
#   make_out NAME              OUT: a fresh folder, removed at exit unless KEEP_OUT
#                              is set (then its path is printed)
#   kill_pids_at_exit          PIDS=(), and every process put in PIDS is killed at exit
#   stop_pids                  SIGINT to every process in PIDS, then wait for each;
#                              returns 1 when one exited with an error; PIDS=()

# shellcheck source=tests/system/wait_for.sh
. "$(dirname "${BASH_SOURCE[0]}")/wait_for.sh"

needs_netns() {
  local name="$1"
  [ "$(id -u)" -eq 0 ] || { echo "$name: skipped (needs root for network namespaces)"; exit 77; }
  ip netns list >/dev/null 2>&1 || { echo "$name: skipped (no ip netns)"; exit 77; }
  if [ "${2:-}" = "--venv" ] && [ ! -x "$PY" ]; then
    echo "$name: skipped (no .venv with the Python lcm; tools/setup.sh makes it)"
    exit 77
  fi
}

make_out() {
  OUT="$(mktemp -d)"
  if [ -n "${KEEP_OUT:-}" ]; then
    echo "$1: output in $OUT"
  else
    trap 'rm -rf "$OUT"' EXIT
  fi
}

kill_pids_at_exit() {
  PIDS=()
  trap 'for p in "${PIDS[@]}"; do kill -KILL "$p" 2>/dev/null || true; done' EXIT
}

stop_pids() {
  local p rc=0
  for p in "${PIDS[@]}"; do kill -INT "$p" 2>/dev/null || true; done
  for p in "${PIDS[@]}"; do wait "$p" || rc=1; done
  PIDS=()
  return $rc
}

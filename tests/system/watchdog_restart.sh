#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# System test `system_watchdog`: systemd's watchdog restarts a hung node. A transient
# service (systemd-run) runs robot_node as the units do (Type=notify, WatchdogSec=,
# Restart=on-failure) with WatchdogSec=2s, on memq:// (no network: PrivateNetwork=yes
# besides); once it is active, its process is stopped with SIGSTOP (a hang: the loop
# turns no more, so no WATCHDOG=1), and the test waits for systemd to kill it
# (SIGABRT, "Watchdog timeout"; a stopped process takes no SIGABRT, so SIGKILL after
# TimeoutAbortSec=2s) and start a new process that says READY=1 again.
# Prints the time from the hang to the new process being active.
# Needs systemd as PID 1 (a booted machine or a systemd container) and root: exit 77
# (skipped) otherwise, with the reason.
#   tests/system/watchdog_restart.sh BUILD_DIR
set -euo pipefail
BUILD="$(cd "${1:?usage: watchdog_restart.sh BUILD_DIR}" && pwd)"
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
skip() { echo "SKIP: $*"; exit 77; }

[ "$(id -u)" -eq 0 ] || skip "needs root (a system service)"
[ "$(cat /proc/1/comm 2>/dev/null)" = systemd ] ||
  skip "systemd is not PID 1 here (PID 1 is '$(cat /proc/1/comm 2>/dev/null)'): no service manager to run a unit"
command -v systemd-run >/dev/null || skip "no systemd-run"
state="$(systemctl is-system-running 2>/dev/null || true)"
case "$state" in running|degraded) ;; *) skip "the system manager is '$state', not running" ;; esac
[ -x "$BUILD/bin/robot_node" ] || { echo "FAIL: $BUILD/bin/robot_node is not built" >&2; exit 1; }

UNIT="elaslam-watchdog-test-$$"
cleanup() { systemctl stop "$UNIT" >/dev/null 2>&1 || true; systemctl reset-failed "$UNIT" >/dev/null 2>&1 || true; }
trap cleanup EXIT
prop() { systemctl show -p "$1" --value "$UNIT"; }
# wait_for SECONDS COMMAND...: true once COMMAND succeeds, polled every 0.1 s.
wait_for() {
  local end=$((SECONDS + $1)); shift
  until "$@"; do [ $SECONDS -lt $end ] || return 1; sleep 0.1; done
}

# systemd-run waits for READY=1 (Type=notify): it returns once the node is ready.
systemd-run --unit "$UNIT" --quiet --collect=no \
  -p Type=notify -p WatchdogSec=2s -p Restart=on-failure -p RestartSec=200ms -p PrivateNetwork=yes \
  -p TimeoutAbortSec=2s \
  "$BUILD/bin/robot_node" --robot 1 --config "$ROOT/config/paper.yaml" --lcm-url memq://
[ "$(prop ActiveState)" = active ] || { echo "FAIL: $UNIT is not active after start" >&2; exit 1; }
pid="$(prop MainPID)"
[ "$(prop NRestarts)" = 0 ] || { echo "FAIL: restarted before the hang" >&2; exit 1; }
# Alive: the watchdog does not fire while the loop turns (3 periods).
sleep 6
[ "$(prop MainPID)" = "$pid" ] || { echo "FAIL: a healthy node was restarted (pings not seen?)" >&2; journalctl -u "$UNIT" --no-pager | tail -20; exit 1; }

t0=$(date +%s.%N)
kill -STOP "$pid"
new_active() { [ "$(prop NRestarts)" -ge 1 ] && [ "$(prop ActiveState)" = active ] && [ "$(prop MainPID)" != "$pid" ]; }
if ! wait_for 30 new_active; then
  echo "FAIL: no restart within 30 s of the hang (WatchdogSec=2s)" >&2
  journalctl -u "$UNIT" --no-pager | tail -20
  exit 1
fi
t1=$(date +%s.%N)
journalctl -u "$UNIT" --no-pager | grep -q "Watchdog timeout" ||
  { echo "FAIL: the journal does not say 'Watchdog timeout'" >&2; exit 1; }
awk -v a="$t0" -v b="$t1" 'BEGIN { printf "watchdog: hung node restarted and ready again after %.1f s (WatchdogSec=2s, TimeoutAbortSec=2s, RestartSec=200ms)\n", b - a }'
echo "PASS"

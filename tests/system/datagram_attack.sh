#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# System test `system_datagrams` (docs/security.md "Bytes from the network"): a keyed
# live team (simulator, main_robot, every robot_node, the viewer, the monitor and the
# recorder, each its own process on LCM) while a process without any key sends malformed datagrams
# to the team's group the whole run (raw_datagrams.py: the two-datagram pair that made
# every keyed process die with SIGSEGV in the authentication layer, every prefix of a
# valid datagram, fragments with every size field at its extremes, impossible channel
# names). Passes when every process ran to the end and exited cleanly, every robot
# processed every frame, and each process that reads the network the whole run counted the
# malformed datagrams ("refused a datagram"). Before the team received with its own
# checked path (transport/udpm_receiver.hpp), liblcm's receive thread died on the
# fragments (SIGSEGV in every process, lcm-logger too) and the authentication layer
# on the cut short message (a payload size of -1).
# Needs root and ip netns (exit 77 otherwise).
#   tests/system/datagram_attack.sh BUILD_DIR
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
HERE="$ROOT/tests/system"
# shellcheck source=tests/system/lib.sh
. "$ROOT/tests/system/lib.sh"
CONFIG="$ROOT/config/paper.yaml"
ARGS=(--dynamism 50 --speed 0.5 --seed 5 --frames 80)

if [ "${1:-}" = "--inner" ]; then  # inside the namespace: --inner BUILD OUT KEYS [run_team.sh args]
  BUILD="$2" OUT="$3" KEYS="$4"
  shift 4
  # A monitor of its own, to see it live through the attack and exit cleanly.
  "$BUILD/bin/monitor" --config "$CONFIG" --roster "$KEYS/team.yaml" --interval 1 > "$OUT.monitor.txt" 2>&1 &
  MONITOR=$!
  python3 "$HERE/raw_datagrams.py" --rounds 100000 --period 1.0 > "$OUT.attacker.txt" 2>&1 &
  ATTACKER=$!
  trap 'kill -TERM $ATTACKER $MONITOR 2>/dev/null || true' EXIT
  rc=0
  "$ROOT/tools/run_team.sh" --inside --build-dir "$BUILD" --out "$OUT" --no-baseline --keys "$KEYS" "$@" \
    < /dev/null || rc=$?
  kill -TERM $ATTACKER 2>/dev/null || true
  wait $ATTACKER || true
  if ! kill -0 $MONITOR 2>/dev/null; then
    wait $MONITOR && mrc=0 || mrc=$?
    echo "datagrams: the monitor ended during the run (exit $mrc)"
    rc=1
  else
    kill -INT $MONITOR
    wait $MONITOR && mrc=0 || mrc=$?
    [ "$mrc" -eq 0 ] || { echo "datagrams: the monitor exited $mrc"; rc=1; }
  fi
  trap - EXIT
  exit $rc
fi

BUILD="$(cd "${1:?usage: datagram_attack.sh BUILD_DIR}" && pwd)"
needs_netns datagrams
make_out datagrams
fail() { echo "datagrams: $*"; exit 1; }
ROBOTS=($("$BUILD/bin/simulator" --config "$CONFIG" --list-robots))

"$BUILD/bin/keys" team "$OUT/keys" --robots "$(IFS=,; echo "${ROBOTS[*]}")" > /dev/null
rc=0
"$ROOT/tools/netns_run.sh" --port 7724 -- "$0" --inner "$BUILD" "$OUT/run" "$OUT/keys" --view 0 "${ARGS[@]}" \
  > "$OUT/run.txt" 2>&1 || rc=$?
cat "$OUT/run.attacker.txt" 2>/dev/null || true
if [ "$rc" -ne 0 ]; then
  tail -n 30 "$OUT/run.txt"
  for f in "$OUT"/run/logs/*.log; do echo "== $f"; tail -n 4 "$f"; done
  fail "the attacked keyed team did not run to the end (exit $rc)"
fi
grep -q "sent [1-9]" "$OUT/run.attacker.txt" || fail "the attacker sent nothing"
for r in "${ROBOTS[@]}"; do
  grep -q "^robot_node $r: frames=80 " "$OUT/run/logs/robot_node_$r.log" ||
    { tail -n 3 "$OUT/run/logs/robot_node_$r.log"; fail "robot $r did not process every frame"; }
done
# (The simulator listens only until every node has announced itself: it ran to the
# end, run_team.sh says so, but it may have heard no attack.)
for log in logs/main_robot logs/viewer logs/logger "${ROBOTS[@]/#/logs/robot_node_}" ../run.monitor.txt; do
  f="$OUT/run/$log.log"
  [ "$log" != ../run.monitor.txt ] || f="$OUT/run.monitor.txt"
  [ -f "$f" ] || fail "no log of $log"
  grep -q "refused a datagram" "$f" ||
    { tail -n 5 "$f"; fail "$log did not count the cut datagrams"; }
done
echo "datagrams: every process of the keyed team survived the malformed datagrams and refused them:"
grep -h -m1 "refused a datagram" "$OUT"/run/logs/*.log | sed 's/^/  /'

#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# System test (system_foxglove): tools/run_team.sh --foxglove PORT, as a user runs it.
#   1. The team runs 150 frames at 10 Hz in its private namespace (LCM port 7860); the
#      Foxglove bridge (tools/foxglove_bridge.py) serves it on the host's loopback.
#   2. A Foxglove WebSocket client (tests/system/foxglove_client.py, subprotocol
#      foxglove.sdk.v1) connects from the host, reads the advertised channels and
#      subscribes to all: the expected channels are there with Foxglove's schema names,
#      and every robot's poses arrive at 9 or more in every second of the steady part of
#      the run; the per-robot stats carry a NEES and pose sigmas; /map arrives.
#   3. Meanwhile 5 other clients connect, subscribe and drop their connection without a
#      close frame, and 3 rounds of malformed LCM datagrams (tests/system/raw_datagrams.py)
#      are sent into the team's namespace once poses flow: the bridge counts them
#      (/bridge malformed_datagrams > 0) and the poses keep their rate.
#   4. Every key of the last /robot1/stats and /bridge is in docs/data_dictionary.md;
#      run_team.sh printed the ws:// URL and the bridge's final report; the bridge
#      stopped with the team (the client saw the server close; the port refuses).
# Exit 77 (skip) without root or ip netns, or when foxglove-sdk or websocket-client
# cannot be installed into the project's .venv.
#   tests/system/foxglove.sh BUILD_DIR        (KEEP_OUT=1: keep the output)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
HERE="$ROOT/tests/system"
# shellcheck source=tests/system/lib.sh
. "$ROOT/tests/system/lib.sh"
BUILD="$(cd "${1:?usage: foxglove.sh BUILD_DIR}" && pwd)"
LCM_PORT=7860
needs_netns foxglove
PY="$ROOT/.venv/bin/python"
[ -x "$PY" ] || "$ROOT/tools/setup.sh" --build-dir "$BUILD" >/dev/null 2>&1 || true
if ! "$PY" -c 'import foxglove, websocket' 2>/dev/null; then
  "$ROOT/.venv/bin/pip" install -q --disable-pip-version-check -r "$ROOT/tools/requirements.txt" >/dev/null 2>&1 || true
  "$PY" -c 'import foxglove, websocket' 2>/dev/null ||
    { echo "foxglove: skipped (cannot install foxglove-sdk and websocket-client into $ROOT/.venv)"; exit 77; }
fi
make_out foxglove
FPORT=$((20000 + RANDOM % 20000))

"$ROOT/tools/run_team.sh" --build-dir "$BUILD" --out "$OUT/team" --frames 150 --no-baseline --no-progress \
  --port "$LCM_PORT" --foxglove "$FPORT" < /dev/null > "$OUT/team.txt" 2>&1 &
TEAM=$!
"$PY" "$HERE/foxglove_client.py" "ws://127.0.0.1:$FPORT" --robots 1 2 3 --timeout 150 --connect-timeout 120 \
  --churn 5 --flowing "$OUT/flowing" --json "$OUT/client.json" --dump "$OUT" > "$OUT/client.txt" 2>&1 &
CLIENT=$!

rc=0
# 3. Malformed datagrams into the team's namespace (the bridge's), once poses flow.
for _ in $(seq 1200); do
  [ ! -f "$OUT/flowing" ] && kill -0 "$CLIENT" 2>/dev/null || break
  sleep 0.1
done
bpid=$(sed -n 's/^foxglove_bridge: LCM .*(pid \([0-9]*\))$/\1/p' "$OUT/team/logs/foxglove.log" 2>/dev/null || true)
# The bridge serves in the host's namespace (--ws-netns): its parent, the run_team.sh
# inside the team's namespace, is where the team's LCM is. Never the host's own.
tns=""
[ -z "$bpid" ] || tns="/proc/$(ps -o ppid= -p "$bpid" | tr -d ' ')/ns/net"
if [ -n "$tns" ] && [ "$(readlink "$tns" 2>/dev/null)" = "$(readlink /proc/self/ns/net)" ]; then
  echo "foxglove: FAIL the team's namespace is not a private one ($tns): no malformed datagrams sent"; tns=""; rc=1
fi
if [ -f "$OUT/flowing" ] && [ -n "$tns" ]; then
  nsenter --net="$tns" python3 "$HERE/raw_datagrams.py" --url "udpm://239.255.76.67:$LCM_PORT?ttl=0" \
    --rounds 3 --period 0.5 > "$OUT/attack.txt" 2>&1 || { echo "foxglove: FAIL sending malformed datagrams"; cat "$OUT/attack.txt"; rc=1; }
  echo "foxglove: $(tail -n 1 "$OUT/attack.txt")"
elif [ "$rc" -eq 0 ]; then
  echo "foxglove: FAIL poses never flowed to the client (or no bridge pid): no malformed datagrams sent"; rc=1
fi

crc=0; wait "$CLIENT" || crc=$?
trc=0; wait "$TEAM" || trc=$?
cat "$OUT/client.txt"
[ "$crc" -eq 0 ] || { echo "foxglove: FAIL the client's checks (exit $crc)"; rc=1; }
if [ "$trc" -ne 0 ]; then
  echo "foxglove: FAIL run_team.sh --foxglove exited $trc"; tail -n 20 "$OUT/team.txt"
  for f in "$OUT"/team/logs/*.log; do [ -f "$f" ] && { echo "--- $f"; tail -n 5 "$f"; }; done
  rc=1
fi
grep "Foxglove" "$OUT/team.txt" || true
grep -q "^run_team.sh: Foxglove: ws://127.0.0.1:$FPORT " "$OUT/team.txt" ||
  { echo "foxglove: FAIL run_team.sh printed no ws:// URL"; rc=1; }
grep -q "^run_team.sh: Foxglove ws://127.0.0.1:$FPORT stopped with the team; it served" "$OUT/team.txt" ||
  { echo "foxglove: FAIL run_team.sh printed no final report of the bridge"; rc=1; }
malformed=$(python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["bridge"].get("malformed_datagrams", 0))' \
  "$OUT/client.json" 2>/dev/null || echo 0)
echo "foxglove: the bridge counted $malformed malformed datagrams and skipped them"
[ "$malformed" -gt 0 ] || { echo "foxglove: FAIL the bridge counted no malformed datagram"; rc=1; }
# Every key of the JSON channels is in docs/data_dictionary.md.
python3 "$ROOT/tests/docs/data_dictionary_check.py" "$ROOT/docs/data_dictionary.md" "$OUT/robot_stats.json" \
  "$OUT/bridge.json" || rc=1
if [ -n "$bpid" ] && kill -0 "$bpid" 2>/dev/null; then echo "foxglove: FAIL the bridge outlived the team"; rc=1; fi
if python3 -c 'import socket, sys; socket.create_connection(("127.0.0.1", int(sys.argv[1])), 1)' "$FPORT" 2>/dev/null; then
  echo "foxglove: FAIL port $FPORT still accepts connections after the run"; rc=1
fi
[ "$rc" -eq 0 ] && echo "foxglove: PASS" || echo "foxglove: FAIL"
exit $rc

#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# log_merge (tools/log_merge.cpp): logs written here byte by byte in LCM's log format
# (big-endian: magic 0xEDA1DA01, event number, timestamp, channel length, data length,
# channel, data) are merged into one in timestamp order, ties in the inputs' order,
# events renumbered from 0; a truncated input is merged up to its last whole event
# and said; bad arguments exit 2 naming the problem, an existing OUT needs --force.
#   tests/tools/log_merge_check.sh BUILD_DIR
set -euo pipefail
BIN="$(cd "${1:?usage: log_merge_check.sh BUILD_DIR}" && pwd)/bin"
T="$(mktemp -d)"
trap 'rm -rf "$T"' EXIT
fail() { echo "log_merge_check: $*"; exit 1; }
# write LOG "timestamp:channel:data"...: a log with those events (event numbers 100, 101, ...)
write() {
  python3 - "$@" <<'PY'
import struct, sys
with open(sys.argv[1], "wb") as f:
    for n, ev in enumerate(sys.argv[2:]):
        t, ch, data = ev.split(":")
        f.write(struct.pack(">IqqII", 0xEDA1DA01, 100 + n, int(t), len(ch), len(data)) + ch.encode() + data.encode())
PY
}
# events LOG: one line per event, "eventnum timestamp channel data"
events() {
  python3 - "$1" <<'PY'
import struct, sys
b = open(sys.argv[1], "rb").read()
i = 0
while i < len(b):
    magic, num, t, cl, dl = struct.unpack(">IqqII", b[i:i + 28])
    assert magic == 0xEDA1DA01
    i += 28
    print(num, t, b[i:i + cl].decode(), b[i + cl:i + cl + dl].decode())
    i += cl + dl
PY
}
write "$T/a.lcmlog" 10:POSE_1:a1 30:POSE_1:a2 50:POSE_1:a3
write "$T/b.lcmlog" 20:SENSOR_1:b1 30:SENSOR_1:b2 60:SENSOR_1:b3
write "$T/c.lcmlog"
"$BIN/log_merge" "$T/m.lcmlog" "$T/b.lcmlog" "$T/a.lcmlog" "$T/c.lcmlog" > "$T/out.txt" ||
  fail "merge failed: $(cat "$T/out.txt")"
grep -q "6 events from 3 logs" "$T/out.txt" || fail "summary: $(cat "$T/out.txt")"
expected="0 10 POSE_1 a1
1 20 SENSOR_1 b1
2 30 SENSOR_1 b2
3 30 POSE_1 a2
4 50 POSE_1 a3
5 60 SENSOR_1 b3"
[ "$(events "$T/m.lcmlog")" = "$expected" ] || fail "merged: $(events "$T/m.lcmlog")"

# OUT exists: refused without --force (exit 2), replaced with it.
rc=0; "$BIN/log_merge" "$T/m.lcmlog" "$T/a.lcmlog" 2> "$T/err.txt" || rc=$?
[ "$rc" -eq 2 ] && grep -q "exists (--force" "$T/err.txt" || fail "existing OUT: exit $rc, $(cat "$T/err.txt")"
"$BIN/log_merge" --force "$T/m.lcmlog" "$T/a.lcmlog" > /dev/null
[ "$(events "$T/m.lcmlog" | wc -l)" -eq 3 ] || fail "--force did not replace OUT"

# A truncated input (a recorder killed mid-write): its whole events, and a message.
head -c -3 "$T/b.lcmlog" > "$T/cut.lcmlog"
"$BIN/log_merge" -f "$T/m.lcmlog" "$T/a.lcmlog" "$T/cut.lcmlog" > "$T/out.txt" 2> "$T/err.txt" ||
  fail "truncated input: $(cat "$T/err.txt")"
grep -q "cut.lcmlog: a truncated or corrupt tail after 2 events" "$T/err.txt" || fail "truncated: $(cat "$T/err.txt")"
[ "$(events "$T/m.lcmlog" | wc -l)" -eq 5 ] || fail "truncated: $(events "$T/m.lcmlog")"

# Bad arguments: exit 2, the problem named.
bad() {  # bad WHAT EXPECTED_TEXT ARGS...
  local what="$1" text="$2" rc=0; shift 2
  "$BIN/log_merge" "$@" > /dev/null 2> "$T/err.txt" || rc=$?
  [ "$rc" -eq 2 ] && grep -q -- "$text" "$T/err.txt" || fail "$what: exit $rc, $(cat "$T/err.txt")"
}
bad "no input" "IN is required" "$T/x.lcmlog"
bad "a missing input" "nope.lcmlog" "$T/x.lcmlog" "$T/nope.lcmlog"
echo "not a log" > "$T/text.txt"
bad "not a log" "text.txt" "$T/x.lcmlog" "$T/text.txt"
bad "input is output" "both an input and the output" -f "$T/a.lcmlog" "$T/a.lcmlog"
[ ! -e "$T/x.lcmlog" ] || fail "a refused merge left $T/x.lcmlog"
echo "log_merge_check: ok"

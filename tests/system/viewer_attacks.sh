#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# System test (system_viewer_attacks): the viewer as a hardened HTTP service
# (docs/security.md, "The viewer as an HTTP service"). A real viewer (--lcm-url memq://: it needs no LCM
# traffic) is attacked by tests/system/viewer_attacks.py, one case after the other,
# its VmRSS read during each (bound: 64 MB):
#   1. on 127.0.0.1 (no root needed): a flood of 8 KB header lines (431, memory flat),
#      the head limits (431, 414, 413, 411, 400), 40 slowloris connections (/state.json
#      answers within 1 s; each closed within 10 s), 100 idle connections from one
#      address (the surplus refused at once with 503), 8 event streams never read (new
#      browsers get a stream; the stalled ones are closed within 15 s); then the viewer
#      still answers and stops with exit 0 on SIGINT;
#   2. the start: a --bind that is not loopback without a token, or with a token file
#      that fails its checks, is refused (exit 2); --make-token makes a 0600 file and
#      never overwrites one or follows a link;
#   3. (root) the viewer on 0.0.0.0 with --token-file in a network namespace, its
#      clients in a second one joined by a veth pair (10.200.0.1 and 10.200.0.2): the
#      printed URL carries the token; requests from 10.200.0.2 need it (401 without or
#      with a wrong one, 200 with a bearer header or ?token=), from 127.0.0.1 not;
#      headless Chromium (when there is one and the .venv) opens the page with
#      ?token= from 10.200.0.2 and receives states over the event stream.
# Exit 0: all passed; 1: a failure; 77: step 3 skipped (not root, or no ip netns)
# after steps 1 and 2 passed.
#   tests/system/viewer_attacks.sh BUILD_DIR        (KEEP_OUT=1: keep the output)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
HERE="$ROOT/tests/system"
BUILD="$(cd "${1:?usage: viewer_attacks.sh BUILD_DIR}" && pwd)"
VIEWER="$BUILD/bin/viewer"
CONFIG="$ROOT/config/paper.yaml"
[ -x "$VIEWER" ] || { echo "viewer_attacks: no $VIEWER (build the viewer target)"; exit 1; }
# shellcheck source=tools/viewer_url.sh
. "$ROOT/tools/viewer_url.sh"
OUT="$(mktemp -d)"
PIDS=() NS=""
cleanup() {
  for p in "${PIDS[@]}"; do kill -KILL "$p" 2>/dev/null || true; done
  [ -z "$NS" ] || ip netns del "$NS" 2>/dev/null || true
  [ -n "${KEEP_OUT:-}" ] && echo "viewer_attacks: output in $OUT" || rm -rf "$OUT"
}
trap cleanup EXIT
rc=0
fail() { echo "viewer_attacks: FAIL $*"; rc=1; }

# Starts a viewer (its arguments after the common ones; a prefix command in $WRAP):
# sets PID and URL, or fails the test.
start_viewer() {
  local name="$1"; shift
  ${WRAP:-} "$VIEWER" --config "$CONFIG" --lcm-url memq:// --port 0 "$@" > "$OUT/$name.out" 2> "$OUT/$name.err" &
  PID=$!
  PIDS+=("$PID")
  URL=$(wait_viewer_url "$OUT/$name.out" "$PID" 100)
  [ -n "$URL" ] || { echo "viewer_attacks: $name: no URL"; cat "$OUT/$name.err"; exit 1; }
}

# --- 1. the attacks, on loopback
start_viewer loop --max-clients 8
echo "viewer_attacks: viewer $PID at $URL"
for c in flood limits slowloris crowd streams; do
  python3 "$HERE/viewer_attacks.py" "$c" "$URL" --pid "$PID" --rss-mb 64 --max-clients 8 || fail "case $c"
done
code=$(curl -s -o /dev/null -w '%{http_code}' --max-time 2 "${URL}state.json" || true)
[ "$code" = 200 ] || fail "/state.json after the attacks: $code"
kill -INT "$PID"
wait "$PID" && echo "viewer_attacks: the viewer stopped with exit 0 after the attacks" ||
  fail "the viewer exited with $? after the attacks"
echo "viewer_attacks: what the viewer said of them:"
sed 's/^/  /' "$OUT/loop.err"

# --- 2. the start
expect_exit() {  # expect_exit CODE WORDS WHAT -- ARGS...
  local want="$1" words="$2" what="$3"; shift 4
  local got=0
  timeout 10 "$VIEWER" --config "$CONFIG" --lcm-url memq:// --port 0 "$@" > "$OUT/start.out" 2> "$OUT/start.err" || got=$?
  if [ "$got" -ne "$want" ] || ! grep -q -- "$words" "$OUT/start.err"; then
    fail "$what: exit $got (expected $want, saying '$words'): $(head -c 300 "$OUT/start.err")"
  else
    echo "viewer_attacks: $what: exit $got, '$(head -n 1 "$OUT/start.err" | cut -c 1-110)...'"
  fi
}
expect_exit 2 "--token-file" "--bind 0.0.0.0 without a token" -- --bind 0.0.0.0
expect_exit 2 "--token-file" "--bind 10.200.0.1 without a token" -- --bind 10.200.0.1
expect_exit 2 "--token-file" "--bind :: without a token" -- --bind ::
TOK="$OUT/viewer.token"
expect_exit 0 "made the token file" "--make-token" -- --make-token "$TOK"
[ "$(stat -c %a "$TOK")" = 600 ] && [ "$(wc -c < "$TOK")" -eq 65 ] || fail "--make-token: $(stat -c '%a %s' "$TOK")"
cp "$TOK" "$OUT/before"
expect_exit 1 "never overwritten" "--make-token over an existing file" -- --make-token "$TOK"
cmp -s "$TOK" "$OUT/before" || fail "--make-token changed an existing file"
ln -s "$OUT/target" "$OUT/dangling"
expect_exit 1 "File exists" "--make-token onto a dangling link" -- --make-token "$OUT/dangling"
[ ! -e "$OUT/target" ] || fail "--make-token wrote through a link"
cp "$TOK" "$OUT/open.token" && chmod 644 "$OUT/open.token"
expect_exit 2 "chmod 600" "--token-file readable by others" -- --bind 0.0.0.0 --token-file "$OUT/open.token"
ln -s "$TOK" "$OUT/link.token"
expect_exit 2 "symbolic link" "--token-file a symbolic link" -- --bind 0.0.0.0 --token-file "$OUT/link.token"
echo 1234 > "$OUT/short.token" && chmod 600 "$OUT/short.token"
expect_exit 2 "64 to 256" "--token-file too short" -- --bind 0.0.0.0 --token-file "$OUT/short.token"

# --- 3. the token, from a peer that is not loopback: the viewer in one namespace, the
# clients in another, joined by a veth pair (10.200.0.1 and 10.200.0.2).
if [ "$(id -u)" -ne 0 ] || ! ip netns list > /dev/null 2>&1; then
  echo "viewer_attacks: the token from a non-loopback peer skipped (needs root and ip netns)"
  [ "$rc" -eq 0 ] && exit 77 || exit 1
fi
NS="elaslam_va_$$_$RANDOM" NS2="elaslam_va_$$_${RANDOM}_peer"
cleanup_peer() { ip netns del "$NS2" 2>/dev/null || true; cleanup; }
trap cleanup_peer EXIT
ip netns add "$NS"
ip netns add "$NS2"
ip -n "$NS" link set lo up
ip -n "$NS2" link set lo up
ip -n "$NS" link add va type veth peer name vb netns "$NS2"
ip -n "$NS" addr add 10.200.0.1/24 dev va
ip -n "$NS2" addr add 10.200.0.2/24 dev vb
ip -n "$NS" link set va up
ip -n "$NS2" link set vb up
WRAP="ip netns exec $NS" start_viewer token --bind 0.0.0.0 --token-file "$TOK"
TOKEN="$(tr -d '\n' < "$TOK")"
PORT="${URL##*:}"; PORT="${PORT%%/*}"
case "$URL" in
  *"?token=$TOKEN") echo "viewer_attacks: the printed URL carries the token (http://127.0.0.1:$PORT/?token=...)" ;;
  *) fail "the printed URL has no token: $URL" ;;
esac
ip netns exec "$NS2" python3 "$HERE/viewer_attacks.py" token "http://10.200.0.1:$PORT/" --pid "$PID" \
  --source 10.200.0.2 --token "$TOKEN" || fail "case token"
code=$(ip netns exec "$NS" curl -s -o /dev/null -w '%{http_code}' --max-time 3 "http://127.0.0.1:$PORT/state.json" || true)
echo "viewer_attacks: token: /state.json from 127.0.0.1 without the token: $code"
[ "$code" = 200 ] || fail "/state.json from loopback without the token: $code, expected 200"
PY="$ROOT/.venv/bin/python"
if [ -x "$PY" ] && command -v chromium > /dev/null; then
  # The page passes its own ?token= on to /events and /state.json (viewer/web/index.html).
  ip netns exec "$NS2" "$PY" "$HERE/browser_check.py" "http://10.200.0.1:$PORT/?token=$TOKEN" \
    --out "$OUT/token.png" --seconds 2 --min-rate 0.5 > "$OUT/browser.txt" 2>&1 || fail "the page from 10.200.0.2"
  cat "$OUT/browser.txt"
  grep -q '"transport": "sse"' "$OUT/browser.txt" || fail "the page from 10.200.0.2 did not get the event stream"
else
  echo "viewer_attacks: the page in a browser skipped (no chromium or no .venv)"
fi
kill -INT "$PID"
wait "$PID" || fail "the token viewer exited with $?"
exit $rc

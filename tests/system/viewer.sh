#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# System test (system_viewer): the viewer shown a recorded run, in a real browser.
#   1. the live team records run.lcmlog (tools/run_team.sh in a private namespace);
#   2. in a second namespace the viewer starts (--port 0) and lcm-logplayer plays the
#      whole log into it at the recorded speed; headless Chromium loads the page
#      during the replay (tests/system/browser_check.py, over the DevTools protocol):
#      it receives states over Server-Sent Events at >= 10 per second, its frame
#      advances between two looks 2 s apart, it draws the 3 robots and the landmarks
#      and throws nothing; a screenshot is saved after the replay;
#      during the replay, 8 event streams that are never read (the most, --max-clients)
#      leave /state.json answering at once, a 9th browser gets a stream within 10 s
#      all the same (it evicts a stalled one), the viewer closes the stalled ones
#      within 15 s, and the count of clients is back to 0 once all close
#      (tests/system/viewer_clients.py);
#   3. /state.json after the replay equals the log's last POSE_<r> of each robot and
#      its GLOBAL_MAP assembled from the chunks (tests/system/viewer_check.py), and
#      every key of it is in docs/data_dictionary.md;
#   4. tools/run_team.sh --view PORT: the team runs in its private namespace and the
#      page is reachable from here, the host side: /state.json polled during the run
#      shows the three robots and the frames advancing.
# Exit 77 (skip) without root / ip netns / the Python venv / lcm-logplayer / chromium.
#   tests/system/viewer.sh BUILD_DIR        (KEEP_OUT=1: keep the output, screenshots)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
HERE="$ROOT/tests/system"
# shellcheck source=tools/viewer_url.sh
. "$ROOT/tools/viewer_url.sh"
# shellcheck source=tests/system/lib.sh
. "$HERE/lib.sh"
# The viewer's /state.json (at URL $1) shows at least $2 robots with a pose and $3 landmarks.
state_shows() {
  curl -sf "$1/state.json" | python3 -c 'import json, sys
s = json.load(sys.stdin)
robots, landmarks = len([r for r in s["robots"] if r["x"] is not None]), len(s["landmarks"])
print(robots, "robots with a pose,", landmarks, "landmarks, frame", s["frame"])
sys.exit(0 if robots >= int(sys.argv[1]) and landmarks >= int(sys.argv[2]) else 1)' "$2" "$3"
}
# /state.json (at URL $1, saved to $4) agrees with log $3's last POSEs and GLOBAL_MAP
# (viewer_check.py with build $2).
state_is_log_end() {
  curl -sf "$1/state.json" > "$4" && "$ROOT/.venv/bin/python" "$HERE/viewer_check.py" --build-dir "$2" "$3" "$4"
}

# --- step 2, inside the replay namespace: viewer.sh --inside BUILD LOG OUT
if [ "${1:-}" = "--inside" ]; then
  BUILD="$2" LOG="$3" OUT="$4"
  mkdir -p "$OUT"
  "$BUILD/bin/viewer" --config "$ROOT/config/paper.yaml" --port 0 > "$OUT/viewer.out" 2> "$OUT/viewer.err" &
  VIEWER=$!
  trap 'kill -KILL $VIEWER 2>/dev/null || true' EXIT
  URL=$(wait_viewer_url "$OUT/viewer.out" "$VIEWER" 100)
  URL="${URL%/}"
  [ -n "$URL" ] || { echo "viewer: no URL"; cat "$OUT/viewer.err"; exit 1; }
  lcm-logplayer "$LOG" > "$OUT/logplayer.log" 2>&1 &
  PLAYER=$!
  rc=0
  # The replay has reached the viewer: what browser_check.py asks to see drawn is there.
  wait_for 30 "the viewer's state showing 3 robots with a pose and 20 landmarks" state_shows "$URL" 3 20 || rc=1
  "$ROOT/.venv/bin/python" "$HERE/browser_check.py" "$URL/" --out "$OUT/during.png" --seconds 2 \
    --min-rate 10 --robots 3 --min-landmarks 20 --advancing || rc=1
  # Stalled and surplus browsers during the replay (tests/system/viewer_clients.py).
  "$ROOT/.venv/bin/python" "$HERE/viewer_clients.py" "$URL" --max 8 || rc=1
  wait "$PLAYER"
  # The viewer has taken in the whole log: its state equals the log's last poses and map.
  wait_for 20 "the viewer's state equal to the log's last POSEs and GLOBAL_MAP" \
    state_is_log_end "$URL" "$BUILD" "$LOG" "$OUT/state_end.json" || rc=1
  # Every track the state holds (the robots' and main's fused) is drawn as an arrow.
  arrows=$(python3 -c 'import json, sys
s = json.load(open(sys.argv[1]))
print(sum(len(r.get("tracks", [])) for r in s["robots"] if r["x"] is not None) + len(s["global_tracks"]))' \
    "$OUT/state_end.json")
  echo "viewer: $arrows tracks in the state at the log's end"
  "$ROOT/.venv/bin/python" "$HERE/browser_check.py" "$URL/" --out "$OUT/after.png" --seconds 0.5 --robots 3 \
    --arrows "$arrows" || rc=1
  curl -sf "$URL/state.json" > "$OUT/state.json"
  code=$(curl -s -o /dev/null -w '%{http_code}' "$URL/no-such-page")
  kill -INT "$VIEWER"; wait "$VIEWER" || { echo "viewer: exited with an error"; cat "$OUT/viewer.err"; exit 1; }
  trap - EXIT
  echo "viewer: unknown path answered $code"
  exit $rc
fi

BUILD="$(cd "${1:?usage: viewer.sh BUILD_DIR}" && pwd)"
needs_netns viewer
PY="$ROOT/.venv/bin/python"
[ -x "$PY" ] || { echo "viewer: skipped (no .venv with the Python lcm; tools/setup.sh makes it)"; exit 77; }
command -v lcm-logplayer >/dev/null || { echo "viewer: skipped (no lcm-logplayer)"; exit 77; }
command -v chromium >/dev/null || { echo "viewer: skipped (no chromium: tools/setup.sh --with-test-tools)"; exit 77; }
make_out viewer

"$ROOT/tools/netns_run.sh" --port 7730 -- "$ROOT/tools/run_team.sh" --inside --build-dir "$BUILD" \
  --out "$OUT/live" --frames 80 > "$OUT/live.txt" 2>&1 || { cat "$OUT/live.txt"; exit 1; }
rc=0
"$ROOT/tools/netns_run.sh" --port 7731 -- "$0" --inside "$BUILD" "$OUT/live/run.lcmlog" "$OUT/view" \
  > "$OUT/view.txt" 2>&1 || rc=1
cat "$OUT/view.txt"
"$PY" "$HERE/viewer_check.py" --build-dir "$BUILD" "$OUT/live/run.lcmlog" "$OUT/view/state.json" || rc=1
# Every key of the state is in docs/data_dictionary.md.
python3 "$ROOT/tests/docs/data_dictionary_check.py" "$ROOT/docs/data_dictionary.md" "$OUT/view/state.json" || rc=1
[ -s "$OUT/view/after.png" ] || { echo "viewer: FAIL no screenshot"; rc=1; }
grep -q "answered 404" "$OUT/view.txt" || { echo "viewer: FAIL an unknown path is not 404"; rc=1; }

# 4. run_team.sh --view: served on the host side of the team's namespace.
VPORT=$((20000 + RANDOM % 20000))
"$ROOT/tools/run_team.sh" --build-dir "$BUILD" --out "$OUT/team" --frames 60 --rate 20 --no-baseline --no-progress \
  --port 7732 --view "$VPORT" < /dev/null > "$OUT/team.txt" 2>&1 &
TEAM=$!
frames=()
for _ in $(seq 200); do
  if s=$(curl -sf "http://127.0.0.1:$VPORT/state.json" 2>/dev/null); then
    f=$(python3 -c 'import json, sys; s = json.load(sys.stdin); print(s["frame"], len([r for r in s["robots"] if r["x"] is not None]))' <<<"$s")
    frames+=("$f")
  fi
  kill -0 "$TEAM" 2>/dev/null || break
  sleep 0.1
done
wait "$TEAM" || {
  echo "viewer: FAIL run_team.sh --view failed"; tail -n 20 "$OUT/team.txt"
  for f in "$OUT"/team/logs/*.log; do [ -f "$f" ] && { echo "--- $f"; tail -n 5 "$f"; }; done  # where it stopped
  rc=1
}
grep -q "the viewer: http://127.0.0.1:$VPORT/" "$OUT/team.txt" || { echo "viewer: FAIL run_team.sh printed no viewer URL"; rc=1; }
first=none last=none  # no look at all: the failure below, not a bash error on an empty array
[ "${#frames[@]}" -eq 0 ] || { first="${frames[0]}"; last="${frames[-1]}"; }
echo "viewer: run_team.sh --view: ${#frames[@]} looks from the host, first (frame robots) $first, last $last"
read -r f1 _ <<<"$first"; read -r f2 n2 <<<"$last"
[ "${#frames[@]}" -ge 2 ] && [ "${f2:-0}" -gt "${f1:-0}" ] && [ "${n2:-0}" -eq 3 ] ||
  { echo "viewer: FAIL the page of a team in its namespace was not seen advancing from the host"; rc=1; }
exit $rc

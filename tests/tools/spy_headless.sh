#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# System test of tools/spy.sh: lcm-spy starts headless (Xvfb), opens its "LCM Spy"
# window, decodes the simulator's channels with the elaslam types, and a screenshot
# of it is kept in <build>/tests/spy/spy.png (with spy.log, table.txt, windows.txt).
#
#   tests/tools/spy_headless.sh BUILD_DIR [HAVE_JAR_TARGET]
#
# HAVE_JAR_TARGET (1/0, from CMake): whether the build has the elaslam_lcmtypes_jar
# target (it has none without a JDK; then the test is skipped).
# Everything (Xvfb, lcm-spy, simulator) runs inside a private network namespace
# (tools/netns_run.sh --port 7702), so no LCM traffic leaves it.
# Exit 77 (ctest: skipped) when not root, or Xvfb, X tools, ImageMagick or a JDK are
# missing (tools/setup.sh --with-test-tools installs them).
# What lcm-spy shows is read from inside its JVM by a small Java agent
# (SpyTableDump.java, through JAVA_TOOL_OPTIONS): its channel table, row by row.
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
PORT=7702

if [ "${1:-}" != --inside ]; then
  BUILD="$(cd "${1:?usage: spy_headless.sh BUILD_DIR [HAVE_JAR_TARGET]}" && pwd)"
  HAVE_JAR="${2:-1}"
  skip() { echo "spy_headless: skipped: $*"; exit 77; }
  [ "$(id -u)" -eq 0 ] || skip "needs root (network namespace for the LCM traffic)"
  [ "$HAVE_JAR" = 1 ] || skip "the build has no elaslam_lcmtypes_jar target (no JDK or liblcm-java at configure time)"
  for tool in Xvfb xwininfo import identify java javac jar; do
    command -v "$tool" >/dev/null 2>&1 ||
      skip "'$tool' is missing (tools/setup.sh --with-test-tools installs xvfb, x11-utils, imagemagick, openjdk-17-jdk-headless)"
  done
  [ -x "$BUILD/bin/simulator" ] || { echo "spy_headless: $BUILD/bin/simulator is not built"; exit 1; }
  exec "$ROOT/tools/netns_run.sh" --port "$PORT" -- "$0" --inside "$BUILD"
fi

# ---- inside the namespace -------------------------------------------------------------
BUILD="$2"
OUT="$BUILD/tests/spy"
FRAMES=60
RATE=20
rm -rf "$OUT"
mkdir -p "$OUT"
echo "spy_headless: LCM $LCM_DEFAULT_URL; output in $OUT"

XVFB_PID=""
SPY_PID=""
SIM_PID=""
# Stop a process (for lcm-spy: its process group, setsid below) and wait for it, bounded.
stop() {
  local pid=$1 group=${2:-}
  [ -n "$pid" ] || return 0
  if kill -0 "$pid" 2>/dev/null; then
    if [ -n "$group" ]; then kill -TERM -- "-$pid" 2>/dev/null || true; else kill -TERM "$pid" 2>/dev/null || true; fi
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    if kill -0 "$pid" 2>/dev/null; then
      if [ -n "$group" ]; then kill -KILL -- "-$pid" 2>/dev/null || true; else kill -KILL "$pid" 2>/dev/null || true; fi
    fi
  fi
  wait "$pid" 2>/dev/null || true
}
cleanup() {
  stop "$SIM_PID"
  stop "$SPY_PID" group
  stop "$XVFB_PID"
}
trap cleanup EXIT
trap 'exit 143' TERM
trap 'exit 130' INT
trap 'exit 129' HUP

FAILS=()
fail() { FAILS+=("$*"); echo "spy_headless: FAIL: $*"; }
finish() {
  if [ ${#FAILS[@]} -gt 0 ]; then
    echo "--- lcm-spy output ($OUT/spy.log) ---"; cat "$OUT/spy.log" 2>/dev/null || true
    echo "--- lcm-spy table ($OUT/table.txt) ---"; cat "$OUT/table.txt" 2>/dev/null || true
    echo "spy_headless: ${#FAILS[@]} failure(s)"
    exit 1
  fi
  echo "spy_headless: ok (screenshot: $OUT/spy.png)"
  exit 0
}

# The agent that reads lcm-spy's table from inside its JVM.
mkdir -p "$OUT/agent/classes"
javac -nowarn -d "$OUT/agent/classes" "$HERE/SpyTableDump.java"
printf 'Premain-Class: SpyTableDump\n' > "$OUT/agent/manifest.txt"
jar cfm "$OUT/agent/spy_table_dump.jar" "$OUT/agent/manifest.txt" -C "$OUT/agent/classes" .

# Xvfb on a free display: -displayfd makes it pick one and tell us which. -noreset:
# otherwise it resets when its last client leaves (each xwininfo poll below), and a
# client connecting during the reset (java) is refused.
Xvfb -displayfd 3 -screen 0 1280x800x24 -nolisten tcp -noreset 3>"$OUT/xvfb.display" >"$OUT/xvfb.log" 2>&1 &
XVFB_PID=$!
for _ in $(seq 100); do
  [ -s "$OUT/xvfb.display" ] && break
  kill -0 "$XVFB_PID" 2>/dev/null || break
  sleep 0.1
done
[ -s "$OUT/xvfb.display" ] || { cat "$OUT/xvfb.log"; echo "spy_headless: Xvfb did not start"; exit 1; }
export DISPLAY=":$(tr -d '[:space:]' < "$OUT/xvfb.display")"
echo "spy_headless: Xvfb on $DISPLAY"

# lcm-spy, through the launcher under test (set-up and the jar build are no-ops when
# the build is up to date). setsid: its own process group, so cleanup reaches
# anything it starts; spy.sh execs java, so $SPY_PID is the JVM in the end.
JAVA_TOOL_OPTIONS="-javaagent:$OUT/agent/spy_table_dump.jar=$OUT/table.txt" \
  setsid "$ROOT/tools/spy.sh" --build-dir "$BUILD" >"$OUT/spy.log" 2>&1 &
SPY_PID=$!

# Its window (bounded: the launcher may have to build the jar first).
WINDOW=0
for _ in $(seq 600); do   # 600 x 0.2 s
  kill -0 "$SPY_PID" 2>/dev/null || break
  if xwininfo -root -tree > "$OUT/windows.txt" 2>/dev/null && grep -q '"LCM Spy"' "$OUT/windows.txt"; then
    WINDOW=1; break
  fi
  sleep 0.2
done
if [ "$WINDOW" -ne 1 ]; then
  kill -0 "$SPY_PID" 2>/dev/null && fail "no 'LCM Spy' window within 120 s" || fail "lcm-spy exited before its window appeared"
  finish
fi
echo "spy_headless: window: $(grep '"LCM Spy"' "$OUT/windows.txt" | sed 's/^ *//')"

# Traffic: the simulator's channels (SENSOR_<r>, GROUND_TRUTH, ...). The start delay
# lets lcm-spy subscribe (it opens its window first, then LCM).
read -r -a ROBOTS <<< "$("$BUILD/bin/simulator" --config "$ROOT/config/paper.yaml" --list-robots)"
"$BUILD/bin/simulator" --config "$ROOT/config/paper.yaml" --frames "$FRAMES" --rate "$RATE" \
  --start-delay-ms 1000 > "$OUT/simulator.log" 2>&1 &
SIM_PID=$!
EXPECT=(GROUND_TRUTH:ground_truth_t)
for r in "${ROBOTS[@]}"; do EXPECT+=("SENSOR_$r:sensor_frame_t"); done

# count CHANNEL: lcm-spy's "Num Msgs" for it (0 if no row yet); type CHANNEL: its "Type".
col() { awk -F'\t' -v ch="$1" -v c="$2" '$1 == "row" && $2 == ch { print $c; exit }' "$OUT/table.txt" 2>/dev/null || true; }
count() { local n; n="$(col "$1" 4)"; echo "${n:-0}"; }
all_at_least() {
  local e
  for e in "${EXPECT[@]}"; do [ "$(count "${e%%:*}")" -ge "$1" ] || return 1; done
}

# Screenshot while the traffic flows (2/3 of the frames seen on every channel, so
# that lcm-spy's once-a-second rates are up to date), bounded.
for _ in $(seq 150); do   # 150 x 0.2 s
  all_at_least $((FRAMES * 2 / 3)) && break
  kill -0 "$SIM_PID" 2>/dev/null || break
  sleep 0.2
done
sleep 0.2   # one repaint: the agent reads the table's model, the screen follows it
import -window root "$OUT/spy.png"

# The simulator ends by itself after FRAMES / RATE s (+1 s delay); bounded wait.
for _ in $(seq 150); do kill -0 "$SIM_PID" 2>/dev/null || break; sleep 0.2; done
if kill -0 "$SIM_PID" 2>/dev/null; then
  fail "the simulator did not finish within 30 s"
  stop "$SIM_PID"
  SIM_RC=1
else
  SIM_RC=0; wait "$SIM_PID" || SIM_RC=$?
fi
SIM_PID=""
[ "$SIM_RC" -eq 0 ] || { fail "simulator exited with $SIM_RC"; cat "$OUT/simulator.log"; }
# Let lcm-spy's table settle on the final counts (unchanged for 1 s; at most 10 s).
prev=""; same=0
for _ in $(seq 40); do
  now="$(for e in "${EXPECT[@]}"; do count "${e%%:*}"; done | tr '\n' ' ')"
  if [ "$now" = "$prev" ]; then same=$((same + 1)); [ "$same" -ge 4 ] && break; else same=0; fi
  prev="$now"
  sleep 0.25
done

# ---- checks ------------------------------------------------------------------------------
kill -0 "$SPY_PID" 2>/dev/null || fail "lcm-spy (java) died"
if grep -E 'Exception|ClassNotFound|NoClassDefFound|Unrecognized VM option|Error:' "$OUT/spy.log"; then
  fail "lcm-spy's output has errors (above)"
fi
grep -q 'Found [1-9][0-9]* LCM types' "$OUT/spy.log" || fail "lcm-spy did not report finding the LCM types"

# lcm-spy decoded our channels with our types (as its window shows them).
if [ ! -s "$OUT/table.txt" ]; then
  fail "no table from lcm-spy's window (the agent wrote nothing)"
else
  grep -q $'^window\tLCM Spy$' "$OUT/table.txt" || fail "the agent saw no 'LCM Spy' window"
  for e in "${EXPECT[@]}"; do
    ch="${e%%:*}"; want="${e#*:}"
    got="$(col "$ch" 3)"; n="$(count "$ch")"; undecodable="$(col "$ch" 9)"
    [ "$got" = "$want" ] || fail "$ch: type '$got' in lcm-spy, want '$want'"
    # udpm on a namespace's loopback at 20 Hz loses nothing in practice; allow some.
    [ "$n" -ge $((FRAMES / 2)) ] || fail "$ch: lcm-spy counted $n messages of $FRAMES"
    [ "$undecodable" = 0 ] || fail "$ch: $undecodable undecodable messages"
    echo "spy_headless: $ch: $want, $n of $FRAMES messages"
  done
  if awk -F'\t' '$1 == "row" && $3 ~ /^\?\?/' "$OUT/table.txt" | grep -q .; then
    fail "channels lcm-spy could not decode: $(awk -F'\t' '$1 == "row" && $3 ~ /^\?\?/ { printf "%s ", $2 }' "$OUT/table.txt")"
  fi
fi

# The screenshot: the whole screen, not one colour (a blank screen has 1).
if [ -s "$OUT/spy.png" ]; then
  info="$(identify -format '%w %h %k' "$OUT/spy.png" 2>/dev/null || true)"
  read -r w h colours <<< "${info:-0 0 0}"
  echo "spy_headless: screenshot $OUT/spy.png: ${w}x${h}, $colours colours"
  [ "$w" -eq 1280 ] && [ "$h" -eq 800 ] || fail "screenshot is ${w}x${h}, want 1280x800"
  [ "$colours" -ge 8 ] || fail "screenshot has $colours colours (blank window?)"
else
  fail "no screenshot"
fi
finish

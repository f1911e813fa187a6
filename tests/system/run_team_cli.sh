#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# System test `system_run_team_cli`: tools/run_team.sh as a user meets it.
# 1. Bad arguments are refused before anything starts (exit 2, the argument named,
#    no output directory, no set-up or build); a valid-looking combination the
#    scenario cannot run (--rate 0.1: robots would jump 12.7 m per frame) is refused
#    by the config check before any process starts.
# 2. A short live run shows the progress line (frame k/N, poses, moving landmarks)
#    and the summary with the in-process ekf baseline.
# 3. Ctrl-C (SIGINT to the terminal's process group, through a pseudo-terminal)
#    stops the run: exit 130, "interrupted", no process of the run left.
#   tests/system/run_team_cli.sh BUILD_DIR
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD="$(cd "${1:?usage: run_team_cli.sh BUILD_DIR}" && pwd)"
TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT
RT="$ROOT/tools/run_team.sh"
fail() { echo "run_team_cli: FAIL: $*"; exit 1; }
# shellcheck source=tests/system/wait_for.sh
. "$ROOT/tests/system/wait_for.sh"

# ---- 1. arguments checked first ---------------------------------------------------
refuse() {  # refuse WHAT-THE-ERROR-NAMES ARGS...
  local want="$1"; shift
  local out="$TMP/refused" rc=0
  ELASLAM_BUILD_DIR="$TMP/no-build" "$RT" --out "$out" "$@" > "$TMP/err" 2>&1 || rc=$?
  [ "$rc" -eq 2 ] || { cat "$TMP/err"; fail "run_team.sh $* exited $rc, not 2"; }
  grep -q -- "$want" "$TMP/err" || { cat "$TMP/err"; fail "run_team.sh $*: the error does not name '$want'"; }
  ! grep -q "setup:" "$TMP/err" || fail "run_team.sh $*: set-up ran before the arguments were checked"
  [ ! -e "$out" ] || fail "run_team.sh $*: created $out before the arguments were checked"
  [ ! -e "$TMP/no-build" ] || fail "run_team.sh $*: configured a build before the arguments were checked"
}
refuse --dynamism --dynamism 150
refuse --dynamism --dynamism abc
refuse --speed --speed -1
refuse --seed --seed 1.5
refuse --frames --frames 0
refuse --rate --rate 0
refuse --port --port 70000
refuse --mode --mode fast
refuse "no such config" --config /nonexistent.yaml
refuse "unknown argument" --no-such-option
refuse "--config needs a value" --config
refuse --foxglove --foxglove 70000
refuse "--foxglove needs the live team" --foxglove --in-process
refuse "need different ports" --view 9000 --foxglove 9000
echo "run_team_cli: 14 bad command lines refused before anything started"

[ "$(id -u)" -eq 0 ] && ip netns list >/dev/null 2>&1 || { echo "run_team_cli: skipped the live parts (needs root)"; exit 77; }
rc=0
"$RT" --build-dir "$BUILD" --rate 0.1 --out "$TMP/slow" > "$TMP/slow.txt" 2>&1 || rc=$?
[ "$rc" -eq 2 ] || { cat "$TMP/slow.txt"; fail "--rate 0.1 exited $rc, not 2"; }
grep -q "scenario.robots\[0\].speed_mps" "$TMP/slow.txt" || { cat "$TMP/slow.txt"; fail "--rate 0.1: no reason given"; }
[ ! -e "$TMP/slow/run.lcmlog" ] && [ ! -e "$TMP/slow/logs/simulator.log" ] || fail "--rate 0.1: the team was started"
echo "run_team_cli: --rate 0.1 refused by the config check before the team started"

# ---- 2. a short live run: progress line and baseline ---------------------------------
"$RT" --build-dir "$BUILD" --frames 40 --rate 20 --port 7703 --out "$TMP/live" > "$TMP/live.txt" 2>&1 ||
  { cat "$TMP/live.txt"; fail "the live run failed"; }
grep -Eq "^frame [0-9]+/40 \| poses [0-9]+ from 3 robots \| moving landmarks found [0-9]+" "$TMP/live.txt" ||
  { cat "$TMP/live.txt"; fail "no progress line"; }
grep -q "against ekf on the same scenario and seed" "$TMP/live.txt" || { cat "$TMP/live.txt"; fail "no ekf baseline"; }
grep -q "frames dropped: 0" "$TMP/live.txt" || { cat "$TMP/live.txt"; fail "frames dropped"; }
python3 - "$TMP/live/metrics.json" <<'PY' || fail "metrics.json provenance"
import json, sys
m = json.load(open(sys.argv[1]))
assert m["schema_version"] == 2 and m["elaslam_version"].startswith("0."), m["elaslam_version"]
assert m["config"]["scenario"]["frames"] == 40 and m["config"]["scenario"]["rate_hz"] == 20, m["config"]["scenario"]
assert m["run_info"]["source"] == "simulator" and m["run_info"]["frames"] == 40, m["run_info"]
assert m["baseline"]["mode"] == "ekf" and m["baseline"]["frames"] == 40, m["baseline"]
assert "evaluate" in m["command_line"], m["command_line"]
PY
echo "run_team_cli: live run with a progress line, the ekf baseline and provenance"

# ---- 3. Ctrl-C --------------------------------------------------------------------
python3 - "$RT" --build-dir "$BUILD" --port 7704 --out "$TMP/intr" > "$TMP/intr.txt" 2>&1 <<'PY'
import os, pty, select, sys, time
pid, fd = pty.fork()
if pid == 0:
    os.execv(sys.argv[1], sys.argv[1:])
out, sent, t0 = b"", False, time.time()
while True:
    if not sent and (b"| poses" in out or time.time() - t0 > 60):  # the team is running
        os.write(fd, b"\x03")  # Ctrl-C: the terminal sends SIGINT to its foreground process group
        sent = True
    r, _, _ = select.select([fd], [], [], 0.2)
    if fd in r:
        try:
            data = os.read(fd, 4096)
        except OSError:
            break
        if not data:
            break
        out += data
_, status = os.waitpid(pid, 0)
sys.stdout.write(out.decode(errors="replace"))
print(f"\nexit status {os.waitstatus_to_exitcode(status)}")
PY
grep -q "exit status 130" "$TMP/intr.txt" || { cat "$TMP/intr.txt"; fail "Ctrl-C: exit status not 130"; }
grep -q "run_team.sh: interrupted: the run did not finish" "$TMP/intr.txt" || { cat "$TMP/intr.txt"; fail "Ctrl-C: not said"; }
# run_team.sh reaps its processes before it exits; the deadline is slack for the
# kernel's bookkeeping only.
none_left() { ! pgrep -f "$TMP/intr" > /dev/null; }  # (in this shell: no command line naming it)
if ! wait_for 5 "the end of every process of the interrupted run" none_left; then
  pgrep -f "$TMP/intr" > "$TMP/left" && ps -fp $(cat "$TMP/left")
  fail "Ctrl-C: processes of the run left"
fi
echo "run_team_cli: Ctrl-C stopped the run (exit 130), nothing left"

#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# System test `system_insider` (docs/security.md, "Threat model"): a team member taken
# over, and an earlier mission's recording, against a live team with its keys.
#   1. a short run of mission M1 records run.lcmlog (another mission's, for step 3);
#   2. the team of mission M2 (the same keys), unattacked;
#   3. the same while insider.py, holding robot 3's key, signs messages in robot 2's,
#      main's and the simulator's names (events with a newer incarnation, notices,
#      sensor frames, the moving set), once a SENSOR_1 with the simulator's key and
#      a counter of 2^64 - 9, and once mid-run every SENSOR_1 of step 1's recording.
# Passes when the attacked team ends as the unattacked one (poses frame by frame and
# the final map, read with the roster), every robot processed every frame and none
# started over, and evaluate counts the insider's messages as signed by a key that
# is not the sender's (unknown_key) or by a sender that may not send them
# (wrong_sender), the far counter as a jump and the recording as another mission's.
# With a shared team key each of these was accepted (robot 2's stream taken over,
# notices applied, robot 1 driven 5 m off, robot 1 silenced, a new run started).
# Needs root and ip netns (exit 77 otherwise) and the .venv (tools/setup.sh).
#   tests/system/insider.sh BUILD_DIR
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
HERE="$ROOT/tests/system"
PY="$ROOT/.venv/bin/python"
# shellcheck source=tests/system/lib.sh
. "$ROOT/tests/system/lib.sh"
CONFIG="$ROOT/config/paper.yaml"
ARGS=(--dynamism 50 --speed 0.5 --seed 4)

if [ "${1:-}" = "--inner" ]; then  # inside a namespace: --inner BUILD OUT KEYS OLD_LOG [run_team.sh args]
  BUILD="$2" OUT="$3" KEYS="$4" OLD="$5"
  shift 5
  mkdir -p "$OUT"
  run_team_attacked "$OUT.insider.txt" "$PY" "$HERE/insider.py" --build-dir "$BUILD" --key "$KEYS/robot_3.key" \
    --sender 3 --roster "$KEYS/team.yaml" --silence-key "$KEYS/simulator.key" --replay "$OLD" --period 0.1 \
    -- --build-dir "$BUILD" --out "$OUT" --no-progress --no-baseline --keys "$KEYS" "$@"
fi

BUILD="$(cd "${1:?usage: insider.sh BUILD_DIR}" && pwd)"
needs_netns insider --venv
make_out insider
fail() { echo "insider: $*"; exit 1; }
ROBOTS=($("$BUILD/bin/simulator" --config "$CONFIG" --list-robots))
FRAMES=$(awk '/^scenario:/ {s = 1; next} /^[^ #]/ {s = 0} s && $1 == "frames:" {print $2; exit}' "$CONFIG")
# Mission M1's keys, and the same keys with mission M2.
"$BUILD/bin/keys" team "$OUT/m1" --robots "$(IFS=,; echo "${ROBOTS[*]}")" > /dev/null
mkdir -m 700 "$OUT/m2"
cp -p "$OUT"/m1/*.key "$OUT/m2/"
sed "s/^  mission: .*/  mission: \"$("$BUILD/bin/keys" mission)\"/" "$OUT/m1/team.yaml" > "$OUT/m2/team.yaml"
cmp -s "$OUT/m1/team.yaml" "$OUT/m2/team.yaml" && fail "the second mission's roster is the first's"

"$ROOT/tools/netns_run.sh" --port 7727 -- "$ROOT/tools/run_team.sh" --inside --build-dir "$BUILD" --out "$OUT/old" \
  --no-progress --no-baseline --keys "$OUT/m1" "${ARGS[@]}" --frames 40 > "$OUT/old.txt" 2>&1 || { cat "$OUT/old.txt"; exit 1; }
"$ROOT/tools/netns_run.sh" --port 7728 -- "$ROOT/tools/run_team.sh" --inside --build-dir "$BUILD" --out "$OUT/ref" \
  --no-progress --no-baseline --keys "$OUT/m2" "${ARGS[@]}" > "$OUT/ref.txt" 2>&1 || { cat "$OUT/ref.txt"; exit 1; }
"$ROOT/tools/netns_run.sh" --port 7729 -- "$0" --inner "$BUILD" "$OUT/attacked" "$OUT/m2" "$OUT/old/run.lcmlog" \
  "${ARGS[@]}" > "$OUT/attacked.txt" 2>&1 || { cat "$OUT/attacked.txt"; tail -n 5 "$OUT"/attacked/logs/*.log; exit 1; }
cat "$OUT/attacked.insider.txt"
grep -q "SENSOR_1 with counter 2^64-9" "$OUT/attacked.insider.txt" || fail "the far counter was not sent"
grep -q "SENSOR_1 of another mission's recording [1-9]" "$OUT/attacked.insider.txt" || fail "the old mission was not replayed"

for r in "${ROBOTS[@]}"; do
  grep -q "^robot_node $r: frames=$FRAMES gaps=0 duplicates=0 out_of_order=0 rejected=0 " \
    "$OUT/attacked/logs/robot_node_$r.log" || { tail -n 3 "$OUT/attacked/logs/robot_node_$r.log"; fail "robot $r's frames"; }
  ! grep -q "started over\|starting fresh" "$OUT/attacked/logs/robot_node_$r.log" || fail "robot $r started over"
done
check() { "$PY" "$HERE/lcm_check.py" --build-dir "$BUILD" --roster "$OUT/m2/team.yaml" "$@"; }
compare_attacked insider
python3 - "$OUT/attacked/metrics.json" <<'PY' || fail "evaluate's refusals"
import json, sys
a = json.load(open(sys.argv[1]))["authentication"]
by = a["refused_by_reason"]
print(f"insider: evaluate with the roster: {a['accepted']} verified, {a['refused']} refused {by}")
for reason in ("unknown_key", "wrong_sender", "other_mission", "jump"):
    assert by.get(reason, 0) > 0, f"no {reason} refusal"
PY
echo "insider: robot 3's key spoke for nobody else, the far counter silenced nobody, the old mission replayed nothing"

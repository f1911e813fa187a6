#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# System test `system_forger` (docs/security.md): a live team with its keys (each
# process its own, elaslam-keys team), attacked by a process on its LCM network
# without any of them (forger.py: forged
# LMAP_EVENT ADDs at (100, 100) from robot ids in and out of the team, DYNAMIC_NOTICEs,
# LMAP_SNAPSHOTs, POSEs, fake trailers, replayed, altered and moved genuine datagrams),
# ends as the same team unattacked: the robots' poses (compare-poses) and the final
# GLOBAL_MAP (compare-maps) of both recordings, read as a keyed node reads them
# (lcm_check.py --roster: only what verifies, each message once), are the same,
# following the rule of the other two-run tests: exit 0 of compare-poses (the same
# input, the same poses) requires the same map; exit 3 (notice timing differed) is
# reported, not failed. Every robot and main_robot reported auth_refused > 0.
# The unattacked keyed recording is read by evaluate (run_team.sh) and by the Python
# tools (decode_log.py): signed messages decode unchanged. evaluate and log_info with
# the roster (--roster) leave out what the nodes refused: the attacked recording scores
# as the unattacked one.
# Last, the same attack on the team without a key: its map is not the unattacked one
# (the attack is real; skipped with UNKEYED=0).
# Needs root and ip netns (exit 77 otherwise) and the .venv (tools/setup.sh).
#   [UNKEYED=1] tests/system/forger.sh BUILD_DIR
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
HERE="$ROOT/tests/system"
PY="$ROOT/.venv/bin/python"
# shellcheck source=tests/system/lib.sh
. "$ROOT/tests/system/lib.sh"
ARGS=(--dynamism 50 --speed 0.5 --seed 3)
CONFIG="$ROOT/config/paper.yaml"

if [ "${1:-}" = "--inner" ]; then  # inside a namespace: --inner BUILD OUT [run_team.sh args]
  BUILD="$2" OUT="$3"
  shift 3
  mkdir -p "$OUT"
  run_team_attacked "$OUT.forger.txt" "$PY" "$HERE/forger.py" --build-dir "$BUILD" --period 0.1 \
    -- --build-dir "$BUILD" --out "$OUT" --no-progress --no-baseline "$@"
fi

BUILD="$(cd "${1:?usage: forger.sh BUILD_DIR}" && pwd)"
needs_netns forger --venv
make_out forger
ROBOTS=($("$BUILD/bin/simulator" --config "$CONFIG" --list-robots))
KEYS="$OUT/keys"
"$BUILD/bin/keys" team "$KEYS" --robots "$(IFS=,; echo "${ROBOTS[*]}")" > /dev/null
FRAMES=$(awk '/^scenario:/ {s = 1; next} /^[^ #]/ {s = 0} s && $1 == "frames:" {print $2; exit}' "$CONFIG")
check() { "$PY" "$HERE/lcm_check.py" --build-dir "$BUILD" --roster "$KEYS/team.yaml" "$@"; }
fail() { echo "forger: $*"; exit 1; }

# 1. The keyed team, unattacked; 2. the same, attacked.
"$ROOT/tools/netns_run.sh" --port 7720 -- "$ROOT/tools/run_team.sh" --inside --build-dir "$BUILD" --out "$OUT/ref" \
  --no-progress --no-baseline --keys "$KEYS" "${ARGS[@]}" > "$OUT/ref.txt" 2>&1 || { cat "$OUT/ref.txt"; exit 1; }
"$ROOT/tools/netns_run.sh" --port 7721 -- "$0" --inner "$BUILD" "$OUT/attacked" --keys "$KEYS" "${ARGS[@]}" \
  > "$OUT/attacked.txt" 2>&1 || { cat "$OUT/attacked.txt"; tail -n 5 "$OUT"/attacked/logs/*.log; exit 1; }
cat "$OUT/attacked.forger.txt"
grep -q "authentication on: .*signing as main" "$OUT/attacked/logs/main_robot.log" || fail "main_robot did not sign"
grep -h "refused a message" "$OUT"/attacked/logs/*.log | head -n 4 || true

# Every robot processed every frame, none lost or refused (its own count): a pose
# missing from a recording is then the recorder's loss (lcm-logger's 30-message
# queue, busier under the flood), noted by compare-poses, not failed.
for r in "${ROBOTS[@]}"; do
  grep -q "^robot_node $r: frames=$FRAMES gaps=0 duplicates=0 out_of_order=0 rejected=0 decode_errors=0 " \
    "$OUT/attacked/logs/robot_node_$r.log" || { tail -n 3 "$OUT/attacked/logs/robot_node_$r.log"; fail "robot $r's frames"; }
done
rc=0
compare_attacked forger
# evaluate with the roster (run_team.sh passes it) leaves out what the nodes refused: the
# attacked recording scores as the unattacked one; log_info --roster counts it.
python3 - "$OUT/ref/metrics.json" "$OUT/attacked/metrics.json" "$poses" <<'PY' || fail "evaluate --roster"
import json, sys
ref, att, poses = json.load(open(sys.argv[1])), json.load(open(sys.argv[2])), int(sys.argv[3])
a = att["authentication"]
assert a and a["refused"] > 0, f"evaluate refused nothing in the attacked recording: {a}"
assert ref["authentication"]["refused"] == 0, ref["authentication"]
print(f"forger: evaluate --roster on the attacked recording: {a['accepted']} events verified, "
      f"{a['refused']} refused {dict((ch, r) for ch, r in a['refused_by'].items())}")
if poses == 0:  # the same poses; the recorder may have lost a few of either run's (compare-poses --allow-missing)
    for r, s in zip(ref["robots"], att["robots"]):
        assert abs(r["error_mean"] - s["error_mean"]) <= 0.02 * r["error_mean"] + 1e-9, (r, s)
    print("forger: evaluate scores the attacked recording as the unattacked one (robot errors within 2 %: "
          + ", ".join(f"{r['error_mean']:.4f}/{s['error_mean']:.4f}" for r, s in zip(ref["robots"], att["robots"])) + ")")
PY
"$BUILD/bin/log_info" "$OUT/attacked/run.lcmlog" --roster "$KEYS/team.yaml" --json > "$OUT/info.json"
python3 - "$OUT/info.json" <<'PY' || fail "log_info --roster"
import json, sys
a = json.load(open(sys.argv[1]))["authentication"]
assert a["refused"] > 0 and a["accepted"] > 0, a
print(f"forger: log_info --roster: {a['accepted']} verified, {a['refused']} refused {a['refused_by']}")
PY
nodes=("${ROBOTS[@]/#/ROBOT_}" MAIN)
check auth-refused "$OUT/attacked/run.lcmlog" --nodes "${nodes[@]}" || fail "a node refused nothing"

# The keyed recording reads as any other: evaluate (run_team.sh) and the Python tools.
[ -s "$OUT/ref/metrics.json" ] || fail "evaluate wrote no metrics.json for the keyed recording"
"$PY" "$ROOT/tools/decode_log.py" "$OUT/ref/run.lcmlog" --build-dir "$BUILD" > "$OUT/decoded.txt"
for ch in POSE_1 SENSOR_1 GROUND_TRUTH; do
  grep -q "^$ch  *$FRAMES decoded$" "$OUT/decoded.txt" || { cat "$OUT/decoded.txt"; fail "decode_log.py: $ch"; }
done
echo "forger: the keyed recording: evaluate and decode_log.py read every message"
python3 - "$OUT/ref/metrics.json" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))
print(f"forger: unattacked keyed team: landmark error {m['landmark_error']['mean_euclidean']:.4f} m, "
      f"robots {[round(r['error_mean'], 4) for r in m['robots']]}")
PY

# 3. The same attack on the team without a key: the attack is real.
if [ "${UNKEYED:-1}" = 1 ]; then
  "$ROOT/tools/netns_run.sh" --port 7722 -- "$0" --inner "$BUILD" "$OUT/unkeyed" "${ARGS[@]}" \
    > "$OUT/unkeyed.txt" 2>&1 || { echo "forger: (the unkeyed attacked team failed to run, as may be)"; }
  echo -n "forger: the same attack without a key, final map vs unattacked: "
  if "$PY" "$HERE/lcm_check.py" --build-dir "$BUILD" compare-maps "$OUT/ref/run.lcmlog" "$OUT/unkeyed/run.lcmlog" \
      --tol 1e-6 2>&1; then
    echo "forger: the attack had no effect on a team without a key: the test proves nothing"; rc=1
  fi
fi
exit $rc

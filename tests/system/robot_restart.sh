#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# System test `system_robot_restart`: a robot_node killed at any instant and started
# again with the same command continues from its --state file.
# For each seed, two live teams in a private namespace (150 frames at 20 Hz; robot 2
# runs `robot_node --state FILE` in both):
#   ref:     uninterrupted;
#   restart: robot 2 gets SIGKILL when its state file says frame >= KILL_FRAME (~60;
#            the file is saved every node.state_save_interval_s, so the kill lands
#            a few frames later) and is started again at once with the same command;
#   fresh:   the same, but its state file is deleted before the restart (it starts
#            over from its odometer with the late-start prior): for comparison only.
# Then: robot 2's log says "resumed from FILE at frame F" with F >= KILL_FRAME, and
# its mean pose error (evaluate, metrics.json robots[].error_mean) is within RATIO
# of the uninterrupted run's. RATIO is 2: the frames the robot misses while its
# process restarts (4-9 at 20 Hz, set by timing) cost something by themselves. In
# process, with no restart at all, robot 2 of seeds 1-6 missing 2-12 frames from
# frame 64 ends within 1.32 times its uninterrupted error (test_frame_gap,
# FrameGap.AFewFramesMissedCostLittle). RATIO was 3.5 from 2026-12-03 to -04: then
# seed 3 missing 9 frames cost 3.1 times, and failed the 1.5 bound on unloaded CI;
# eq 16 now re-tests what it set aside after a gap (docs/faults.md, "What a gap
# costs"). Prints the figures per seed. Last, a stale state file
# (the previous run's last frame) at the start of a new run is dropped after 10
# refused frames and the robot runs on. And a robot killed twice right after its
# resume, before any frame, skips its seq ahead twice (a resume saves at once); and
# a running robot whose sensor source starts over starts fresh.
# Needs root and ip netns (exit 77 otherwise); no Python venv (the state file is
# read with the system python3's json).
#   [SEEDS="1 2 3"] [KILL_FRAME=60] [RATIO=2] tests/system/robot_restart.sh BUILD_DIR
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
# shellcheck source=tests/system/lib.sh
. "$ROOT/tests/system/lib.sh"
CONFIG="$ROOT/config/paper.yaml"
SEEDS=${SEEDS:-"1 2 3"}
KILL_FRAME=${KILL_FRAME:-60}
RATIO=${RATIO:-2}
SIM_ARGS=(--rate 20)

# The frame of a robot state file (-1 while there is none or it is being replaced).
state_frame() {
  python3 -c 'import json, sys
try: print(json.load(open(sys.argv[1]))["state"]["node"]["last_frame"])
except Exception: print(-1)' "$1"
}

if [ "${1:-}" = "--inner" ]; then  # inside the namespace: --inner BUILD OUT SEED ref|restart|fresh
  BUILD="$2" OUT="$3" SEED="$4" VARIANT="$5"
  mkdir -p "$OUT/logs"
  PIDS=()
  R2=""
  trap 'for p in "${PIDS[@]}" $R2; do kill -KILL "$p" 2>/dev/null || true; done' EXIT
  robot() { "$BUILD/bin/robot_node" --config "$CONFIG" --robot "$@" >> "$OUT/logs/robot_node_$1.log" 2>&1 & }
  R2_CMD=(2 --state "$OUT/robot2/state.json")
  mkdir -p "$OUT/robot2"
  lcm-logger -f -q "$OUT/run.lcmlog" > "$OUT/logs/logger.log" 2>&1 & PIDS+=($!)
  "$BUILD/bin/main_robot" --config "$CONFIG" > "$OUT/logs/main_robot.log" 2>&1 & PIDS+=($!)
  robot 1; PIDS+=($!)
  robot 3; PIDS+=($!)
  robot "${R2_CMD[@]}"; R2=$!
  "$BUILD/bin/simulator" --config "$CONFIG" --seed "$SEED" "${SIM_ARGS[@]}" --wait-for-nodes 4 \
    > "$OUT/logs/simulator.log" 2>&1 &
  SIM=$!
  if [ "$VARIANT" != ref ]; then
    deadline=$((SECONDS + 60))
    while [ "$(state_frame "$OUT/robot2/state.json")" -lt "$KILL_FRAME" ]; do
      [ $SECONDS -lt $deadline ] || { echo "robot_restart: robot 2 never saved frame $KILL_FRAME"; exit 1; }
      sleep 0.02
    done
    kill -KILL "$R2"; wait "$R2" 2>/dev/null || true
    echo "--- killed (SIGKILL), state file at frame $(state_frame "$OUT/robot2/state.json")" >> "$OUT/logs/robot_node_2.log"
    [ "$VARIANT" = restart ] || rm -f "$OUT/robot2/state.json"
    robot "${R2_CMD[@]}"; R2=$!  # at once, the same command (as systemd's Restart= would)
  fi
  rc=0
  wait "$SIM" || { echo "robot_restart: simulator failed"; rc=1; }
  sleep 0.3  # the last frame's messages reach the logger
  for p in "${PIDS[@]}" $R2; do kill -INT "$p" 2>/dev/null || true; done
  for p in "${PIDS[@]}" $R2; do wait "$p" || { echo "robot_restart: process $p exited with an error"; rc=1; }; done
  PIDS=(); R2=""
  exit $rc
fi

BUILD="$(cd "${1:?usage: robot_restart.sh BUILD_DIR}" && pwd)"
needs_netns robot_restart
command -v lcm-logger > /dev/null || { echo "robot_restart: skipped (no lcm-logger)"; exit 77; }
make_out robot_restart
rc=0
for seed in $SEEDS; do
  for variant in ref restart fresh; do
    dir="$OUT/seed$seed/$variant"
    mkdir -p "$dir"
    "$ROOT/tools/netns_run.sh" --port 7710 -- "$0" --inner "$BUILD" "$dir" "$seed" "$variant" > "$dir.txt" 2>&1 ||
      { cat "$dir.txt"; tail -n 3 "$dir"/logs/*.log; exit 1; }
    "$BUILD/bin/evaluate" --log "$dir/run.lcmlog" --out "$dir/eval" --quiet
  done
  # None of the resumed robot's events refused at main_robot (duplicates/stale: 0),
  # and main_robot did not take it for a new incarnation (restarts: none said).
  main_line="$(grep -h "^main_robot: events=" "$OUT/seed$seed/restart/logs/main_robot.log" || true)"
  echo "robot_restart: seed $seed: $main_line"
  case "$main_line" in
    *" duplicates=0 "*) ;;
    *) echo "robot_restart: seed $seed: main_robot refused events of the resumed robot"; rc=1 ;;
  esac
  if grep -q "restarted without its state" "$OUT/seed$seed/restart/logs/main_robot.log"; then
    echo "robot_restart: seed $seed: main_robot saw a new incarnation, the state's was not kept"; rc=1
  fi
  resumed="$(grep -h "resumed from" "$OUT/seed$seed/restart/logs/robot_node_2.log" || true)"
  [ -n "$resumed" ] || { echo "robot_restart: seed $seed: robot 2 did not say it resumed"; cat "$OUT/seed$seed/restart/logs/robot_node_2.log"; exit 1; }
  python3 - "$OUT/seed$seed/ref/eval/metrics.json" "$OUT/seed$seed/restart/eval/metrics.json" \
      "$OUT/seed$seed/fresh/eval/metrics.json" "$seed" "$RATIO" "$KILL_FRAME" "$resumed" <<'PY' || rc=1
import json, re, sys
ref, rst, fresh = (json.load(open(p)) for p in sys.argv[1:4])
seed, ratio, kill_frame, resumed = sys.argv[4], float(sys.argv[5]), int(sys.argv[6]), sys.argv[7]
r2 = lambda m: next(r for r in m["robots"] if r["id"] == 2)
a, b, c = r2(ref), r2(rst), r2(fresh)
frame = int(re.search(r"at frame (\d+)", resumed).group(1))
print(f"robot_restart: seed {seed}: robot 2 mean pose error uninterrupted {a['error_mean']:.4f} m "
      f"({a['frames']} poses), killed and resumed at frame {frame}: {b['error_mean']:.4f} m ({b['frames']} poses), "
      f"ratio {b['error_mean'] / a['error_mean']:.3f}; restarted without state: {c['error_mean']:.4f} m "
      f"(ratio {c['error_mean'] / a['error_mean']:.3f})")
fails = []
if frame < kill_frame:
    fails.append(f"resumed at frame {frame}, before the kill frame {kill_frame}")
if b["error_mean"] > ratio * a["error_mean"]:
    fails.append(f"error {b['error_mean']:.4f} m beyond {ratio} x {a['error_mean']:.4f} m")
if b["frames"] < 150 - 40:
    fails.append(f"only {b['frames']} poses: down far too long")
if fails:
    print("robot_restart: seed " + seed + ": " + "; ".join(fails)); sys.exit(1)
PY
done
# A state that the arriving frames do not continue (the last run's, at frame 149,
# while a new run starts at frame 0): robot 2 resumes, sees its frames refused as
# old, drops the state after 10 of them and runs on from there.
seed=${SEEDS%% *}
dir="$OUT/stale"
mkdir -p "$dir/robot2"
cp "$OUT/seed$seed/ref/robot2/state.json" "$dir/robot2/state.json"
"$ROOT/tools/netns_run.sh" --port 7710 -- "$0" --inner "$BUILD" "$dir" "$seed" ref > "$dir.txt" 2>&1 ||
  { cat "$dir.txt"; tail -n 3 "$dir"/logs/*.log; exit 1; }
"$BUILD/bin/evaluate" --log "$dir/run.lcmlog" --out "$dir/eval" --quiet
grep -q "does not fit the frames arriving" "$dir/logs/robot_node_2.log" ||
  { echo "robot_restart: a stale state was not dropped"; cat "$dir/logs/robot_node_2.log"; exit 1; }
python3 - "$dir/eval/metrics.json" <<'PY' || rc=1
import json, sys
r2 = next(r for r in json.load(open(sys.argv[1]))["robots"] if r["id"] == 2)
print(f"robot_restart: a stale state (frame 149) at the start of a new run: dropped, {r2['frames']} poses, "
      f"mean pose error {r2['error_mean']:.4f} m")
if r2["frames"] < 130:
    print("robot_restart: the stale state kept robot 2 down too long"); sys.exit(1)
PY
# A resume saves at once, before anything is sent: a robot killed again before its
# first frame resumes with seq numbers of its own, not the killed run's again (main
# would take the second run's events for duplicates and see no gap).
dir="$OUT/twice"
mkdir -p "$dir"
cp "$OUT/seed$seed/restart/robot2/state.json" "$dir/state.json"
state_seq() { python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["state"]["node"]["seq"])' "$1"; }
seq0=$(state_seq "$dir/state.json")
for run in 1 2; do
  "$ROOT/tools/netns_run.sh" --port 7710 -- bash -c '
    "$1/bin/robot_node" --config "$2" --robot 2 --state "$3/state.json" > "$3/run'$run'.log" 2>&1 & p=$!
    for _ in $(seq 100); do grep -q "resumed from" "$3/run'$run'.log" && break; sleep 0.05; done
    sleep 0.1; kill -KILL $p; wait $p 2>/dev/null; true' _ "$BUILD" "$CONFIG" "$dir" > "$dir/netns$run.txt" 2>&1 ||
    { cat "$dir/netns$run.txt"; exit 1; }
  grep -q "resumed from" "$dir/run$run.log" || { echo "robot_restart: run $run did not resume"; cat "$dir/run$run.log"; exit 1; }
done
seq2=$(state_seq "$dir/state.json")
echo "robot_restart: killed twice before a frame: state seq $seq0 -> $seq2"
[ "$seq2" -ge $((seq0 + 2 * (1 << 24))) ] ||
  { echo "robot_restart: the second resume reused the first one's seq numbers (state seq $seq0 -> $seq2)"; rc=1; }
# A sensor source that starts over while the robot runs on (a new run from frame 0,
# no state file): the robot starts fresh after 10 refused frames and processes the
# rest, instead of refusing every frame until they pass its old ones.
dir="$OUT/source"
mkdir -p "$dir"
"$ROOT/tools/netns_run.sh" --port 7710 -- bash -c '
  "$1/bin/robot_node" --config "$2" --robot 2 > "$3/robot.log" 2>&1 & p=$!
  for n in 40 60; do
    "$1/bin/simulator" --config "$2" --seed 1 --rate 20 --frames $n --wait-for-nodes 1 > "$3/sim$n.log" 2>&1 || exit 1
    sleep 0.3
  done
  kill -INT $p; wait $p' _ "$BUILD" "$CONFIG" "$dir" > "$dir/netns.txt" 2>&1 ||
  { cat "$dir/netns.txt" "$dir"/*.log; exit 1; }
frames=$(sed -n 's/^robot_node 2: frames=\([0-9]*\) .*/\1/p' "$dir/robot.log")
echo "robot_restart: a sensor source that started over: robot 2 processed ${frames:-?} frames of the second run's 60"
grep -q "sensor frames started over" "$dir/robot.log" && [ "${frames:-0}" -ge 45 ] ||
  { echo "robot_restart: the robot did not start fresh on a new run"; cat "$dir/robot.log"; rc=1; }
exit $rc

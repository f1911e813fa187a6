#!/usr/bin/env bash
# Run the team live, one process per role over LCM, record every channel, evaluate
# the recording against ground truth and print the summary.
#
#   tools/run_team.sh [--config FILE] [--mode M] [--rate F] [--dynamism P] [--speed V]
#                     [--seed S] [--frames N] [--out DIR] [--hosts] [--port P] [--in-process]
#                     [--build-dir DIR] [--realtime]
#
# - Does the set-up if needed (tools/setup.sh) and builds.
# - Starts lcm-logger (DIR/run.lcmlog), main_robot, one robot_node per robot of the
#   scenario, then the simulator, which waits until every node has announced itself
#   on STATUS_* and then publishes at F frames/s. Process logs go to DIR/logs/.
# - As root, the whole team runs in a private network namespace with multicast on
#   its loopback (nothing leaves the machine); with --hosts each process gets a
#   namespace of its own, joined by a bridge (veth pairs), as separate onboard
#   computers would be (multicast TTL 1). Not as root: the LCM URL comes from
#   LCM_DEFAULT_URL (or LCM's default) and multicast on loopback must be enabled.
# - A process that dies is reported with its exit status; the script then exits
#   non-zero. Nothing is left behind (processes, namespaces), also on Ctrl-C.
# - --in-process runs the same scenario in one process, in lockstep (run_scenario).
# - --build-dir DIR (or ELASLAM_BUILD_DIR) takes the programs from DIR/bin (default:
#   build/); tests pass their own build dir.
# - --realtime (root): real-time scheduling (SCHED_FIFO, chrt) as an onboard
#   computer would give its control loop: the simulator at priority 60 (it publishes
#   a frame's SENSOR messages in one burst, not preempted by the robots it wakes),
#   every robot_node and lcm-logger at 50 (the logger at the robots' level, or its
#   LCM queue overflows while the robots hold both CPUs), main_robot normal. On this
#   2-vCPU machine it brings sensor-to-pose p99 at 100 Hz under 1 ms
#   (docs/benchmarks.md).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${ELASLAM_BUILD_DIR:-$ROOT/build}"
CONFIG="$ROOT/config/paper.yaml"
OUT=""
MODE=""
PORT=7667
HOSTS=0
IN_PROCESS=0
INSIDE=0
REALTIME=0
SIM_ARGS=()
EVAL_ARGS=()

usage() { sed -n '2,/^set -e/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit "${1:-0}"; }
while [ $# -gt 0 ]; do
  case "$1" in
    --config) CONFIG="$2"; shift 2 ;;
    --out) OUT="$2"; shift 2 ;;
    --mode) MODE="$2"; shift 2 ;;
    --dynamism|--speed|--seed) SIM_ARGS+=("$1" "$2"); EVAL_ARGS+=("$1" "$2"); shift 2 ;;
    --rate|--frames) SIM_ARGS+=("$1" "$2"); shift 2 ;;
    --port) PORT="$2"; shift 2 ;;
    --build-dir) BUILD_DIR="$2"; shift 2 ;;
    --hosts) HOSTS=1; shift ;;
    --in-process) IN_PROCESS=1; shift ;;
    --realtime) REALTIME=1; shift ;;
    --inside) INSIDE=1; shift ;;  # internal: already inside the namespace
    -h|--help) usage 0 ;;
    *) echo "run_team.sh: unknown argument '$1'" >&2; usage 2 ;;
  esac
done
case "$MODE" in ""|ekf|gated|ela|consensus) ;; *) echo "run_team.sh: --mode must be ekf, gated, ela or consensus" >&2; exit 2 ;; esac
[ -f "$CONFIG" ] || { echo "run_team.sh: no such config file: $CONFIG" >&2; exit 2; }
CONFIG="$(cd "$(dirname "$CONFIG")" && pwd)/$(basename "$CONFIG")"
[ -d "$BUILD_DIR" ] || { echo "run_team.sh: no such build directory: $BUILD_DIR" >&2; exit 2; }
BUILD_DIR="$(cd "$BUILD_DIR" && pwd)"
BIN="$BUILD_DIR/bin"
[ -n "$OUT" ] || OUT="$ROOT/runs/team_$(date +%Y%m%d_%H%M%S)"
mkdir -p "$OUT/logs"
OUT="$(cd "$OUT" && pwd)"

if [ "$REALTIME" -eq 1 ] && { [ "$(id -u)" -ne 0 ] || ! command -v chrt >/dev/null; }; then
  echo "run_team.sh: --realtime needs root and chrt (util-linux); running with normal scheduling" >&2
  REALTIME=0
fi
if [ "$INSIDE" -eq 0 ]; then
  "$ROOT/tools/setup.sh" >/dev/null
  cmake --build "$BUILD_DIR" --target simulator robot_node main_robot run_scenario $([ -f "$ROOT/tools/evaluate.cpp" ] && echo evaluate) -j "$(nproc)" >/dev/null
fi
if [ "$IN_PROCESS" -eq 1 ]; then
  # run_scenario takes no --rate / --frames (the config's scenario.rate_hz / frames).
  if [ "${#SIM_ARGS[@]}" -ne "${#EVAL_ARGS[@]}" ]; then
    echo "run_team.sh: --in-process runs the config's frames and rate; --rate and --frames are for the live team" >&2
    exit 2
  fi
  exec "$BIN/run_scenario" --config "$CONFIG" --out "$OUT" ${MODE:+--mode "$MODE"} "${EVAL_ARGS[@]}"
fi

ROBOTS=($("$BIN/simulator" --config "$CONFIG" --list-robots))
MODE_ARGS=(${MODE:+--mode "$MODE"})
# The mode for the report: the override, else the config's robot.mode.
config_mode() { awk '/^robot:/ {r = 1; next} /^[^ #]/ {r = 0} r && $1 == "mode:" {print $2; exit}' "$CONFIG"; }
MODE_NAME="$MODE"
[ -n "$MODE_NAME" ] || MODE_NAME="$(config_mode)"
PIDS=()
NAMES=()
NETNS=()
declare -A HOST_NS

cleanup() {
  local pid
  for pid in "${PIDS[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
  for pid in "${PIDS[@]}"; do wait "$pid" 2>/dev/null || true; done
  for ns in "${NETNS[@]}"; do ip netns del "$ns" 2>/dev/null || true; done
  PIDS=(); NETNS=()
}
trap cleanup EXIT
trap 'echo "run_team.sh: interrupted" >&2; exit 130' INT TERM

# start NAME PREFIX... -- CMD...: a process in the background, output in logs/NAME.log.
start() {
  local name="$1"; shift
  local prefix=()
  while [ "$1" != "--" ]; do prefix+=("$1"); shift; done
  shift
  "${prefix[@]}" "$@" >"$OUT/logs/$name.log" 2>&1 &
  PIDS+=($!)
  NAMES+=("$name")
}

# One namespace per "host", joined by the bridge in the hub namespace.
make_host() {
  local name="$1" index="$2" ns="elaslam_${$}_$1"
  ip netns add "$ns"; NETNS+=("$ns"); HOST_NS[$name]="$ns"
  ip link add "v$$_$index" type veth peer name eth0 netns "$ns"
  ip link set "v$$_$index" netns "$HUB" up
  ip -n "$HUB" link set "v$$_$index" master br0 up
  ip -n "$ns" link set lo up
  ip -n "$ns" addr add "10.77.0.$((index + 1))/24" dev eth0
  ip -n "$ns" link set eth0 up multicast on
  ip -n "$ns" route add 224.0.0.0/4 dev eth0
}

# Real-time priority prefix for a role (--realtime), empty otherwise.
rt() { [ "$REALTIME" -eq 1 ] && echo chrt -f "$1"; return 0; }

launch() {  # $1: how to run each role (a function printing the prefix)
  local where="$1"
  start logger $($where main) $(rt 50) -- lcm-logger -f -q "$OUT/run.lcmlog"
  start main_robot $($where main) -- "$BIN/main_robot" --config "$CONFIG" --state "$OUT/main_state.json"
  for r in "${ROBOTS[@]}"; do
    start "robot_node_$r" $($where "robot$r") $(rt 50) -- "$BIN/robot_node" --config "$CONFIG" --robot "$r" "${MODE_ARGS[@]}"
  done
  start simulator $($where sim) $(rt 60) -- "$BIN/simulator" --config "$CONFIG" --wait-for-nodes $((${#ROBOTS[@]} + 1)) "${SIM_ARGS[@]}"
}

# Wait for the simulator to finish; any other process that exits first is a failure.
supervise() {
  local sim_pid="${PIDS[-1]}" i
  while kill -0 "$sim_pid" 2>/dev/null; do
    for i in "${!PIDS[@]}"; do
      [ "${PIDS[$i]}" = "$sim_pid" ] && continue
      if ! kill -0 "${PIDS[$i]}" 2>/dev/null; then
        local rc=0; wait "${PIDS[$i]}" || rc=$?
        echo "run_team.sh: ${NAMES[$i]} died with exit status $rc (log: $OUT/logs/${NAMES[$i]}.log)" >&2
        tail -n 5 "$OUT/logs/${NAMES[$i]}.log" >&2 || true
        return 1
      fi
    done
    sleep 0.1
  done
  local rc=0; wait "$sim_pid" || rc=$?
  if [ "$rc" -ne 0 ]; then
    echo "run_team.sh: simulator exited with status $rc (log: $OUT/logs/simulator.log)" >&2
    tail -n 5 "$OUT/logs/simulator.log" >&2 || true
    return 1
  fi
}

# Stop every node (SIGINT: clean exit with a final status line), bounded.
stop_all() {
  local failed=0 i
  sleep 0.3  # let the last frame's messages arrive at the logger
  for i in "${!PIDS[@]}"; do kill -INT "${PIDS[$i]}" 2>/dev/null || true; done
  for i in "${!PIDS[@]}"; do
    local rc=0 waited=0
    while kill -0 "${PIDS[$i]}" 2>/dev/null && [ $waited -lt 50 ]; do sleep 0.1; waited=$((waited + 1)); done
    kill -KILL "${PIDS[$i]}" 2>/dev/null || true
    wait "${PIDS[$i]}" || rc=$?
    if [ "$rc" -ne 0 ] && [ "${NAMES[$i]}" != simulator ]; then
      echo "run_team.sh: ${NAMES[$i]} exited with status $rc (log: $OUT/logs/${NAMES[$i]}.log)" >&2
      failed=1
    fi
  done
  PIDS=()
  return $failed
}

same_host() { :; }                       # every role here, no prefix
own_host() { echo ip netns exec "${HOST_NS[$1]}" env "LCM_DEFAULT_URL=$URL"; }

if [ "$INSIDE" -eq 0 ] && [ "$HOSTS" -eq 0 ] && [ "$(id -u)" -eq 0 ] && ip netns list >/dev/null 2>&1; then
  # The whole team in a private namespace: run this script again inside it.
  rc=0
  "$ROOT/tools/netns_run.sh" --port "$PORT" -- "$0" --inside --build-dir "$BUILD_DIR" --config "$CONFIG" --out "$OUT" \
    ${MODE:+--mode "$MODE"} $([ "$REALTIME" -eq 1 ] && echo --realtime) "${SIM_ARGS[@]}" || rc=$?
  exit $rc
fi

if [ "$HOSTS" -eq 1 ]; then
  [ "$(id -u)" -eq 0 ] || { echo "run_team.sh: --hosts needs root (network namespaces)" >&2; exit 2; }
  HUB="elaslam_${$}_hub"
  ip netns add "$HUB"; NETNS+=("$HUB")
  ip -n "$HUB" link add br0 type bridge
  ip -n "$HUB" link set br0 type bridge mcast_snooping 0
  ip -n "$HUB" link set br0 up
  URL="udpm://239.255.76.67:${PORT}?ttl=1&recv_buf_size=8388608"
  idx=0
  for h in sim main "${ROBOTS[@]/#/robot}"; do
    make_host "$h" $idx
    idx=$((idx + 1))
  done
  echo "run_team.sh: ${#HOST_NS[@]} hosts on a bridge (10.77.0.0/24), LCM $URL"
  launch own_host
elif [ "$INSIDE" -eq 1 ]; then
  echo "run_team.sh: team in a private network namespace, LCM $LCM_DEFAULT_URL"
  launch same_host
else
  echo "run_team.sh: not root: using ${LCM_DEFAULT_URL:-the LCM default URL}. Multicast on loopback needs" >&2
  echo "  sudo ip link set lo multicast on && sudo ip route add 224.0.0.0/4 dev lo" >&2
  launch same_host
fi

status=0
supervise || status=1
stop_all || status=1
[ "$status" -eq 0 ] || { echo "run_team.sh: the run failed; logs in $OUT/logs" >&2; exit 1; }
echo "run_team.sh: recorded $OUT/run.lcmlog"
# The run's facts for the summary: what was given, else the config's scenario values.
scenario_value() { awk -v k="$1:" '/^scenario:/ {s = 1; next} /^[^ #]/ {s = 0} s && $1 == k {print $2; exit}' "$CONFIG"; }
for kv in "--seed seed" "--dynamism dynamism_percent" "--speed landmark_speed_mps"; do
  set -- $kv
  case " ${EVAL_ARGS[*]} " in *" $1 "*) ;; *) v="$(scenario_value "$2")"; [ -n "$v" ] && EVAL_ARGS+=("$1" "$v") ;; esac
done
"$BIN/evaluate" --log "$OUT/run.lcmlog" --out "$OUT" --mode "${MODE_NAME:-unknown}" "${EVAL_ARGS[@]}"
echo "run_team.sh: results in $OUT (metrics.json, frames.csv, trajectories/, logs/)"

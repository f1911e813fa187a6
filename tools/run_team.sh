#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Run the team live, one process per role over LCM, record every channel, evaluate
# the recording against ground truth and print the summary, beside what plain
# EKF-SLAM gives on the same scenario and seed.
#
#   tools/run_team.sh [--config FILE] [--mode M] [--rate F] [--dynamism P] [--speed V]
#                     [--seed S] [--frames N] [--out DIR] [--hosts] [--port P] [--in-process]
#                     [--build-dir DIR] [--realtime] [--no-progress] [--no-baseline]
#                     [--loss P [--loss-scope radio|all]]
#                     [--kill-robot R --kill-at-frame F [--restart-after S]]
#                     [--robot-state] [--keys DIR | --auth] [--view [PORT]] [--foxglove [PORT]]
#                     [--channel-groups]
#
# - Works as the very first command on a fresh clone: does the set-up when needed
#   (tools/setup.sh: Debian packages, the Python venv, build/) and builds the programs.
#   Arguments are checked before any of that starts.
# - Defaults: config/paper.yaml (its scenario: 50 % of the landmarks moving at
#   0.5 m/s, seed 1, 150 frames at 10 Hz), the config's robot.mode (ela).
# - Starts the recorder (record, an lcm-logger that survives malformed datagrams:
#   DIR/run.lcmlog), main_robot, one robot_node per robot of the
#   scenario, a progress line (monitor: frame k/N, poses, moving landmarks found),
#   then the simulator, which waits until every node has announced itself on
#   STATUS_* and then publishes at F frames/s. Process logs go to DIR/logs/.
# - The summary (tools' evaluate): per-robot and global map error, moving landmarks
#   detected, latency, frames per robot (dropped / not yet started / missing from
#   the recording), and the same scenario and seed run in process with plain `ekf`
#   (--no-baseline: without). DIR/metrics.json has everything, with provenance.
# - As root, the whole team runs in a private network namespace with multicast on
#   its loopback (nothing leaves the machine); with --hosts each process gets a
#   namespace of its own (the recorder too), joined by a bridge (veth pairs), as
#   separate onboard computers would be (multicast TTL 1). Not as root: the LCM URL
#   comes from LCM_DEFAULT_URL (or LCM's default) and multicast on loopback must be
#   enabled.
# - A process that dies is reported with its exit status; the script then exits 1.
#   Ctrl-C stops everything, says the run was interrupted and exits 130. Nothing is
#   left behind (processes, namespaces).
# - --in-process runs the same scenario in one process, in lockstep (run_scenario).
# - --build-dir DIR (or ELASLAM_BUILD_DIR) takes the programs from DIR/bin (default:
#   build/); tests pass their own build dir.
# - --realtime (root): real-time scheduling (SCHED_FIFO, chrt) as an onboard
#   computer would give its control loop: the simulator at priority 60 (it publishes
#   a frame's SENSOR messages in one burst, not preempted by the robots it wakes),
#   every robot_node and the recorder at 50 (the recorder at the robots' level, or its
#   LCM queue overflows while the robots hold both CPUs; in channel groups each
#   group's recorder at 40), main_robot normal. On this
#   2-vCPU machine it brings sensor-to-pose p99 at 100 Hz under 1 ms
#   (docs/benchmarks.md). --no-progress: no progress line (measurements: one process
#   fewer woken by every datagram).
# - Faults (docs/faults.md; tools/fault_test.sh runs a set of them):
#   --loss P (with --hosts; P in [0, 100], at most one decimal): every receiving
#   host (simulator, main_robot, each robot; not the recorder's host, so that the
#   recording is complete) drops P % of its incoming IPv4 UDP packets, single IP
#   fragments before reassembly (nftables, prerouting at priority -450, numgen
#   random), as a lossy link would: a datagram of k fragments is lost with
#   1-(1-P)^k. DIR/loss.csv: per host, incoming UDP packets (fragments) and those
#   dropped, from the rule's counters.
#   --loss-scope radio (default): the links between the team's computers lose
#   packets, a robot's SENSOR frames do not (on a robot they come from its own
#   drivers, on board; the simulator stands in for them), so robot hosts do not
#   drop what the simulator sends them. all: the robots lose SENSOR frames too.
#   --kill-robot R --kill-at-frame F: when robot R has published its pose of frame F
#   (or later; watched from the recorder's host), its robot_node gets SIGKILL and,
#   --restart-after S seconds later (default 1.0; -1: never), is started again with
#   the same command, host and arguments (its log appended). DIR/faults.log says
#   when. Needs the Python venv (tools/setup.sh).
#   --robot-state: each robot_node gets --state DIR/state/robot<R>.json (a
#   robot_node that saves and reloads its state; main_robot always has --state).
# - Message authentication (docs/security.md): --keys DIR takes a team's keys made by
#   `build/bin/keys team DIR --robots 1,2,3` (elaslam-keys): every process verifies
#   with the roster DIR/team.yaml (--roster), and each that sends signs with its own
#   key, DIR/<sender>.key (--key-file); the recording is verified with the roster.
#   --auth makes a new team's keys and mission in DIR/keys and uses them. Without
#   either, the config's team: section decides (the repo's configs have none).
# - --channel-groups (or the config's team.channel_groups: true): every process opens
#   one LCM port per channel group, ports P to P+20 (docs/adr/0037-channel-groups.md), so that
#   each is woken only by what it reads. The recording is then one
#   recorder per group in use (DIR/groups/), merged by log_merge into DIR/run.lcmlog
#   after the run.
# - --view [PORT] (default 8765; 0: any free port): the live viewer (docs/tools.md) with the team; its
#   URL, http://127.0.0.1:PORT/, is printed at the start. It listens on the host's
#   loopback even when the team runs in a private namespace (viewer --http-netns).
#   On a terminal the viewer stays up after the summary until Enter is pressed.
# - --foxglove [PORT] (default 8765; 0: any free port): the Foxglove bridge
#   (tools/foxglove_bridge.py, docs/tools.md "Foxglove") with the team: open the
#   ws://127.0.0.1:PORT it prints in Foxglove (app.foxglove.dev or Foxglove Studio,
#   "Open connection"). It listens on the host's loopback only, also when the team runs
#   in a private namespace, and stops with the team; the summary says what it served.
#   Needs foxglove-sdk in the Python venv (tools/setup.sh installs it).
# Exit status: 0 done, 1 the run failed, 2 bad arguments, 130 interrupted.
set -euo pipefail
# The real source tree, also when started through a symbolic link (a scratch copy).
ROOT="$(cd "$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")/.." && pwd)"
BUILD_DIR="${ELASLAM_BUILD_DIR:-$ROOT/build}"
CONFIG="$ROOT/config/paper.yaml"
OUT=""
MODE=""
PORT=7667
HOSTS=0
IN_PROCESS=0
INSIDE=0
REALTIME=0
PROGRESS=1
BASELINE=1
LOSS=""          # --loss: percent, as given
LOSS_SCOPE=radio # --loss-scope: radio (SENSOR frames arrive) or all
KILL_ROBOT=""
KILL_FRAME=""
RESTART_AFTER=1.0
ROBOT_STATE=0
KEYS=""          # --keys: a team's key directory, or DIR/keys with --auth
AUTH=0
VIEW_PORT=""     # --view [PORT]
VIEW_NS=""       # internal: the network namespace the viewer's HTTP socket goes in
FOX_PORT=""      # --foxglove [PORT]
FOX_NS=""        # internal: the network namespace the Foxglove bridge serves in
GROUPED=0        # --channel-groups, or the config's team.channel_groups
FRAMES_ARG=""    # --frames, when given (to check --kill-at-frame against)
SIM_ARGS=()      # overrides for the simulator (and run_scenario)
EVAL_ARGS=()     # the same facts, for the record when a log lacks RUN_INFO

usage() { sed -n '3,/^set -e/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit "${1:-0}"; }
die() { echo "run_team.sh: $*" >&2; exit 2; }
# number NAME VALUE LO HI [int]: VALUE is a number (an integer with "int") in [LO, HI].
number() {
  local re='^[+]?([0-9]+([.][0-9]*)?|[.][0-9]+)([eE][-+]?[0-9]+)?$'
  [ "${5:-}" = int ] && re='^[+]?[0-9]+$'
  [[ "$2" =~ $re ]] || die "$1 must be ${5:+an integer }in [$3, $4], got '$2'"
  awk -v v="$2" -v lo="$3" -v hi="$4" 'BEGIN { exit !(v + 0 >= lo + 0 && v + 0 <= hi + 0) }' ||
    die "$1 must be in [$3, $4], got $2"
}
while [ $# -gt 0 ]; do
  case "$1" in
    --config|--out|--mode|--dynamism|--speed|--seed|--rate|--frames|--port|--build-dir|--loss|--loss-scope|--kill-robot|\
    --kill-at-frame|--restart-after|--keys)
      [ $# -ge 2 ] || die "$1 needs a value (see --help)" ;;&
    --config) CONFIG="$2"; shift 2 ;;
    --out) OUT="$2"; shift 2 ;;
    --mode) MODE="$2"; shift 2 ;;
    --dynamism) number --dynamism "$2" 0 100; SIM_ARGS+=("$1" "$2"); EVAL_ARGS+=("$1" "$2"); shift 2 ;;
    --speed) number --speed "$2" 0 100; SIM_ARGS+=("$1" "$2"); EVAL_ARGS+=("$1" "$2"); shift 2 ;;
    --seed) number --seed "$2" 0 2147483647 int; SIM_ARGS+=("$1" "$2"); EVAL_ARGS+=("$1" "$2"); shift 2 ;;
    --rate) number --rate "$2" 0.001 100000; SIM_ARGS+=("$1" "$2"); shift 2 ;;
    --frames) number --frames "$2" 1 100000000 int; SIM_ARGS+=("$1" "$2"); FRAMES_ARG="$2"; shift 2 ;;
    --port) number --port "$2" 1 65535 int; PORT="$2"; shift 2 ;;
    --build-dir) BUILD_DIR="$2"; shift 2 ;;
    --hosts) HOSTS=1; shift ;;
    --loss) [[ "$2" =~ ^[0-9]+([.][0-9])?$ ]] || die "--loss must be a percentage in [0, 100] with at most one decimal, got '$2'"
            number --loss "$2" 0 100; LOSS="$2"; shift 2 ;;
    --loss-scope) case "$2" in radio|all) LOSS_SCOPE="$2" ;; *) die "--loss-scope must be radio or all, got '$2'" ;; esac
                  shift 2 ;;
    --kill-robot) number --kill-robot "$2" 1 16 int; KILL_ROBOT="$2"; shift 2 ;;
    --kill-at-frame) number --kill-at-frame "$2" 0 100000000 int; KILL_FRAME="$2"; shift 2 ;;
    --restart-after) [ "$2" = -1 ] || number --restart-after "$2" 0 3600; RESTART_AFTER="$2"; shift 2 ;;
    --robot-state) ROBOT_STATE=1; shift ;;
    --keys) KEYS="$2"; shift 2 ;;
    --auth) AUTH=1; shift ;;
    --channel-groups) GROUPED=1; shift ;;
    --in-process) IN_PROCESS=1; shift ;;
    --realtime) REALTIME=1; shift ;;
    --no-progress) PROGRESS=0; shift ;;
    --no-baseline) BASELINE=0; shift ;;
    --view) VIEW_PORT=8765; shift
            if [ $# -gt 0 ] && [[ "$1" =~ ^[0-9]+$ ]]; then number --view "$1" 0 65535 int; VIEW_PORT="$1"; shift; fi ;;
    --view-ns) [ $# -ge 2 ] || die "$1 needs a value"; VIEW_NS="$2"; shift 2 ;;  # internal (nested run)
    --foxglove) FOX_PORT=8765; shift
                if [ $# -gt 0 ] && [[ "$1" =~ ^[0-9]+$ ]]; then number --foxglove "$1" 0 65535 int; FOX_PORT="$1"; shift; fi ;;
    --foxglove-ns) [ $# -ge 2 ] || die "$1 needs a value"; FOX_NS="$2"; shift 2 ;;  # internal (nested run)
    --inside) INSIDE=1; shift ;;  # internal: already inside the namespace, set-up done
    -h|--help) usage 0 ;;
    *) echo "run_team.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
case "$MODE" in ""|ekf|gated|ela|consensus) ;; *) die "--mode must be ekf, gated, ela or consensus, got '$MODE'" ;; esac
[ -f "$CONFIG" ] || die "no such config file: $CONFIG"
CONFIG="$(cd "$(dirname "$CONFIG")" && pwd)/$(basename "$CONFIG")"
[ "$HOSTS" -eq 0 ] || [ "$(id -u)" -eq 0 ] || die "--hosts needs root (network namespaces)"
[ "$IN_PROCESS" -eq 0 ] || [ "$HOSTS" -eq 0 ] || die "--in-process and --hosts do not go together"
[ -z "$LOSS" ] || [ "$HOSTS" -eq 1 ] || die "--loss needs --hosts (the loss is a rule in each host's namespace)"
[ -z "$LOSS" ] || command -v nft >/dev/null || die "--loss needs nft (Debian package nftables)"
{ [ -z "$KILL_ROBOT" ] && [ -z "$KILL_FRAME" ]; } || { [ -n "$KILL_ROBOT" ] && [ -n "$KILL_FRAME" ]; } ||
  die "--kill-robot and --kill-at-frame go together"
[ -z "$KILL_FRAME" ] || [ -z "$FRAMES_ARG" ] || [ "$KILL_FRAME" -lt "$FRAMES_ARG" ] ||
  die "--kill-at-frame must be below --frames ($FRAMES_ARG), got $KILL_FRAME"
[ -n "$KILL_ROBOT" ] || [ "$RESTART_AFTER" = 1.0 ] || die "--restart-after needs --kill-robot"
[ -z "$VIEW_PORT" ] || [ "$IN_PROCESS" -eq 0 ] || die "--view needs the live team (not --in-process: nothing is on the bus)"
[ -z "$FOX_PORT" ] || [ "$IN_PROCESS" -eq 0 ] || die "--foxglove needs the live team (not --in-process: nothing is on the bus)"
[ -z "$FOX_PORT" ] || [ -z "$VIEW_PORT" ] || [ "$FOX_PORT" != "$VIEW_PORT" ] || [ "$FOX_PORT" = 0 ] ||
  die "--view and --foxglove need different ports (both $FOX_PORT): e.g. --view 8765 --foxglove 8766"
if [ "$IN_PROCESS" -eq 1 ] && { [ -n "$KILL_ROBOT" ] || [ "$ROBOT_STATE" -eq 1 ]; }; then
  die "--in-process has no processes to kill, no network to lose packets on and no robot state files"
fi
if [ "$REALTIME" -eq 1 ] && { [ "$(id -u)" -ne 0 ] || ! command -v chrt >/dev/null; }; then
  echo "run_team.sh: --realtime needs root and chrt (util-linux); running with normal scheduling" >&2
  REALTIME=0
fi
[ -z "$KEYS" ] || [ "$AUTH" -eq 0 ] || die "--keys and --auth do not go together (--auth makes the keys)"
[ -z "$KEYS" ] || [ -f "$KEYS/team.yaml" ] || die "--keys $KEYS: no team.yaml there (make the keys with: build/bin/keys team DIR --robots 1,2,3)"
[ -z "$KEYS" ] || KEYS="$(cd "$KEYS" && pwd)"
[ -n "$OUT" ] || OUT="$ROOT/runs/team_$(date +%Y%m%d_%H%M%S)"
mkdir -p "$OUT/logs" 2>/dev/null || die "cannot create the output directory $OUT"
OUT="$(cd "$OUT" && pwd)"
[ "$ROBOT_STATE" -eq 0 ] || mkdir -p "$OUT/state"
# Given to every process: its transport (the team's roster, the channel groups); each
# sender also gets its own key (key_of).
KEY_ARGS=()
[ "$GROUPED" -eq 0 ] || KEY_ARGS+=(--channel-groups)
# --view holds the page after the run only for someone at a terminal (the outermost
# run's stdin; a nested run's is /dev/null).
[ "$INSIDE" -eq 1 ] || { [ -t 0 ] && export ELASLAM_VIEW_HOLD=1; } || export ELASLAM_VIEW_HOLD=0

# Whoever is outermost says that the run was interrupted (once).
NESTED_PID=""
interrupted() {
  trap '' INT TERM
  if [ -n "$NESTED_PID" ]; then kill -TERM "$NESTED_PID" 2>/dev/null || true; wait "$NESTED_PID" 2>/dev/null || true; fi
  [ -n "${ELASLAM_RUN_TEAM_NESTED:-}" ] || echo -e "\nrun_team.sh: interrupted: the run did not finish (partial logs in $OUT)" >&2
  exit 130
}
trap interrupted INT TERM

# The build's own progress (ninja's "[N/M]" lines) while the whole output goes to LOG:
# one line rewritten in place on a terminal, else a line at every tenth of the steps
# (a first build takes minutes: a log or CI shows it is moving). The caller's
# pipefail gives the build's status.
build_progress() {
  local log="$1"
  awk -v tty="$([ -t 2 ] && echo 1 || echo 0)" -v logf="$log" '
    { print > logf; fflush(logf) }
    match($0, /^\[[0-9]+\/[0-9]+\]/) {
      split(substr($0, 2, RLENGTH - 2), nm, "/"); n = nm[1] + 0; m = nm[2] + 0
      if (m < 20) next                       # an incremental build: nothing to show
      pct = int(100 * n / m)
      if (tty == 1) { printf "\rrun_team.sh: building: %d/%d steps (%d %%)", n, m, pct > "/dev/stderr"; shown = 1 }
      else if (pct >= next_pct) { printf "run_team.sh: building: %d/%d steps (%d %%)\n", n, m, pct > "/dev/stderr"; next_pct = pct - pct % 10 + 10 }
    }
    END { if (shown) printf "\n" > "/dev/stderr" }'
}

TARGETS=(simulator robot_node main_robot run_scenario evaluate monitor log_merge record keys)
[ -z "$VIEW_PORT" ] || TARGETS+=(viewer)
[ -z "$FOX_PORT" ] || TARGETS+=(elaslam_lcmtypes_py)
if [ "$INSIDE" -eq 0 ]; then
  first=0
  if [ ! -f "$BUILD_DIR/build.ninja" ] || [ ! -x "$ROOT/.venv/bin/python" ]; then
    echo "run_team.sh: first run: set-up (Debian packages, Python venv, build configuration)" >&2
    first=1
  fi
  "$ROOT/tools/setup.sh" --build-dir "$BUILD_DIR" >&2
  echo "run_team.sh: building ${TARGETS[*]} in ${BUILD_DIR#$ROOT/}$([ "$first" -eq 1 ] &&
    echo " (the first build takes a few minutes)")" >&2
  build_log="$OUT/logs/build.log"
  if ! cmake --build "$BUILD_DIR" --target "${TARGETS[@]}" -j "$(nproc)" 2>&1 | build_progress "$build_log"; then
    tail -n 30 "$build_log" >&2
    echo "run_team.sh: the build failed (log: $build_log)" >&2
    exit 1
  fi
fi
[ -d "$BUILD_DIR/bin" ] || die "no programs in $BUILD_DIR/bin (build them: cmake --build $BUILD_DIR)"
BUILD_DIR="$(cd "$BUILD_DIR" && pwd)"
BIN="$BUILD_DIR/bin"
if [ "$AUTH" -eq 1 ]; then  # a new team's keys and mission for this run (a nested run gets --keys)
  rm -rf "$OUT/keys"
  "$BIN/keys" team "$OUT/keys" --robots "$("$BIN/simulator" --config "$CONFIG" --list-robots | tr ' ' ,)" \
    >"$OUT/logs/keys.log" 2>&1 || { cat "$OUT/logs/keys.log" >&2; die "cannot make the team's keys in $OUT/keys"; }
  KEYS="$OUT/keys"
fi
[ -z "$KEYS" ] || KEY_ARGS+=(--roster "$KEYS/team.yaml")
# key_of SENDER: the --key-file of a process that signs as SENDER (robot_<r>, main, simulator).
key_of() { [ -z "$KEYS" ] || echo "--key-file $KEYS/$1.key"; }
# The whole configuration with the overrides, checked by the simulator before anything starts.
# As root the team will run in a namespace of its own on --port (netns_run.sh, --hosts):
# checked with that URL, not the caller's.
CHECK_ENV=()
if [ "$INSIDE" -eq 0 ] && { [ "$HOSTS" -eq 1 ] || { [ "$(id -u)" -eq 0 ] && ip netns list >/dev/null 2>&1; }; }; then
  CHECK_ENV=(env "LCM_DEFAULT_URL=udpm://239.255.76.67:$PORT?ttl=0")
fi
"${CHECK_ENV[@]}" "$BIN/simulator" --config "$CONFIG" "${SIM_ARGS[@]}" "${KEY_ARGS[@]}" $(key_of simulator) --check \
  >"$OUT/logs/check.log" 2>&1 ||
  { sed 's/^/  /' "$OUT/logs/check.log" >&2; die "the configuration with these arguments is not valid"; }
# Channel groups as the nodes will open them (the config may ask for them).
if [ "$GROUPED" -eq 0 ] && grep -q "channel groups on" "$OUT/logs/check.log"; then
  GROUPED=1
  KEY_ARGS+=(--channel-groups)
fi
# shellcheck source=tools/lcm_groups.sh
. "$ROOT/tools/lcm_groups.sh"
[ "$GROUPED" -eq 0 ] || [ $((PORT + LCM_GROUP_LAST)) -le 65535 ] || die "--channel-groups uses ports $PORT..$((PORT + LCM_GROUP_LAST)): past 65535"

# The robots' mode (the override, else the config's robot.mode) as robot_node reads
# it: its --check validates the robot section and says "valid, mode M".
"${CHECK_ENV[@]}" "$BIN/robot_node" --config "$CONFIG" --robot 1 ${MODE:+--mode "$MODE"} "${KEY_ARGS[@]}" $(key_of robot_1) --check \
  >"$OUT/logs/check_robot.log" 2>&1 ||
  { sed 's/^/  /' "$OUT/logs/check_robot.log" >&2; die "the robots' configuration is not valid"; }
MODE_NAME="$(sed -n 's/.*: valid, mode \([a-z]*\)$/\1/p' "$OUT/logs/check_robot.log")"
BASE_ARGS=()
[ "$BASELINE" -eq 1 ] && [ "$MODE_NAME" != ekf ] && BASE_ARGS=(--baseline ekf)

if [ "$IN_PROCESS" -eq 1 ]; then
  exec "$BIN/run_scenario" --config "$CONFIG" --out "$OUT" ${MODE:+--mode "$MODE"} "${SIM_ARGS[@]}" "${BASE_ARGS[@]}"
fi

ROBOTS=($("$BIN/simulator" --config "$CONFIG" --list-robots))
MODE_ARGS=(${MODE:+--mode "$MODE"})
PY="$ROOT/.venv/bin/python"
if [ -n "$KILL_ROBOT" ]; then
  [[ " ${ROBOTS[*]} " == *" $KILL_ROBOT "* ]] || die "--kill-robot $KILL_ROBOT: the scenario's robots are ${ROBOTS[*]}"
  if [ ! -x "$PY" ] || [ ! -f "$BUILD_DIR/lcmgen/python/elaslam/__init__.py" ]; then
    die "--kill-robot needs the Python venv (tools/setup.sh) and the Python message types (build target elaslam_lcmtypes_py)"
  fi
fi
if [ -n "$FOX_PORT" ]; then
  "$PY" -c 'import foxglove' 2>/dev/null ||
    die "--foxglove needs foxglove-sdk in the Python venv $ROOT/.venv (tools/setup.sh installs tools/requirements.txt)"
  [ -f "$BUILD_DIR/lcmgen/python/elaslam/__init__.py" ] ||
    die "--foxglove needs the Python message types (build target elaslam_lcmtypes_py)"
fi
PIDS=()
NAMES=()
NETNS=()
MONITOR_PID=""
VIEWER_PID=""    # --view
FOX_PID=""       # --foxglove
FOX_URL=""
WATCH_PID=""     # --kill-robot: waits for robot R's pose of frame F
declare -A HOST_NS HOST_IP CMDS

cleanup() {
  local pid
  trap '' INT TERM  # a second Ctrl-C (or TERM) must not leave namespaces behind
  for pid in "${PIDS[@]}" $MONITOR_PID $WATCH_PID $VIEWER_PID $FOX_PID; do kill -TERM "$pid" 2>/dev/null || true; done
  for pid in "${PIDS[@]}" $MONITOR_PID $WATCH_PID $VIEWER_PID $FOX_PID; do wait "$pid" 2>/dev/null || true; done
  for ns in "${NETNS[@]}"; do
    [ -z "$LOSS" ] || ip netns exec "$ns" nft delete table inet elaslam_loss 2>/dev/null || true
    ip netns del "$ns" 2>/dev/null || true
  done
  PIDS=(); NETNS=(); MONITOR_PID=""; WATCH_PID=""; VIEWER_PID=""; FOX_PID=""
}
trap cleanup EXIT

# start NAME PREFIX... -- CMD...: a process in the background, output in logs/NAME.log.
start() {
  local name="$1"; shift
  local prefix=()
  while [ "$1" != "--" ]; do prefix+=("$1"); shift; done
  shift
  CMDS[$name]="$(printf '%q ' "${prefix[@]}" "$@")"
  "${prefix[@]}" "$@" >"$OUT/logs/$name.log" 2>&1 &
  PIDS+=($!)
  NAMES+=("$name")
}

# restart NAME: the same command again (same host, same arguments), log appended.
restart() {
  eval "${CMDS[$1]}" '>>"$OUT/logs/$1.log" 2>&1 &'
  PIDS+=($!)
  NAMES+=("$1")
}

# One namespace per "host", joined by the bridge in the hub namespace.
# shellcheck source=tools/netns_bridge.sh
. "$ROOT/tools/netns_bridge.sh"
make_host() {
  local name="$1" index="$2" ns="elaslam_${$}_$1"
  ip netns add "$ns"; NETNS+=("$ns"); HOST_NS[$name]="$ns"; HOST_IP[$name]="10.77.0.$((index + 1))"
  bridge_host "$HUB" "$ns" "v$$_$index" "${HOST_IP[$name]}"
}

# add_loss HOST: drop LOSS % of the host's incoming UDP packets (tools/loss_rule.sh).
# shellcheck source=tools/loss_rule.sh
. "$ROOT/tools/loss_rule.sh"
# shellcheck source=tools/viewer_url.sh
. "$ROOT/tools/viewer_url.sh"
# With --loss-scope radio a robot's host does not drop what the simulator sends (its
# SENSOR frames: on a robot they come from its own drivers, not over the radio).
add_loss() {
  if [ "$LOSS_SCOPE" = radio ] && [[ "$1" == robot* ]]; then
    install_loss_rule "${HOST_NS[$1]}" "${HOST_IP[$1]}" "$LOSS" "${HOST_IP[sim]}"
  else
    install_loss_rule "${HOST_NS[$1]}" "${HOST_IP[$1]}" "$LOSS"
  fi
}

# loss_report: per host, incoming UDP packets and those dropped (DIR/loss.csv), and a
# line; also the host's IP reassembly: datagrams reassembled from fragments, and
# reassemblies that failed (the rest of a datagram with a fragment lost waits
# ipfrag_time, 30 s, in at most ipfrag_high_thresh, 4 MB, of memory: it fails when
# it times out, or at once when the memory is full: then the loss of fragmented
# datagrams exceeds 1-(1-p)^k).
loss_report() {
  local h n d ok fails total_n=0 total_d=0
  echo "host,packets,dropped,loss_percent,reassembled,reassembly_failed" >"$OUT/loss.csv"
  for h in "${!HOST_NS[@]}"; do
    [ "$h" != log ] || continue
    read -r n d < <(ip netns exec "${HOST_NS[$h]}" nft list table inet elaslam_loss 2>/dev/null |
      awk '/comment "incoming"/ { for (i = 1; i < NF; i++) if ($i == "packets") n = $(i + 1) }
           /comment "dropped"/  { for (i = 1; i < NF; i++) if ($i == "packets") d = $(i + 1) }
           END { print n + 0, d + 0 }')
    read -r ok fails < <(ip netns exec "${HOST_NS[$h]}" cat /proc/net/snmp 2>/dev/null |
      awk '$1 == "Ip:" && !hdr { for (i = 2; i <= NF; i++) col[$i] = i; hdr = 1; next }
           $1 == "Ip:" { print $col["ReasmOKs"] + 0, $col["ReasmFails"] + 0; found = 1 }
           END { if (!found) print 0, 0 }')
    echo "$h,$n,$d,$(awk -v n="$n" -v d="$d" 'BEGIN { printf "%.2f", n ? 100 * d / n : 0 }'),$ok,$fails" >>"$OUT/loss.csv"
    total_n=$((total_n + n)); total_d=$((total_d + d))
  done
  echo "run_team.sh: loss $LOSS %: dropped $total_d of $total_n incoming UDP packets (IP fragments) at the hosts," \
    "$(awk -v n="$total_n" -v d="$total_d" 'BEGIN { printf "%.2f", n ? 100 * d / n : 0 }') % ($OUT/loss.csv)"
}

# The recorder (record, not lcm-logger: liblcm's receive thread dies on a malformed
# datagram, transport/udpm_receiver.hpp) reads what waits in its socket's buffer; a
# burst (the first landmarks' ADD events, ~30 at once a few frames in) waits there
# while it waits for a CPU. As root it gets a higher share (nice -10), unless it runs
# real-time anyway.
logger_nice() { [ "$REALTIME" -eq 0 ] && [ "$(id -u)" -eq 0 ] && echo nice -n -10; return 0; }

# Real-time priority prefix for a role (--realtime), empty otherwise.
rt() { [ "$REALTIME" -eq 1 ] && echo chrt -f "$1"; return 0; }

launch() {  # $1: how to run each role (a function printing the prefix)
  local where="$1"
  if [ "$GROUPED" -eq 0 ]; then
    start logger $($where log) $(rt 50) $(logger_nice) -- "$BIN/record" -f -q "$OUT/run.lcmlog"
  else  # one recorder per group in use: the team-wide ones and the team's robots' own
    # Each carries a part of the traffic, so below the robots (--realtime: 40), not at
    # their level: at 100 Hz that took sensor-to-pose p99 from 401-567 to 377-413 us
    # in 3 runs each, with no message lost (docs/benchmarks.md, "Channel groups").
    mkdir -p "$OUT/groups"
    local g
    for g in $(lcm_team_groups "${ROBOTS[@]}"); do
      start "logger_g$g" $($where log) $(rt 40) $(logger_nice) -- "$BIN/record" -f -q --lcm-url="$(lcm_group_url "$g")" \
        "$OUT/groups/g$g.lcmlog"
    done
  fi
  start main_robot $($where main) -- "$BIN/main_robot" --config "$CONFIG" --state "$OUT/main_state.json" "${KEY_ARGS[@]}" \
    $(key_of main)
  local state=()
  for r in "${ROBOTS[@]}"; do
    [ "$ROBOT_STATE" -eq 0 ] || state=(--state "$OUT/state/robot$r.json")
    start "robot_node_$r" $($where "robot$r") $(rt 50) -- "$BIN/robot_node" --config "$CONFIG" --robot "$r" "${MODE_ARGS[@]}" \
      "${state[@]}" "${KEY_ARGS[@]}" $(key_of "robot_$r")
  done
  if [ -n "$KILL_ROBOT" ]; then  # from the logger's host: it hears every pose
    $($where log) env "LCM_DEFAULT_URL=$(pose_url)" "$PY" "$ROOT/tests/system/lcm_check.py" --build-dir "$BUILD_DIR" wait-frame "POSE_$KILL_ROBOT" \
      "$KILL_FRAME" --timeout 86400 >"$OUT/logs/kill_watch.log" 2>&1 &
    WATCH_PID=$!
  fi
  if [ -n "$VIEW_PORT" ]; then  # from the logger's host: it hears every channel; not supervised
    $($where log) "$BIN/viewer" --config "$CONFIG" --port "$VIEW_PORT" ${VIEW_NS:+--http-netns "$VIEW_NS"} \
      "${KEY_ARGS[@]}" >"$OUT/logs/viewer.log" 2>&1 &
    VIEWER_PID=$!
    local url
    url=$(wait_viewer_url "$OUT/logs/viewer.log" "$VIEWER_PID")
    if [ -n "$url" ]; then
      echo "run_team.sh: the viewer: $url" >&2
    else
      echo "run_team.sh: the viewer did not start (log: $OUT/logs/viewer.log): $(tail -n 1 "$OUT/logs/viewer.log")" >&2
      VIEWER_PID=""
    fi
  fi
  if [ -n "$FOX_PORT" ]; then  # from the logger's host: it hears every channel; not supervised
    $($where log) "$PY" "$ROOT/tools/foxglove_bridge.py" --port "$FOX_PORT" --build-dir "$BUILD_DIR" \
      --robots "$(IFS=,; echo "${ROBOTS[*]}")" ${FOX_NS:+--ws-netns "$FOX_NS"} $([ "$GROUPED" -eq 1 ] && echo --channel-groups) \
      >"$OUT/logs/foxglove.log" 2>&1 &
    FOX_PID=$!
    local i
    for ((i = 0; i < 150; i++)); do  # the venv's Python and the SDK start in about a second
      FOX_URL=$(sed -n 's/^foxglove_bridge: \(ws:[^ ]*\)$/\1/p' "$OUT/logs/foxglove.log" 2>/dev/null || true)
      [ -z "$FOX_URL" ] && kill -0 "$FOX_PID" 2>/dev/null || break
      sleep 0.1
    done
    if [ -n "$FOX_URL" ]; then
      echo "run_team.sh: Foxglove: $FOX_URL (in Foxglove: Open connection, Foxglove WebSocket; docs/tools.md)" >&2
    else
      echo "run_team.sh: the Foxglove bridge did not start (log: $OUT/logs/foxglove.log): $(tail -n 1 "$OUT/logs/foxglove.log")" >&2
      kill -TERM "$FOX_PID" 2>/dev/null || true
      FOX_PID=""
    fi
  fi
  if [ "$PROGRESS" -eq 1 ]; then  # to the terminal; not supervised (a failure costs only the line)
    $($where main) "$BIN/monitor" --config "$CONFIG" "${KEY_ARGS[@]}" &
    MONITOR_PID=$!
  fi
  start simulator $($where sim) $(rt 60) -- "$BIN/simulator" --config "$CONFIG" --wait-for-nodes $((${#ROBOTS[@]} + 1)) \
    ${MODE_NAME:+--team-mode "$MODE_NAME"} "${SIM_ARGS[@]}" "${KEY_ARGS[@]}" $(key_of simulator)
}

# --foxglove: the bridge stops with the team (SIGINT, bounded) and says what it served.
stop_foxglove() {
  [ -n "$FOX_PID" ] || return 0
  local waited=0
  kill -INT "$FOX_PID" 2>/dev/null || true
  while kill -0 "$FOX_PID" 2>/dev/null && [ $waited -lt 50 ]; do sleep 0.1; waited=$((waited + 1)); done
  kill -KILL "$FOX_PID" 2>/dev/null || true
  wait "$FOX_PID" 2>/dev/null || true
  FOX_PID=""
  local served
  served=$(sed -n 's/^foxglove_bridge: stopped: ws:[^ ]* //p' "$OUT/logs/foxglove.log" | tail -n 1)
  echo "run_team.sh: Foxglove $FOX_URL stopped with the team; it ${served:-gave no final report (log: $OUT/logs/foxglove.log)}"
}

# fault NOTE: a line in DIR/faults.log (Unix time, what happened) and on stderr.
fault() { echo "$EPOCHREALTIME $*" >>"$OUT/faults.log"; echo "run_team.sh: $*" >&2; }

# --kill-robot: SIGKILL robot_node R (it is no longer supervised until restarted).
RESTART_AT_US=""
kill_robot() {
  local i name="robot_node_$KILL_ROBOT" pid=""
  for i in "${!PIDS[@]}"; do [ "${NAMES[$i]}" = "$name" ] && pid="${PIDS[$i]}" && break; done
  [ -n "$pid" ] || { echo "run_team.sh: $name is not running, cannot kill it" >&2; return 1; }
  kill -KILL "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
  unset 'PIDS[i]' 'NAMES[i]'
  PIDS=("${PIDS[@]}"); NAMES=("${NAMES[@]}")
  echo "--- $(date -u +%FT%T.%3NZ) run_team.sh: SIGKILL after frame $KILL_FRAME" >>"$OUT/logs/$name.log"
  fault "killed robot $KILL_ROBOT (robot_node pid $pid, SIGKILL): it had published its pose of frame $KILL_FRAME or later"
  if [ "$RESTART_AFTER" != -1 ]; then
    RESTART_AT_US=$(awk -v now="${EPOCHREALTIME/./}" -v s="$RESTART_AFTER" 'BEGIN { printf "%.0f", now + s * 1e6 }')
  fi
}

# Wait for the simulator to finish; any other process that exits first is a failure.
supervise() {
  local sim_pid="${PIDS[-1]}" i
  while kill -0 "$sim_pid" 2>/dev/null; do
    if [ -n "$WATCH_PID" ] && ! kill -0 "$WATCH_PID" 2>/dev/null; then
      local wrc=0; wait "$WATCH_PID" || wrc=$?
      WATCH_PID=""
      if [ "$wrc" -ne 0 ]; then
        echo "run_team.sh: watching robot $KILL_ROBOT's poses failed (log: $OUT/logs/kill_watch.log)" >&2
        return 1
      fi
      kill_robot || return 1
    fi
    if [ -n "$RESTART_AT_US" ] && [ "${EPOCHREALTIME/./}" -ge "$RESTART_AT_US" ]; then
      RESTART_AT_US=""
      echo "--- $(date -u +%FT%T.%3NZ) run_team.sh: restarted after ${RESTART_AFTER}s" >>"$OUT/logs/robot_node_$KILL_ROBOT.log"
      restart "robot_node_$KILL_ROBOT"
      fault "restarted robot $KILL_ROBOT (robot_node pid ${PIDS[-1]}, the same command) after ${RESTART_AFTER}s down"
    fi
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
  if [ -n "$WATCH_PID" ]; then
    echo "run_team.sh: robot $KILL_ROBOT never published its pose of frame $KILL_FRAME: it was not killed" >&2
    return 1
  fi
  [ -z "$RESTART_AT_US" ] || fault "the run ended before robot $KILL_ROBOT's restart was due"
  return 0
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
  if [ -n "$MONITOR_PID" ]; then
    kill -INT "$MONITOR_PID" 2>/dev/null || true
    wait "$MONITOR_PID" 2>/dev/null || true
    MONITOR_PID=""
  fi
  return $failed
}

same_host() { :; }                       # every role here, no prefix
# The team's LCM URL as every process opens it, and its channel groups' (lcm_groups.sh,
# sourced above).
pose_url() { if [ "$GROUPED" -eq 1 ]; then lcm_group_url "$LCM_GROUP_POSES"; else lcm_base_url; fi; }
own_host() { echo ip netns exec "${HOST_NS[$1]}" env "LCM_DEFAULT_URL=$URL"; }

if [ "$INSIDE" -eq 0 ] && [ "$HOSTS" -eq 0 ] && [ "$(id -u)" -eq 0 ] && ip netns list >/dev/null 2>&1; then
  # The whole team in a private namespace: run this script again inside it.
  # In the background with `wait`: a signal to this script alone (kill, timeout,
  # systemd) is handled at once, not after the run; netns_run.sh passes it on.
  rc=0
  ELASLAM_RUN_TEAM_NESTED=1 "$ROOT/tools/netns_run.sh" --port "$PORT" -- "$0" --inside --build-dir "$BUILD_DIR" \
    --config "$CONFIG" --out "$OUT" ${MODE:+--mode "$MODE"} $([ "$REALTIME" -eq 1 ] && echo --realtime) \
    $([ "$PROGRESS" -eq 0 ] && echo --no-progress) $([ "$BASELINE" -eq 0 ] && echo --no-baseline) "${SIM_ARGS[@]}" \
    ${KILL_ROBOT:+--kill-robot "$KILL_ROBOT" --kill-at-frame "$KILL_FRAME" --restart-after "$RESTART_AFTER"} \
    $([ "$ROBOT_STATE" -eq 1 ] && echo --robot-state) ${KEYS:+--keys "$KEYS"} \
    $([ "$GROUPED" -eq 1 ] && echo --channel-groups) ${VIEW_PORT:+--view "$VIEW_PORT" --view-ns "/proc/$$/ns/net"} \
    ${FOX_PORT:+--foxglove "$FOX_PORT" --foxglove-ns "/proc/$$/ns/net"} &
  NESTED_PID=$!
  wait "$NESTED_PID" || rc=$?
  NESTED_PID=""
  [ "$rc" -ne 130 ] || interrupted
  exit $rc
fi

if [ "$HOSTS" -eq 1 ]; then
  [ -z "$VIEW_PORT" ] || VIEW_NS="/proc/$$/ns/net"  # the viewer's page on this (the host's) side
  [ -z "$FOX_PORT" ] || FOX_NS="/proc/$$/ns/net"    # the Foxglove bridge's WebSocket too
  HUB="elaslam_${$}_hub"
  ip netns add "$HUB"; NETNS+=("$HUB")
  bridge_hub "$HUB"
  URL="udpm://239.255.76.67:${PORT}?ttl=1&recv_buf_size=8388608"
  idx=0
  for h in sim main "${ROBOTS[@]/#/robot}" log; do
    make_host "$h" $idx
    idx=$((idx + 1))
  done
  echo "run_team.sh: ${#HOST_NS[@]} hosts on a bridge (10.77.0.0/24), LCM $URL"
  if [ -n "$LOSS" ]; then
    for h in sim main "${ROBOTS[@]/#/robot}"; do add_loss "$h"; done
    if [ "$LOSS_SCOPE" = radio ]; then
      echo "run_team.sh: every host but the logger's drops $LOSS % of its incoming UDP packets (nftables);" \
        "SENSOR frames (the simulator's, to the robots) are not dropped (--loss-scope radio)"
    else
      echo "run_team.sh: every host but the logger's drops $LOSS % of its incoming UDP packets (nftables)," \
        "the robots' SENSOR frames included (--loss-scope all)"
    fi
  fi
  launch own_host
elif [ "$INSIDE" -eq 1 ]; then
  echo "run_team.sh: team in a private network namespace, LCM $LCM_DEFAULT_URL"
  launch same_host
else
  echo "run_team.sh: not root: using ${LCM_DEFAULT_URL:-the LCM default URL}. Multicast on loopback needs" >&2
  echo "  sudo ip link set lo multicast on && sudo ip route add 224.0.0.0/4 dev lo" >&2
  launch same_host
fi
if [ "$GROUPED" -eq 1 ]; then
  echo "run_team.sh: ${#ROBOTS[@]} robots (${MODE_NAME:-?}), main_robot, simulator; channel groups on LCM ports" \
    "$(lcm_group_url 0 | sed 's/.*:\([0-9]*\).*/\1/')-$(lcm_group_url "$LCM_GROUP_LAST" | sed 's/.*:\([0-9]*\).*/\1/'), one recorder per group;" \
    "logs in $OUT/logs" >&2
else
  echo "run_team.sh: ${#ROBOTS[@]} robots (${MODE_NAME:-?}), main_robot, simulator, recorder; logs in $OUT/logs" >&2
fi

status=0
supervise || status=1
stop_all || status=1
stop_foxglove
[ -z "$LOSS" ] || loss_report
[ "$status" -eq 0 ] || { echo "run_team.sh: the run failed; logs in $OUT/logs" >&2; exit 1; }
if [ "$GROUPED" -eq 1 ]; then  # the groups' recordings into one log, in receive order
  "$BIN/log_merge" -f "$OUT/run.lcmlog" "$OUT"/groups/g*.lcmlog >"$OUT/logs/log_merge.log" 2>&1 ||
    { cat "$OUT/logs/log_merge.log" >&2; echo "run_team.sh: merging the groups' recordings failed" >&2; exit 1; }
fi
echo "run_team.sh: recorded $OUT/run.lcmlog"
# A keyed team's recording is read as its nodes read the wire: what they would refuse
# (injected by someone without a key, another mission's, replayed; also recorded) is
# counted, not evaluated.
"$BIN/evaluate" --log "$OUT/run.lcmlog" --out "$OUT" --config "$CONFIG" "${BASE_ARGS[@]}" ${MODE_NAME:+--mode "$MODE_NAME"} \
  ${KEYS:+--roster "$KEYS/team.yaml"} "${EVAL_ARGS[@]}"
echo "run_team.sh: results in $OUT (metrics.json, frames.csv, map.csv, trajectories/, logs/)"
# --view on a terminal: the page keeps the run's last state until Enter.
if [ -n "$VIEWER_PID" ] && [ "${ELASLAM_VIEW_HOLD:-0}" = 1 ] && kill -0 "$VIEWER_PID" 2>/dev/null &&
   { exec 3</dev/tty; } 2>/dev/null; then
  echo "run_team.sh: the viewer still shows the run at $(sed -n 's/^viewer: //p' "$OUT/logs/viewer.log"); press Enter to stop it" >&2
  read -r -u 3 _ || true
  exec 3<&-
fi

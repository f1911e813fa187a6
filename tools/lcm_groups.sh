# SPDX-License-Identifier: Apache-2.0
# Sourced by tools/run_team.sh and tools/replay_team.sh: channel groups in shell
# (team.channel_groups; grouped_lcm_transport.hpp, channels.hpp). Each group of
# channels has its own port, the team's base port + the group's number:
#   0 team-wide (DYNAMIC_NOTICE, GLOBAL_MOVING, LMAP_RESYNC, STATUS_*, RUN_INFO), 1 the
#   robots' outputs (LMAP_EVENT(S), LMAP_SNAPSHOT), 2 GLOBAL_MAP, 3 observers
#   (GROUND_TRUTH, CANDIDATES_<r>), 4 POSE_<r>, 4+r robot r's inputs (SENSOR_<r>,
#   TEAM_MAP_<r>).
# lcm-logger and lcm-logplayer open one URL each: one per group.
#
#   lcm_base_url                 the team's URL: $URL, else $LCM_DEFAULT_URL, else LCM's default
#   lcm_group_url G              the base URL with its port moved by G
#   lcm_team_groups R...         the groups a team of robots R... uses, one per line
#   lcm_groups_in_check LOG      0/1: a node's --check output says channel groups are on
#   lcm_group_of_input CHANNEL   the group of a recorded input (SENSOR_<r>, GROUND_TRUTH, RUN_INFO)
LCM_GROUP_POSES=4     # POSE_<r>
LCM_GROUP_ROBOT=4     # + r: SENSOR_<r>, TEAM_MAP_<r>
LCM_GROUP_LAST=20     # the last group: robot 16's
lcm_base_url() { echo "${URL:-${LCM_DEFAULT_URL:-udpm://239.255.76.67:7667?ttl=0}}"; }
lcm_group_url() {
  local u port
  u="$(lcm_base_url)"
  port="${u#udpm://*:}"
  port="${port%%\?*}"
  [[ "$port" =~ ^[0-9]+$ ]] || { echo "lcm_groups.sh: no port in the LCM URL $u" >&2; return 1; }
  echo "${u%%:"$port"*}:$((port + $1))${u#*:"$port"}"
}
lcm_team_groups() {
  local r
  printf '%s\n' 0 1 2 3 "$LCM_GROUP_POSES"
  for r in "$@"; do echo $((LCM_GROUP_ROBOT + r)); done
}
lcm_groups_in_check() { grep -q "channel groups on" "$1" && echo 1 || echo 0; }
lcm_group_of_input() {
  case "$1" in
    SENSOR_*) echo $((LCM_GROUP_ROBOT + ${1#SENSOR_})) ;;
    GROUND_TRUTH) echo 3 ;;
    *) echo 0 ;;
  esac
}

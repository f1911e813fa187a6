# SPDX-License-Identifier: Apache-2.0
# Sourced by tools/run_team.sh and tools/replay_team.sh: channel groups in shell
# (team.channel_groups; grouped_lcm_transport.hpp, channels.hpp). Each group of
# channels has its own port, the team's base port + the group's number:
#   0 team-wide (DYNAMIC_NOTICE, GLOBAL_MOVING, LMAP_RESYNC, STATUS_*, RUN_INFO), 1 the
#   robots' outputs (LMAP_EVENT(S), LMAP_SNAPSHOT, TRACKS_<r>), 2 GLOBAL_MAP and
#   GLOBAL_TRACKS, 3 observers
#   (GROUND_TRUTH, CANDIDATES_<r>), 4 POSE_<r>, 4+r robot r's inputs (SENSOR_<r>,
#   TEAM_MAP_<r>).
# lcm-logger and lcm-logplayer open one URL each: one per group. The numbers and
# lcm_group_of are a copy of channels.hpp's (kGroup*, channel_group) that the ctest
# channel_tables compares with it, channel by channel.
#
#   lcm_base_url                 the team's URL: $URL, else $LCM_DEFAULT_URL, else LCM's default
#   lcm_group_url G              the base URL with its port moved by G
#   lcm_team_groups R...         the groups a team of robots R... uses, one per line
#   lcm_groups_in_check LOG      0/1: a node's --check output says channel groups are on
#   lcm_group_of CHANNEL         the group of a channel (without a suffix)
LCM_GROUP_TEAM=0      # DYNAMIC_NOTICE, GLOBAL_MOVING, LMAP_RESYNC, STATUS_*, RUN_INFO, any other name
LCM_GROUP_OUTPUTS=1   # LMAP_EVENT, LMAP_EVENTS, LMAP_SNAPSHOT, TRACKS_<r>
LCM_GROUP_MAP=2       # GLOBAL_MAP, GLOBAL_TRACKS
LCM_GROUP_OBSERVERS=3 # GROUND_TRUTH, CANDIDATES_<r>
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
  printf '%s\n' "$LCM_GROUP_TEAM" "$LCM_GROUP_OUTPUTS" "$LCM_GROUP_MAP" "$LCM_GROUP_OBSERVERS" "$LCM_GROUP_POSES"
  for r in "$@"; do echo $((LCM_GROUP_ROBOT + r)); done
}
lcm_groups_in_check() { grep -q "channel groups on" "$1" && echo 1 || echo 0; }
# The robot id of "<prefix><id>" (a positive decimal of at most 6 digits), else nothing.
_lcm_robot_of() {
  local id="${1#"$2"}"
  [[ "$1" == "$2"* && "$id" =~ ^[0-9]{1,6}$ ]] && [ $((10#$id)) -gt 0 ] && echo $((10#$id))
}
lcm_group_of() {
  local r p
  for p in SENSOR_ TEAM_MAP_; do
    if r=$(_lcm_robot_of "$1" "$p"); then
      [ "$r" -le $((LCM_GROUP_LAST - LCM_GROUP_ROBOT)) ] && echo $((LCM_GROUP_ROBOT + r)) || echo "$LCM_GROUP_TEAM"
      return
    fi
  done
  if _lcm_robot_of "$1" POSE_ >/dev/null; then echo "$LCM_GROUP_POSES"; return; fi
  if _lcm_robot_of "$1" CANDIDATES_ >/dev/null; then echo "$LCM_GROUP_OBSERVERS"; return; fi
  if _lcm_robot_of "$1" TRACKS_ >/dev/null; then echo "$LCM_GROUP_OUTPUTS"; return; fi
  case "$1" in
    LMAP_EVENT | LMAP_EVENTS | LMAP_SNAPSHOT) echo "$LCM_GROUP_OUTPUTS" ;;
    GLOBAL_MAP | GLOBAL_TRACKS) echo "$LCM_GROUP_MAP" ;;
    GROUND_TRUTH) echo "$LCM_GROUP_OBSERVERS" ;;
    *) echo "$LCM_GROUP_TEAM" ;;
  esac
}

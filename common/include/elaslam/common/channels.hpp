// SPDX-License-Identifier: Apache-2.0
// Every LCM channel name of the system, built in one place (docs/design.md section 2).
// An optional suffix (e.g. "_SIM2") lets two teams share one LCM network.
#pragma once

#include <string>
#include <string_view>

namespace elaslam::channels {

/// The names without a suffix (and the per-robot prefixes), for code that compares
/// names without building them (the authenticating transport, per message).
inline constexpr std::string_view kSensorPrefix = "SENSOR_", kPosePrefix = "POSE_",
                                  kStatusRobotPrefix = "STATUS_ROBOT_", kGroundTruth = "GROUND_TRUTH",
                                  kLmapEvent = "LMAP_EVENT", kLmapEvents = "LMAP_EVENTS",
                                  kLmapSnapshot = "LMAP_SNAPSHOT",
                                  kLmapResync = "LMAP_RESYNC", kGlobalMap = "GLOBAL_MAP",
                                  kDynamicNotice = "DYNAMIC_NOTICE", kStatusMain = "STATUS_MAIN",
                                  kStatusSim = "STATUS_SIM", kRunInfo = "RUN_INFO", kTeamMapPrefix = "TEAM_MAP_",
                                  kGlobalMoving = "GLOBAL_MOVING",
                                  kCandidatesPrefix = "CANDIDATES_", kTracksPrefix = "TRACKS_",
                                  kGlobalTracks = "GLOBAL_TRACKS";

inline std::string sensor(int robot_id, const std::string& suffix = "") {
  return std::string(kSensorPrefix) + std::to_string(robot_id) + suffix;
}
inline std::string pose(int robot_id, const std::string& suffix = "") {
  return std::string(kPosePrefix) + std::to_string(robot_id) + suffix;
}
/// The team's map without robot r's own information, for robot r (robot.team_map).
inline std::string team_map(int robot_id, const std::string& suffix = "") {
  return std::string(kTeamMapPrefix) + std::to_string(robot_id) + suffix;
}
/// Robot r's candidates (candidate_list_t), for the viewer.
inline std::string candidates(int robot_id, const std::string& suffix = "") {
  return std::string(kCandidatesPrefix) + std::to_string(robot_id) + suffix;
}
/// Robot r's tracks of its moving landmarks (track_list_t), for main_robot and the viewer.
inline std::string tracks(int robot_id, const std::string& suffix = "") {
  return std::string(kTracksPrefix) + std::to_string(robot_id) + suffix;
}
inline std::string status_robot(int robot_id, const std::string& suffix = "") {
  return std::string(kStatusRobotPrefix) + std::to_string(robot_id) + suffix;
}
/// Patterns (regular expressions, transport.hpp) matching a per-robot channel of
/// every robot: for subscribers that hear the whole team.
inline std::string any_sensor(const std::string& suffix = "") { return "SENSOR_[0-9]+" + suffix; }
inline std::string any_pose(const std::string& suffix = "") { return "POSE_[0-9]+" + suffix; }
inline std::string any_status_robot(const std::string& suffix = "") { return "STATUS_ROBOT_[0-9]+" + suffix; }
inline std::string any_candidates(const std::string& suffix = "") { return "CANDIDATES_[0-9]+" + suffix; }
inline std::string any_tracks(const std::string& suffix = "") { return "TRACKS_[0-9]+" + suffix; }

/// The robot id of a per-robot channel "<prefix><id><suffix>" (SENSOR_, POSE_,
/// STATUS_ROBOT_; id a positive decimal of at most 6 digits), -1 when `channel` is
/// not one: for readers of recordings, which see every channel.
inline int robot_of(std::string_view channel, std::string_view prefix, std::string_view suffix = "") {
  if (channel.size() <= prefix.size() + suffix.size() || channel.size() > prefix.size() + suffix.size() + 6 ||
      channel.substr(0, prefix.size()) != prefix || channel.substr(channel.size() - suffix.size()) != suffix)
    return -1;
  int id = 0;
  for (std::size_t i = prefix.size(); i < channel.size() - suffix.size(); ++i) {
    if (channel[i] < '0' || channel[i] > '9') return -1;
    id = id * 10 + (channel[i] - '0');
  }
  return id > 0 ? id : -1;
}

inline std::string ground_truth(const std::string& suffix = "") { return std::string(kGroundTruth) + suffix; }
inline std::string lmap_event(const std::string& suffix = "") { return std::string(kLmapEvent) + suffix; }
/// A robot's events of one frame in one message (lmap_events_t; robot.node.batch_events).
inline std::string lmap_events(const std::string& suffix = "") { return std::string(kLmapEvents) + suffix; }
inline std::string lmap_snapshot(const std::string& suffix = "") { return std::string(kLmapSnapshot) + suffix; }
inline std::string lmap_resync(const std::string& suffix = "") { return std::string(kLmapResync) + suffix; }
inline std::string global_map(const std::string& suffix = "") { return std::string(kGlobalMap) + suffix; }
/// The team's fused tracks of its moving landmarks (global_tracks_t), sent with every GLOBAL_MAP.
inline std::string global_tracks(const std::string& suffix = "") { return std::string(kGlobalTracks) + suffix; }
/// GLOBAL_MAP's moving lists alone (global_map_t without landmarks), sent with every
/// GLOBAL_MAP: what a robot reads of the global map (they repair lost notices).
inline std::string global_moving(const std::string& suffix = "") { return std::string(kGlobalMoving) + suffix; }
inline std::string dynamic_notice(const std::string& suffix = "") { return std::string(kDynamicNotice) + suffix; }
inline std::string status_main(const std::string& suffix = "") { return std::string(kStatusMain) + suffix; }
inline std::string status_sim(const std::string& suffix = "") { return std::string(kStatusSim) + suffix; }
inline std::string run_info(const std::string& suffix = "") { return std::string(kRunInfo) + suffix; }

/// The team's channel names without a robot id, and the prefixes of the per-robot ones.
inline constexpr std::string_view kTeamNames[] = {kGroundTruth,  kLmapEvent,     kLmapEvents, kLmapSnapshot,
                                                  kLmapResync,   kGlobalMap,     kGlobalMoving, kDynamicNotice,
                                                  kStatusMain,   kStatusSim,     kRunInfo,    kGlobalTracks};
inline constexpr std::string_view kRobotPrefixes[] = {kSensorPrefix, kPosePrefix, kStatusRobotPrefix, kTeamMapPrefix,
                                                      kCandidatesPrefix, kTracksPrefix};

/// `channel` without `suffix` in *base; false when it does not end with `suffix`.
inline bool strip_suffix(std::string_view channel, std::string_view suffix, std::string_view* base) {
  if (channel.size() < suffix.size() || channel.substr(channel.size() - suffix.size()) != suffix) return false;
  *base = channel.substr(0, channel.size() - suffix.size());
  return true;
}

/// Is `channel` one of the team's channels with `suffix` (docs/design.md section 2)?
inline bool is_team_channel(std::string_view channel, std::string_view suffix = "") {
  for (std::string_view p : kRobotPrefixes)
    if (robot_of(channel, p, suffix) > 0) return true;
  std::string_view base;
  if (!strip_suffix(channel, suffix, &base)) return false;
  for (std::string_view n : kTeamNames)
    if (base == n) return true;
  return false;
}

/// Channel groups (team.channel_groups, docs/adr/0037-channel-groups.md): every
/// group has a UDP port of its own, the base port + its number, so that a process is
/// woken only by the groups it reads. By reader:
/// - kGroupTeam: DYNAMIC_NOTICE, GLOBAL_MOVING, LMAP_RESYNC, STATUS_*, RUN_INFO and
///   any other name (everyone; small messages);
/// - kGroupOutputs: LMAP_EVENT(S), LMAP_SNAPSHOT, TRACKS_<r> (main_robot): one port,
///   so one socket: a robot's events and snapshot of a frame arrive in the order sent;
/// - kGroupMap: GLOBAL_MAP, GLOBAL_TRACKS (the viewer; the robots read GLOBAL_MOVING);
/// - kGroupObservers: GROUND_TRUTH, CANDIDATES_<r> (the viewer and recorders only);
/// - kGroupPoses: POSE_<r> (main_robot, a lockstep simulator, the viewer): the POSE
///   goes out before the frame's events and says what follows it (event_seq,
///   snapshot_chunks), so it needs no common port with them, and a lockstep simulator
///   is woken by the POSEs alone;
/// - kGroupRobot + r: SENSOR_<r>, TEAM_MAP_<r> (robot r alone).
/// Recorders and the viewer join every group. A robot watches for a second sender
/// with its id on its STATUS_ROBOT_<r> then, not on its POSE_<r> (robot_node.hpp).
inline constexpr int kGroupTeam = 0, kGroupOutputs = 1, kGroupMap = 2, kGroupObservers = 3, kGroupPoses = 4,
                     kGroupRobot = 4;
inline constexpr int kMaxGroupRobotId = 16;  // = contract::kMaxRobots (grouped_lcm_transport.cpp checks)
inline constexpr int kChannelGroups = kGroupRobot + kMaxGroupRobotId + 1;

/// The group of `channel` (with the team's `suffix`); robot ids above
/// kMaxGroupRobotId, which no node accepts, fall in kGroupTeam.
inline int channel_group(std::string_view channel, std::string_view suffix = "") {
  for (std::string_view p : {kSensorPrefix, kTeamMapPrefix}) {
    const int r = robot_of(channel, p, suffix);
    if (r > 0) return r <= kMaxGroupRobotId ? kGroupRobot + r : kGroupTeam;
  }
  if (robot_of(channel, kPosePrefix, suffix) > 0) return kGroupPoses;
  if (robot_of(channel, kCandidatesPrefix, suffix) > 0) return kGroupObservers;
  if (robot_of(channel, kTracksPrefix, suffix) > 0) return kGroupOutputs;
  std::string_view base;
  if (!strip_suffix(channel, suffix, &base)) return kGroupTeam;
  if (base == kLmapEvent || base == kLmapEvents || base == kLmapSnapshot) return kGroupOutputs;
  if (base == kGlobalMap || base == kGlobalTracks) return kGroupMap;
  if (base == kGroundTruth) return kGroupObservers;
  return kGroupTeam;
}

}  // namespace elaslam::channels

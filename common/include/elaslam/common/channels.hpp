// Every LCM channel name of the system, built in one place (DESIGN.md section 3).
// An optional suffix (e.g. "_SIM2") lets two teams share one LCM network.
#pragma once

#include <string>

namespace elaslam::channels {

inline std::string sensor(int robot_id, const std::string& suffix = "") {
  return "SENSOR_" + std::to_string(robot_id) + suffix;
}
inline std::string pose(int robot_id, const std::string& suffix = "") {
  return "POSE_" + std::to_string(robot_id) + suffix;
}
inline std::string status_robot(int robot_id, const std::string& suffix = "") {
  return "STATUS_ROBOT_" + std::to_string(robot_id) + suffix;
}
/// Patterns (regular expressions, transport.hpp) matching a per-robot channel of
/// every robot: for subscribers that hear the whole team.
inline std::string any_sensor(const std::string& suffix = "") { return "SENSOR_[0-9]+" + suffix; }
inline std::string any_pose(const std::string& suffix = "") { return "POSE_[0-9]+" + suffix; }
inline std::string any_status_robot(const std::string& suffix = "") { return "STATUS_ROBOT_[0-9]+" + suffix; }

/// The robot id of a per-robot channel "<prefix><id><suffix>" (SENSOR_, POSE_,
/// STATUS_ROBOT_; id a positive decimal of at most 6 digits), -1 when `channel` is
/// not one: for readers of recordings, which see every channel.
inline int robot_of(const std::string& channel, const std::string& prefix, const std::string& suffix = "") {
  if (channel.size() <= prefix.size() + suffix.size() || channel.size() > prefix.size() + suffix.size() + 6 ||
      channel.compare(0, prefix.size(), prefix) != 0 ||
      channel.compare(channel.size() - suffix.size(), suffix.size(), suffix) != 0)
    return -1;
  int id = 0;
  for (std::size_t i = prefix.size(); i < channel.size() - suffix.size(); ++i) {
    if (channel[i] < '0' || channel[i] > '9') return -1;
    id = id * 10 + (channel[i] - '0');
  }
  return id > 0 ? id : -1;
}

inline std::string ground_truth(const std::string& suffix = "") { return "GROUND_TRUTH" + suffix; }
inline std::string lmap_event(const std::string& suffix = "") { return "LMAP_EVENT" + suffix; }
inline std::string lmap_snapshot(const std::string& suffix = "") { return "LMAP_SNAPSHOT" + suffix; }
inline std::string lmap_resync(const std::string& suffix = "") { return "LMAP_RESYNC" + suffix; }
inline std::string global_map(const std::string& suffix = "") { return "GLOBAL_MAP" + suffix; }
inline std::string dynamic_notice(const std::string& suffix = "") { return "DYNAMIC_NOTICE" + suffix; }
inline std::string status_main(const std::string& suffix = "") { return "STATUS_MAIN" + suffix; }
inline std::string status_sim(const std::string& suffix = "") { return "STATUS_SIM" + suffix; }
inline std::string run_info(const std::string& suffix = "") { return "RUN_INFO" + suffix; }

}  // namespace elaslam::channels

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

// SPDX-License-Identifier: Apache-2.0
// The monitor's progress line for a live team: frame k/N, poses received, moving
// landmarks found so far, the robots' dropped frames, refusals, the odometer's
// calibration when the robots estimate it, and every node's faults, e.g.
//   frame 150/150 | poses 450 from 3 robots | moving landmarks found 4 | notices 6
// Filled by the handlers subscribe() registers on a node shell (RUN_INFO, SENSOR_*,
// POSE_*, GLOBAL_MAP, DYNAMIC_NOTICE, STATUS_ROBOT_*, STATUS_MAIN), or by calling
// them directly.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <set>
#include <string>

#include "elaslam/dynamic_notice_t.hpp"
#include "elaslam/global_map_t.hpp"
#include "elaslam/node_status_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/run_info_t.hpp"
#include "elaslam/sensor_frame_t.hpp"

namespace elaslam::transport {

class NodeShell;

class TeamProgress {
 public:
  /// The handlers on `shell`'s channels (with its suffix), each input's queue bounded:
  /// the monitor may fall behind, it must never grow without bound.
  void subscribe(NodeShell& shell);

  void on_run_info(const run_info_t& m);
  void on_sensor(const sensor_frame_t& m);
  void on_pose(const pose_estimate_t& m);
  void on_global_map(const global_map_t& m);
  void on_notice(const dynamic_notice_t& m);
  void on_robot_status(const node_status_t& m);
  void on_main_status(const node_status_t& m);

  /// The line; `undecodable` and `auth_refused` are the shell's own counts.
  std::string line(long long undecodable, long long auth_refused) const;
  /// The line with `shell`'s counts.
  std::string line(const NodeShell& shell) const;

 private:
  // Refusals (every reason of node_status_t.refused) and the fault flags, per node.
  struct Health {
    long long refused = 0;
    std::int32_t faults = 0;  // node_status_t.fault_flags of its last STATUS
  };
  void note_health(const std::string& node, const node_status_t& m);

  int frame_ = -1, frames_ = 0;
  long long poses_ = 0, notices_ = 0, dropped_ = 0;
  std::set<int> pose_robots_, moving_;
  std::map<int, long long> dropped_by_robot_;
  std::map<int, std::array<float, 2>> calibration_;  // robot -> odometer turn and speed scale (STATUS)
  std::map<std::string, Health> health_;
};

}  // namespace elaslam::transport

// SPDX-License-Identifier: Apache-2.0
// A landmark event as main_robot's GlobalMap takes it, for the main_robot tests.
#pragma once

#include <cstdint>

#include <Eigen/Core>

#include "elaslam/main_robot/global_map.hpp"

namespace elaslam::test {

inline GlobalEvent global_event(int robot, std::int64_t seq, int kind, int id, const Eigen::Vector2d& position,
                                const Eigen::Matrix2d& cov, int frame) {
  GlobalEvent e;
  e.robot_id = robot;
  e.seq = seq;
  e.kind = kind;
  e.landmark_id = id;
  e.position = position;
  e.cov = cov;
  e.frame = frame;
  return e;
}

}  // namespace elaslam::test

// SPDX-License-Identifier: Apache-2.0
// main_robot's options for a team of robots 1-3, for the main_robot tests.
#pragma once

#include <string>

#include <gtest/gtest.h>

#include "elaslam/main_robot/main_node.hpp"

namespace elaslam::test {

inline GlobalMapOptions team_of_three() {
  GlobalMapOptions o;
  o.max_landmark_id = 32;
  std::string why;
  EXPECT_TRUE(parse_team("1,2,3", &o.limits.team_mask, &why)) << why;
  return o;
}

}  // namespace elaslam::test

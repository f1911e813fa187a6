// SPDX-License-Identifier: Apache-2.0
// The paper's team (config/paper.yaml), read once, for the team tests to copy and change.
#pragma once

#include <string>

#include "elaslam/team/team_config.hpp"

namespace elaslam::test {

inline const TeamConfig& paper() {
  static const TeamConfig c = load_team_config(std::string(ELASLAM_SOURCE_DIR) + "/config/paper.yaml");
  return c;
}

}  // namespace elaslam::test

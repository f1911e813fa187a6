// SPDX-License-Identifier: Apache-2.0
// The nodes' options for the libFuzzer targets: config/paper.yaml's robot and main
// sections, read once.
#pragma once

#include <string>

#include "elaslam/common/config.hpp"
#include "elaslam/main_robot/global_map.hpp"
#include "elaslam/robot_node/robot_options.hpp"
#include "fuzz_input.hpp"

namespace elaslam::fuzz {

inline const std::string& paper_yaml() {
  static const std::string path = source_dir() + "/config/paper.yaml";
  return path;
}

inline const GlobalMapOptions& main_options() {
  static const GlobalMapOptions o = [] {
    config::Document doc = config::Document::from_file(paper_yaml());
    return config::read_component<GlobalMapOptions>(doc, "main");
  }();
  return o;
}

inline const RobotOptions& robot_options() {
  static const RobotOptions o = load_robot_options(paper_yaml());
  return o;
}

}  // namespace elaslam::fuzz

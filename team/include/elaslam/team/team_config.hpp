// SPDX-License-Identifier: Apache-2.0
// One config file for the whole team: `scenario:` (simulator), `robot:` (every
// robot node), `main:` (main_robot). Loaded and checked together, so that the
// sections agree with each other (e.g. the robots' field of view and the sensor's).
#pragma once

#include <string>

#include "elaslam/common/config.hpp"
#include "elaslam/main_robot/global_map.hpp"
#include "elaslam/robot_node/robot_options.hpp"
#include "elaslam/simulator/scenario.hpp"

namespace elaslam {

struct TeamConfig {
  sim::ScenarioOptions scenario;
  RobotOptions robot;
  GlobalMapOptions main;
  /// Evaluation only: remove every observation of a truly moving landmark before
  /// the robots see it (a perfect detector; the bound any detector can reach).
  bool oracle = false;
  std::string effective_yaml;  // the effective configuration, as read
  std::string source;          // file it came from
};

/// Throws config::ConfigError listing every problem.
TeamConfig load_team_config(const std::string& path);

/// The robot: and main: sections of `doc`, read after the caller's world section
/// (scenario: or dataset:), every other section allowed, the document finished.
/// Throws config::ConfigError listing every problem.
void read_robot_and_main(config::Document& doc, RobotOptions* robot, GlobalMapOptions* main);

/// Check what only the combination of sections can tell; empty when consistent.
std::string check_team(const TeamConfig& c);

}  // namespace elaslam

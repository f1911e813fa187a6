// SPDX-License-Identifier: Apache-2.0
// The simulator on the message layer (docs/design.md sections 1 and 6): publishes RUN_INFO
// (what the run is: scenario, seed, dynamism, speed, rate, effective config) and
// STATUS_SIM before the first frame and about once a second, then SENSOR_<r> for
// every robot and GROUND_TRUTH of each frame at its deadline (scheduler.hpp); in
// lockstep it waits after each frame for every robot's POSE_<r> of that frame
// (lockstep.hpp). simulator/main.cpp is its command line.
#pragma once

#include <string>

#include "elaslam/simulator/scenario.hpp"
#include "elaslam/transport/node_shell.hpp"

namespace elaslam::sim {

struct SimRunOptions {
  int start_delay_ms = 0;       // before frame 0, so that subscribers can join
  bool lockstep = false;
  int lockstep_timeout_ms = 1000;
  int wait_for_nodes = 0;       // before frame 0, wait until this many nodes announced themselves
  int wait_timeout_ms = 10000;
  std::string config_path;      // recorded in RUN_INFO
  std::string effective_yaml;   // the config as read, recorded in RUN_INFO
  std::string team_mode;        // the robots' mode, recorded in RUN_INFO ("" unknown)
};

/// Run the scenario on `shell` to its last frame or until a stop is requested, and
/// say the summary ("done: N frames published, ..."). Returns 0, or 1 when the nodes
/// did not announce themselves in time.
int run_simulator(transport::NodeShell& shell, const ScenarioOptions& o, const SimRunOptions& r);

}  // namespace elaslam::sim

// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: every message handler of robot_node, as the process runs them
// (RobotPorts on a NodeShell: decode into the preallocated message, validate, apply,
// publish what the node answers), on robot 1 with config/paper.yaml (a smaller filter: options()). An input is a
// burst of SENSOR_1, DYNAMIC_NOTICE, GLOBAL_MOVING, LMAP_RESYNC, POSE_1 and TEAM_MAP_1 messages (the team map on)
// (fuzz_input.hpp). The node is made anew per input: a crash reproduces from its input alone.
// After each input the node's status and state must still be producible.
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <string>

#include "elaslam/common/channels.hpp"
#include "elaslam/robot_node/robot_ports.hpp"
#include "elaslam/robot_node/robot_options.hpp"
#include "elaslam/robot_node/robot_state.hpp"
#include "fuzz_options.hpp"
#include "node_harness.hpp"

namespace {

using namespace elaslam;

// config/paper.yaml with 24 filter slots instead of 128: the covariance is copied
// and scanned per input, and coverage instrumentation makes every element a callback;
// a small filter also fills up, so the full-filter paths get exercised.
const RobotOptions& options() {
  static const RobotOptions o = [] {
    RobotOptions r = fuzz::robot_options();
    r.ekf.capacity = 24;
    r.team_map_fuse = true;  // TEAM_MAP_1 into the aided filter (robot.team_map)
    return r;
  }();
  return o;
}

const std::string kChannels[] = {channels::sensor(1), channels::dynamic_notice(), channels::global_moving(),
                                 channels::lmap_resync(), channels::pose(1), channels::team_map(1)};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static fuzz::NodeHarness<RobotNode, RobotPorts> h("robot_node 1", [] { return RobotNode(options(), 1); });
  h.run(data, size, kChannels);
  h.ports.publish_status();
  h.bus.dispatch_all();
  if (save_robot_state(h.node).empty()) std::abort();
  return 0;
}

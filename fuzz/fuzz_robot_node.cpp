// libFuzzer target: every message handler of robot_node, as the process runs them
// (RobotPorts on a NodeShell: decode into the preallocated message, validate, apply,
// publish what the node answers), on robot 1 with config/paper.yaml (a smaller filter: options()). An input is a
// burst of SENSOR_1, DYNAMIC_NOTICE, GLOBAL_MAP, LMAP_RESYNC and POSE_1 messages
// (fuzz_input.hpp). The node is reset to a pristine copy per input: a crash reproduces from its input alone.
// After each input the node's status and state must still be producible.
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <string>

#include "elaslam/common/channels.hpp"
#include "elaslam/robot_node/robot_node.hpp"
#include "elaslam/robot_node/robot_options.hpp"
#include "elaslam/robot_node/robot_state.hpp"
#include "elaslam/transport/inprocess_transport.hpp"
#include "elaslam/transport/node_shell.hpp"
#include "fuzz_input.hpp"
#include "fuzz_options.hpp"

namespace {

using namespace elaslam;

// config/paper.yaml with 24 filter slots instead of 128: the covariance is copied
// and scanned per input, and coverage instrumentation makes every element a callback;
// a small filter also fills up, so the full-filter paths get exercised.
const RobotOptions& options() {
  static const RobotOptions o = [] {
    RobotOptions r = fuzz::robot_options();
    r.ekf.capacity = 24;
    return r;
  }();
  return o;
}

const std::string kChannels[] = {channels::sensor(1), channels::dynamic_notice(), channels::global_map(),
                                 channels::lmap_resync(), channels::pose(1)};

/// The shell, the transport and the ports live across inputs (their decode buffers
/// are reserved once: megabytes); the node is reset to a pristine copy before each
/// input, so that an input's outcome depends on it alone.
struct Harness {
  transport::InProcessTransport bus;
  std::int64_t clock = 0;
  transport::NodeShell shell{bus, [this] {
                               transport::ShellOptions so("robot_node 1", "", nullptr);
                               so.clock = [this] { return clock += 1000; };
                               return so;
                             }()};
  const RobotNode pristine{options(), 1};
  RobotNode node{pristine};
  RobotPorts<transport::NodeShell> ports{shell, node};
  Harness() {
    if (!ports.open()) std::abort();
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static Harness h;
  h.node = h.pristine;
  h.clock = 1'700'000'000'000'000;
  fuzz::for_each_record(data, size, std::size(kChannels), [&](const fuzz::Record& r) {
    h.bus.publish(kChannels[r.channel], r.data, r.size);
    h.bus.dispatch_all();
  });
  h.ports.publish_status();
  h.bus.dispatch_all();
  if (save_robot_state(h.node).empty()) std::abort();
  return 0;
}

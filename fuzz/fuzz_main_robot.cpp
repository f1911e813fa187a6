// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: every message handler of main_robot, as the process runs them
// (MainPorts on a NodeShell: decode, validate, apply, publish notices, resync
// requests and the global map), with config/paper.yaml. An input is a burst of
// LMAP_EVENT, LMAP_EVENTS, LMAP_SNAPSHOT, POSE_<r> and TRACKS_<r> messages (fuzz_input.hpp; POSE of
// robots 1, 2, 3 and 7, TRACKS of robots 1 and 2). The node is made anew per input. After each input the global map, the status
// and the state file's text must still be producible, and the state must load back.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/config.hpp"
#include "elaslam/main_robot/global_map.hpp"
#include "elaslam/main_robot/main_ports.hpp"
#include "fuzz_options.hpp"
#include "node_harness.hpp"

namespace {

using namespace elaslam;

const GlobalMapOptions& options() { return fuzz::main_options(); }

// LMAP_EVENTS and then TRACKS_<r> last: the indices of the corpora written before
// them keep their channels.
const std::string kChannels[] = {channels::lmap_event(), channels::lmap_snapshot(), channels::pose(1),
                                 channels::pose(2),      channels::pose(3),         channels::pose(7),
                                 channels::lmap_events(), channels::tracks(1),      channels::tracks(2)};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static fuzz::NodeHarness<MainNode, MainPorts> h("main_robot", [] { return MainNode(options()); });
  h.run(data, size, kChannels);
  h.ports.publish_map();
  h.ports.publish_status();
  h.bus.dispatch_all();
  // The state main_robot would save must load back into a fresh map.
  const std::string state = h.node.map().to_json();
  GlobalMap reloaded(options());
  std::string why;
  if (!reloaded.from_json(state, &why)) {
    std::fprintf(stderr, "fuzz_main_robot: the saved state does not load back: %s\n", why.c_str());
    std::abort();
  }
  return 0;
}

// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: every input of the viewer, as the process runs them (ViewPorts on
// a NodeShell: decode, check, apply), with config/paper.yaml's limits. An input is a
// burst of RUN_INFO, POSE_1-3, GLOBAL_MAP, DYNAMIC_NOTICE, STATUS_ROBOT_1,
// CANDIDATES_1, GROUND_TRUTH, TRACKS_1 and GLOBAL_TRACKS messages (fuzz_input.hpp). The state is made anew
// per input. After each input the page's state must be valid JSON
// whose landmarks and robots are finite.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <nlohmann/json.hpp>

#include "elaslam/common/channels.hpp"
#include "elaslam/viewer/view_ports.hpp"
#include "elaslam/viewer/view_state.hpp"
#include "fuzz_options.hpp"
#include "node_harness.hpp"

namespace {

using namespace elaslam;

viewer::ViewLimits limits() {
  viewer::ViewLimits l;
  l.max_landmark_id = fuzz::main_options().max_landmark_id;
  l.world_bound_m = fuzz::main_options().limits.world_bound;
  return l;
}

// TRACKS_1 and GLOBAL_TRACKS last: the indices of the corpora written before them keep their channels.
const std::string kChannels[] = {channels::run_info(),       channels::pose(1),         channels::pose(2),
                                 channels::pose(3),          channels::global_map(),    channels::dynamic_notice(),
                                 channels::status_robot(1),  channels::candidates(1),   channels::ground_truth(),
                                 channels::tracks(1),        channels::global_tracks()};

void check_finite(const nlohmann::json& j, const char* what) {
  for (const char* k : {"x", "y"})
    if (j.contains(k) && !j[k].is_null() && !std::isfinite(j[k].get<double>())) {
      std::fprintf(stderr, "fuzz_viewer: a %s with a non-finite %s\n", what, k);
      std::abort();
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static fuzz::NodeHarness<viewer::ViewState, viewer::ViewPorts> h("viewer", [] { return viewer::ViewState(limits()); });
  h.run(data, size, kChannels);
  const nlohmann::json j = nlohmann::json::parse(h.node.to_json(0.0), nullptr, false);
  if (j.is_discarded()) {
    std::fprintf(stderr, "fuzz_viewer: the state is not valid JSON\n");
    std::abort();
  }
  for (const auto& l : j["landmarks"]) check_finite(l, "landmark");
  for (const auto& r : j["robots"]) check_finite(r, "robot");
  return 0;
}

// SPDX-License-Identifier: Apache-2.0
// What the viewer reads of the config and adds to its state (view_state.hpp).
#include <cstdio>
#include <string>

#include "elaslam/common/config.hpp"
#include "elaslam/common/main_options.hpp"
#include "elaslam/viewer/view_state.hpp"

namespace elaslam::viewer {

ViewLimits load_view_limits(const std::string& config_path) {
  config::Document doc = config::Document::from_file(config_path);
  const GlobalMapOptions mo = config::read_component<GlobalMapOptions>(doc, "main");
  ViewLimits limits;
  limits.max_landmark_id = mo.max_landmark_id;
  limits.world_bound_m = mo.limits.world_bound;
  return limits;
}

std::string viewer_counters_json(long long messages, long long bad_messages, long long queue_drops, int clients,
                                 double updates_per_s) {
  char counters[256];
  std::snprintf(counters, sizeof counters,
                "{\"messages\":%lld,\"bad_messages\":%lld,\"queue_drops\":%lld,\"clients\":%d,\"updates_per_s\":%g}",
                messages, bad_messages, queue_drops, clients, updates_per_s);
  return counters;
}

}  // namespace elaslam::viewer

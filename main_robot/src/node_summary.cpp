// SPDX-License-Identifier: Apache-2.0
// main_robot's last words at exit (main_node.hpp, final_summary).
#include <cstdio>
#include <string>

#include "elaslam/main_robot/main_node.hpp"

namespace elaslam {

std::string final_summary(const MainNode& node) {
  const auto& c = node.counters();
  char buf[1024];
  std::snprintf(buf, sizeof buf,
                "main_robot: events=%lld snapshots=%lld duplicates=%lld gaps=%lld rejected=%lld "
                "decode_errors=%lld notices=%lld static=%d moving=%d version=%lld maps=%lld map_chunks=%lld "
                "moving_sets=%lld stale_poses=%lld runs_started=%lld occupied=%lld team_map_left_out=%lld "
                "state_damaged=%lld\n",
                (long long)c.events, (long long)c.snapshots, (long long)c.duplicates, (long long)c.gaps,
                (long long)c.rejected_inputs, (long long)c.decode_errors, (long long)c.notices_sent,
                node.map().count(GlobalStatus::kStatic), node.map().count(GlobalStatus::kMoving),
                (long long)node.map().version(), (long long)c.maps_published, (long long)c.map_chunks,
                (long long)c.moving_sets, (long long)c.stale_poses, (long long)c.runs_started,
                (long long)c.occupied, (long long)node.map().rounds_left_out(), (long long)c.state_damaged);
  std::string out = buf;
  if (c.tracks + c.tracks_refused > 0) {  // robots sent tracks of moving landmarks
    std::snprintf(buf, sizeof buf,
                  "main_robot: tracks=%lld tracks_refused=%lld stale_tracks=%lld global_tracks=%lld "
                  "global_tracks_omitted=%lld\n",
                  (long long)c.tracks, (long long)c.tracks_refused, (long long)c.stale_tracks,
                  (long long)c.global_tracks_published, (long long)c.global_tracks_omitted);
    out += buf;
  }
  return out;
}

}  // namespace elaslam

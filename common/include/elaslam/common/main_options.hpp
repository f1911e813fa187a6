// SPDX-License-Identifier: Apache-2.0
// The `main:` section of a config: main_robot's options (GlobalMap, MainNode and the
// process), read by main_robot and the in-process team, and by the viewer for the
// bounds it checks messages against (max_landmark_id, limits). Here, in common, so
// that a reader of the section needs no main_robot library.
#pragma once

#include <cstdint>

#include "elaslam/common/config.hpp"
#include "elaslam/common/limits.hpp"

namespace elaslam {

enum class Fusion { kInformation, kCovarianceIntersection };

struct GlobalMapOptions {
  int max_landmark_id = 256;    // ids accepted: 0 <= id < max_landmark_id
  Fusion fusion = Fusion::kInformation;
  double publish_rate_hz = 10.0;       // process only: GLOBAL_MAP at least this often (MainPorts::publish_map_if_quiet)
  double state_save_interval_s = 1.0;  // process only: at most one save per interval
  int resync_interval_frames = 5;      // ask a robot with an unrepaired gap again after this many of its frames
  // What a message may say (docs/security.md): bounds, the team.
  MessageLimits limits;
  /// A robot's frame (POSE, events, snapshots) more than this far ahead of the last
  /// one seen from it is held until a next message confirms it (one forged
  /// far-future frame never pins GLOBAL_MAP.frame nor blocks the real stream).
  int max_frame_gap = 100;
  /// The same for event and snapshot seq numbers (a robot resumed from its state
  /// file skips 2^24: its first message is held, the next confirms the jump).
  std::int64_t max_seq_jump = 100000;
  /// Every this many frames, each robot gets the map without its own information
  /// (TEAM_MAP_<r>, for robot.team_map.fuse; docs/adr/0025-team-map-two-filters.md). 0: never.
  int team_map_period_frames = 0;
  /// GLOBAL_MOVING goes out with a GLOBAL_MAP when its moving lists differ from the
  /// last ones sent, or when those went out at least this long ago (a lost one is
  /// repaired within it); 0: with every GLOBAL_MAP. Process and in-process alike
  /// (MainNode::moving_set_due); docs/adr/0038-global-moving.md.
  double moving_repeat_s = 1.0;  // [s]
  /// A robot's body radius [m]: a STATIC landmark found where a robot is is taken as
  /// moving (GlobalMap::occupy). 0: off (the simulator's robots have no body).
  double body_radius_m = 0.0;
  /// Before each round of team maps, every robot's map is checked against the
  /// others': a robot whose estimates disagree with the other robots' fusion beyond
  /// the chi-square quantile (2 dof) of this probability on more than half (and at
  /// least kTeamCheckMinShared) of the landmarks they share is left out of the other
  /// robots' team maps for that round (GlobalMap::check_team; docs/adr/0047-team-check.md). 0:
  /// off (config/mrclam.yaml: 0.9999).
  double team_map_check_probability = 0.0;
};
void parse(config::Reader& r, GlobalMapOptions* o);

}  // namespace elaslam

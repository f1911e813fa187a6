// SPDX-License-Identifier: Apache-2.0
// The checks of a robot's message to main_robot on its own: the contract, the limits
// and the team (limits.hpp). Each returns "" when the message is valid, else the
// problem, with *reason (never null) its kind. What depends on the robot's stream (its
// incarnation, frame and seq windows) is MainNode's. The robot's checks of main's
// messages are in common/limits.hpp (check_global_map) and robot_node.
#pragma once

#include <string>

#include "elaslam/common/limits.hpp"
#include "elaslam/landmark_event_t.hpp"
#include "elaslam/lmap_events_t.hpp"
#include "elaslam/lmap_snapshot_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/track_list_t.hpp"

namespace elaslam::main_checks {

/// A robot id within the contract, then in limits.team.
std::string robot(int robot_id, const MessageLimits& l, Refusal* reason);
/// LMAP_EVENT: ids below `max_landmark_id`; an estimate (not MOVING) within limits.
std::string event(const landmark_event_t& m, const MessageLimits& l, int max_landmark_id, Refusal* reason);
/// LMAP_EVENTS, the message and not its events: a count within the contract, a header
/// that speaks for every event (robot, incarnation, frame), seqs ascending.
std::string events(const lmap_events_t& m, const MessageLimits& l, Refusal* reason);
/// LMAP_SNAPSHOT: a chunk within its id range, ids ascending and listed once (as
/// static or as moving), estimates within limits.
std::string snapshot(const lmap_snapshot_t& m, const MessageLimits& l, int max_landmark_id, Refusal* reason);
/// POSE_<r> as main reads it: what it announces (event_seq, snapshot_chunks) and
/// check_pose.
std::string pose(const pose_estimate_t& m, const MessageLimits& l, Refusal* reason);
/// TRACKS_<r>: the robot in limits.team and check_track_list (ids below
/// `max_landmark_id`, each once; finite numbers, covariances positive semi-definite
/// within limits, model probabilities in [0, 1] summing to 1).
std::string tracks(const track_list_t& m, const MessageLimits& l, int max_landmark_id, Refusal* reason);

}  // namespace elaslam::main_checks

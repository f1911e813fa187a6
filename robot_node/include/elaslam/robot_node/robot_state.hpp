// SPDX-License-Identifier: Apache-2.0
// A robot node's state file: everything a RobotNode needs to continue after a
// restart as if it had never stopped (robot_node --state PATH; docs/deployment.md,
// docs/adr/0021-robot-state-file.md): the filter (mean, covariance, slot layout),
// the L-map (every LMapEntry field), the Robot's frame bookkeeping (last frame, last
// odometer reading and frame time), and the node's last frame, event seq, counters, held notices
// and incarnation. Per-frame scratch (ElaGate, ConsensusSolver, the last frame's
// outgoing messages) is rebuilt by every frame and not kept; neither are processing
// times (DurationHistogram) nor the message layer's notice seq (RobotPorts).
//
// Format: JSON (nlohmann; doubles round-trip exactly) {"format", "version",
// ["mission",] "fnv1a64", "state"}: the checksum is FNV-1a 64 over state.dump(), so
// a flipped byte anywhere in the state is caught; "mission" (16 hexadecimal digits,
// with the team's keys on) says which mission the state belongs to. The covariance is kept as its lower triangle (symmetric
// by construction). Loading validates like a message (finite, bounded, ids and
// counts within the configuration, slots consistent with the L-map, P positive
// semi-definite) into a scratch node and swaps it in only when everything passed.
#pragma once

#include <cstdint>
#include <string>

#include "elaslam/robot_node/robot_node.hpp"

namespace elaslam {

constexpr const char* kRobotStateFormat = "elaslam.robot_state";
/// Version 2: the filter's state has the odometer's calibration states after the
/// pose (StateLayout), predictions in the history carry their dt, and the robot its
/// last frame's utime. A file of another version is refused (the robot starts fresh).
constexpr int kRobotStateVersion = 2;

/// The state file's text for `node` (start-up and between frames; allocates).
/// `mission` (not 0: the team's keys are on) is written in the file's head.
std::string save_robot_state(const RobotNode& node, std::uint64_t mission = 0);

/// Restore `node` from a state file's text. false with `why` (the field and the
/// problem) when the text is not a valid state for this node's robot id, capacity,
/// max_landmark_id and mode, or, with a `mission` (not 0), when the file is not of
/// that mission (a new mission starts fresh); `node` is then unchanged. Never throws.
bool load_robot_state(const std::string& text, RobotNode* node, std::string* why, std::uint64_t mission = 0);

/// FNV-1a 64 of a dumped "state" object, as hex: for tests and tools that edit a
/// state on purpose and must seal it again.
std::string robot_state_checksum(const std::string& state_dump);

}  // namespace elaslam

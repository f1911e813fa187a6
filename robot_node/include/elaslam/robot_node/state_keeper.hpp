// SPDX-License-Identifier: Apache-2.0
// A robot node's state file and restart policy (--state; docs/deployment.md): the
// node resumed from its file at start, saved atomically while it runs and at exit,
// and started fresh when the frames arriving do not continue the state (a new run,
// a node down too long) or when the sensor source starts over. robot_node runs it
// every turn of its shell; the in-process team runs it too, without a file.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

#include "elaslam/robot_node/robot_node.hpp"

namespace elaslam {

/// The state in `path` when there is one (true: resumed); a corrupt one is moved
/// aside to PATH.corrupt (said why) and the node starts fresh: a bad file must not
/// keep a robot down. A fresh start takes this start's incarnation (`incarnation`,
/// transport/incarnation.hpp: later starts have larger ones); a resumed node keeps its own.
/// `mission` (the team's keys' mission, 0: none): a state of another mission is not
/// resumed (robot_state.hpp).
bool resume_state(const std::string& path, std::int64_t incarnation, std::uint64_t mission, RobotNode* node);

/// Save the node's state to `path` atomically. A failed save is said once per series
/// (FAULT line) and flagged in STATUS (FAULT_SAVE_FAILED) until a save succeeds again.
void save_state(const std::string& path, RobotNode& node, std::uint64_t mission);

/// --state while running, called every turn of the shell (after a frame's messages
/// went out, never inside Robot::process): saves once a frame was processed, at most
/// every node.state_save_interval_s (0: after every frame). And a resumed state that
/// the arriving frames do not continue (a new run from frame 0, or down longer than
/// node.max_frame_gap: every frame refused as old or too far ahead) is dropped after
/// kMisfitFrames such refusals with none processed: the node starts fresh. Also
/// without a file (`path` empty): a sensor source that starts over while the node runs.
class StateKeeper {
 public:
  static constexpr std::int64_t kMisfitFrames = 10;
  using Clock = std::chrono::steady_clock;

  /// `resumed`: resume_state's result; `incarnation`: this start's.
  StateKeeper(std::string path, const RobotOptions& o, RobotNode* node, bool resumed, std::int64_t incarnation,
              std::uint64_t mission);

  void turn();

 private:
  std::int64_t refused() const;
  void check_fit();
  void start_fresh();
  void check_source();

  const std::string path_;
  const RobotOptions options_;
  RobotNode* node_;
  bool watching_;
  std::int64_t next_incarnation_;
  const std::uint64_t mission_;
  const Clock::duration period_;
  Clock::time_point next_save_;
  std::int64_t saved_frames_;
  const std::int64_t frames_at_start_;
  const std::int64_t refused_at_start_;
};

}  // namespace elaslam

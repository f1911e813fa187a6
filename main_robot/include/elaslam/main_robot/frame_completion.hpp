// SPDX-License-Identifier: Apache-2.0
// When the team has finished a frame, the moment main_robot publishes GLOBAL_MAP of
// it. A robot sends its POSE first and then the frame's events and snapshot; the
// POSE says up to which event seq the frame goes and whether a snapshot follows. A
// POSE whose events or snapshot are not all applied yet is held: the robot's frame is
// finished when they are, or, should some be lost, at the robot's next POSE. The team
// has finished the oldest frame of the robots seen. It keeps per robot what that
// needs, and nothing of the map: MainNode tells it what was applied.
#pragma once

#include <array>
#include <cstdint>

#include "elaslam/common/contract.hpp"

namespace elaslam {

class FrameCompletion {
 public:
  static constexpr int kRobots = contract::kMaxRobots;

  FrameCompletion();

  /// A POSE of `frame` no newer than one held or finished for the robot (a late or
  /// repeated datagram): it changes nothing.
  bool stale(int robot_id, int frame) const;

  /// What a new POSE did (take_pose).
  struct PoseOutcome {
    int finished = -1;                 // the team's newest finished frame when it advanced, else -1
    int let_go_frame = -1;             // an older held POSE let go now (its events late or lost), -1: none
    std::int64_t let_go_event_seq = 0;  // the event seq that one waited for
  };
  /// Robot `robot_id`'s POSE of `frame` (not stale), announcing events up to
  /// `event_seq` and `snapshot_chunks` chunks; `applied_seq`: the robot's last event
  /// seq applied. Its frame is finished now when all that is in, else the POSE is held
  /// and an older held one is let go (the map is not held back more than a frame).
  PoseOutcome take_pose(int robot_id, int frame, std::int64_t event_seq, int snapshot_chunks,
                        std::int64_t applied_seq);
  /// The robot's events up to `applied_seq` are applied: a held POSE they complete
  /// finishes its frame (take_finished).
  void events_applied(int robot_id, std::int64_t applied_seq);
  /// The last chunk of the robot's snapshot of `frame` is applied (it may come before
  /// the POSE that announces it).
  void snapshot_applied(int robot_id, int frame, std::int64_t applied_seq);
  /// The newest frame the team finished through events_applied or snapshot_applied
  /// since the last call, else -1.
  int take_finished() {
    const int f = finished_;
    finished_ = -1;
    return f;
  }

  /// The robot restarted without its state: what it announced no longer comes.
  void restart(int robot_id);
  /// A new run: the team's frame starts over.
  void new_run() { completed_ = -1; }

  /// The newest frame the whole team has finished, -1: none.
  int completed() const { return completed_; }
  /// The robot's last finished frame, -1: not heard from (no POSE).
  int robot_frame(int robot_id) const { return robot_frame_[index(robot_id)]; }

 private:
  static std::size_t index(int robot_id) { return static_cast<std::size_t>(robot_id - 1); }
  /// The robot finished `frame`: the team's newest finished frame when that advanced,
  /// else -1.
  int finished_frame(int robot_id, int frame);

  struct HeldPose {  // a robot's POSE waiting for what it announced
    int frame = -1;               // -1: none held
    std::int64_t event_seq = 0;   // the event seq it waits for
    bool snapshot = false;        // and whether it waits for its frame's snapshot
  };
  std::array<int, kRobots> robot_frame_;  // last finished frame per robot, -1: never seen
  std::array<HeldPose, kRobots> held_{};
  std::array<int, kRobots> snapshot_done_frame_;  // frame of the last snapshot whose last chunk was applied
  int finished_ = -1;
  int completed_ = -1;
};

}  // namespace elaslam

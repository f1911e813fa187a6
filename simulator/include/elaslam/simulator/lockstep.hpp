// SPDX-License-Identifier: Apache-2.0
// The simulator's waits on the team (docs/design.md section 1):
// - lockstep (--lockstep): after frame k the simulator waits until every robot's
//   POSE_<r> of frame k has come, bounded by a timeout, so the team runs as fast as
//   it answers and never faster;
// - readiness (--wait-for-nodes): every node announces itself on its STATUS_* channel
//   at start; waiting for them (instead of a fixed delay) means no frame goes out
//   before every subscriber exists.
// Both on the node shell: bad messages are counted, never fatal.
#pragma once

#include <cstdint>
#include <vector>

#include "elaslam/transport/node_shell.hpp"

namespace elaslam::sim {

class LockstepWaiter {
 public:
  /// POSE_<r> queue: at most one pose per robot per frame arrives between two waits;
  /// 64 absorbs a robot that catches up after a stall without unbounded memory.
  static constexpr int kPoseQueue = 64;

  /// Subscribes every robot's POSE_<r> (with the shell's channel suffix).
  LockstepWaiter(transport::NodeShell& shell, const std::vector<int>& robot_ids);

  /// Handle messages until every robot has reported a frame >= k (true), or
  /// `timeout_ms` passed or a stop was requested (false).
  bool wait(int k, int timeout_ms);

  std::int64_t rejected() const;       // a POSE whose robot id is not its channel's, or a negative frame
  std::int64_t decode_errors() const;  // not a pose_estimate_t
  std::int64_t transport_errors() const { return transport_errors_; }

 private:
  transport::NodeShell& shell_;
  std::vector<int> inputs_;  // the shell's input per robot
  std::vector<int> newest_;  // newest frame reported per robot, -1: none yet
  std::int64_t transport_errors_ = 0;
};

/// Handle messages until `n` nodes have announced themselves (distinct STATUS_ROBOT_<r>
/// / STATUS_MAIN channels), `timeout_ms` passed or a stop was requested. Says the
/// outcome ("N nodes ready"); true when all came.
bool wait_for_nodes(transport::NodeShell& shell, int n, int timeout_ms);

}  // namespace elaslam::sim

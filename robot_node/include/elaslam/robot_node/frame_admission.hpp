// SPDX-License-Identifier: Apache-2.0
// What a SENSOR frame must pass before the Robot sees it: the contract (robot id,
// counts, finite values, ranges, ids within capacity), one sighting per landmark,
// the order against the last processed frame, the frame window and the odometry
// bound. It holds the state those checks need (the last frame, a held frame jump, a
// refused odometer jump that may be a new origin) and nothing else: RobotNode counts
// and reports what it decides.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "elaslam/common/limits.hpp"
#include "elaslam/robot_node/robot.hpp"
#include "elaslam/sensor_frame_t.hpp"

namespace elaslam {

class FrameAdmission {
 public:
  FrameAdmission(const RobotOptions& options, int robot_id);

  /// The contract and the limits (odometer within world_bound_m): "" when valid, else
  /// the problem and `reason` (when given) its kind.
  std::string validate(const sensor_frame_t& msg, Refusal* reason = nullptr) const;
  /// "" unless a landmark is sighted twice in the frame (the contract allows one).
  /// Ids must have passed validate.
  std::string check_duplicate_ids(const sensor_frame_t& msg, Refusal* reason);

  /// True when `msg` does not continue the last processed frame the way a stream
  /// does (older, or further ahead than confirm_jump_frames): with one frame
  /// processed, that frame was not the stream's.
  bool breaks_from_last(const sensor_frame_t& msg) const;

  enum class Order { kNewer, kDuplicate, kOlder };
  /// `msg` against the last processed frame; an older one counts toward frames_behind.
  Order order(const sensor_frame_t& msg);

  /// A newer frame's window and odometry: "" when it may be processed (`reanchor`
  /// set when it re-anchors the odometer on a confirmed jump), else why not.
  std::string check_progress(const sensor_frame_t& msg, const Robot& robot, bool* reanchor, Refusal* reason);

  /// The frame went through the Robot.
  void processed(int frame) {
    last_frame_ = frame;
    behind_ = 0;
  }
  int last_frame() const { return last_frame_; }
  /// SENSOR frames refused as older than the last processed one since it was
  /// processed (RobotNode::frames_behind).
  int frames_behind() const { return behind_; }

 private:
  friend struct RobotStateAccess;  // the state file restores last_frame_

  RobotOptions options_;
  int robot_id_;
  int last_frame_ = -1;
  JumpGuard frame_guard_;         // frame jumps beyond confirm_jump_frames wait for the next frame
  Pose2 odo_candidate_;           // a refused odometer jump, possibly a new origin
  int odo_candidate_frame_ = -1;  // its frame, -1: none
  int odo_streak_ = 0;            // consecutive refused readings continuing it
  int behind_ = 0;                // SENSOR frames refused as older since the last processed one
  std::vector<std::uint8_t> id_seen_;  // duplicate-id check within a frame
};

}  // namespace elaslam

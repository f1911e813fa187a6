// SPDX-License-Identifier: Apache-2.0
// The filter's last few frames of operations, so that a candidate's sightings can
// correct the robot once it is confirmed (docs/adr/0007-candidate-history.md). A candidate is
// held in the filter as an inert state: its sightings
// correct only itself (a Schmidt "consider" update) until it has been seen
// consistently enough to be trusted. Then its earlier sightings would have corrected
// the pose too, had the robot known. FilterHistory keeps a copy of the filter as it
// was `window` frames ago (the lagged filter) and every operation applied since, in
// order. When a candidate is confirmed, its landmark-only corrections still in the
// window become full ones, and at the end of the frame the current filter is rebuilt:
// the lagged filter, then the operations again. Sightings older than the window stay
// as they were. Every decision (which observation corrected what, which landmark
// was added or removed) is replayed as it was taken; only the estimates change.
//
// Fixed memory: the lagged filter and a ring of operations, both allocated at
// construction; nothing allocates per frame (tests/robot_node/test_frame_no_alloc.cpp).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "elaslam/robot_node/ekf_slam.hpp"

namespace elaslam {

class FilterHistory {
 public:
  /// window_frames 0: off (nothing recorded, nothing allocated). max_ops: the ring's
  /// size; when it is full the oldest operation goes into the lagged filter early
  /// (the window shrinks, nothing is lost).
  FilterHistory(const EkfOptions& options, int window_frames, int max_ops);
  bool enabled() const { return window_ > 0; }
  int window() const { return window_; }

  /// kHeldPosition: a team increment for a candidate (Robot::hold_team_estimate),
  /// applied as nothing until the candidate is confirmed; then it is a kPosition.
  /// kMove: a followed mover's own prediction (EkfSlam::move_landmark; p the
  /// displacement, R its noise).
  enum class Kind : std::uint8_t { kPredict, kUpdate, kLandmarkOnly, kPosition, kAdd, kRemove, kHeldPosition, kMove };
  static const char* to_string(Kind k);
  /// One operation on a filter: the fields its kind uses.
  struct Op {
    Kind kind = Kind::kPredict;
    int frame = 0;
    int id = -1;
    RangeBearing z;                                   // update, landmark-only, add
    Pose2 increment;                                  // predict: the odometer's reported increment
    Eigen::Matrix3d U = Eigen::Matrix3d::Zero();      // predict
    double dt = 0.0;                                  // predict: the time it spans [s]
    Eigen::Vector2d p = Eigen::Vector2d::Zero();      // position; move: the displacement
    Eigen::Matrix2d R = Eigen::Matrix2d::Zero();      // position; move: the displacement's noise
  };
  static Op predict(int frame, const Pose2& increment, const Eigen::Matrix3d& U, double dt = 0.0);
  static Op update(int frame, int id, const RangeBearing& z);
  static Op update_landmark_only(int frame, int id, const RangeBearing& z);
  static Op update_position(int frame, int id, const Eigen::Vector2d& z, const Eigen::Matrix2d& R);
  static Op held_position(int frame, int id, const Eigen::Vector2d& z, const Eigen::Matrix2d& R);
  static Op add(int frame, int id, const RangeBearing& z);
  static Op move(int frame, int id, const Eigen::Vector2d& delta, const Eigen::Matrix2d& Q);
  static Op remove(int frame, int id);

  /// Apply one operation to a filter; false when the filter refuses it.
  static bool apply(const Op& op, EkfSlam* f);
  /// An operation the current filter has applied (successful ones only).
  void record(const Op& op);
  /// apply, then record when it succeeded.
  bool apply_and_record(const Op& op, EkfSlam* f);

  /// The current filter was reset or replaced (its first frame, a state file): the
  /// history starts over from it.
  void restart(const EkfSlam& current);

  /// Candidate `id` is confirmed: its landmark-only corrections in the window become
  /// full ones, and the newest held team increment of the candidate as it is now
  /// (after its last add) becomes a kPosition, copied to *position when given (the
  /// team channel commits it); older held ones stay nothing (the newest carries all
  /// the team's information, TeamChannel::offer). Returns how many ops changed.
  int upgrade(int id, Op* position = nullptr);

  /// End of `frame`'s corrections: operations of frames <= frame - window go into
  /// the lagged filter; when anything was upgraded, `current` is rebuilt from the
  /// lagged filter and the operations in the window. Returns the operations the
  /// rebuilt filter refused (its health checks; 0 normally).
  int end_frame(int frame, EkfSlam* current);

  // ---- state file (robot_state.cpp) ----------------------------------------------
  /// The lagged filter (nullptr when off) and the operations held, oldest first.
  const EkfSlam* lagged() const { return lagged_ ? &*lagged_ : nullptr; }
  const Op& op(int k) const { return ops_[index(k)]; }
  int capacity() const { return static_cast<int>(ops_.size()); }
  /// Replace the history by a saved one: the lagged filter's state (EkfSlam::restore)
  /// and the operations; when there are more than the ring holds, the oldest are
  /// applied to the lagged filter. kBadInput when off or when the lagged filter
  /// refuses the state. Start-up only (allocates).
  EkfStatus restore(const Eigen::VectorXd& x, const Eigen::MatrixXd& P, const std::vector<int>& slot_ids,
                    const std::vector<Op>& ops);
  int held() const { return count_; }
  std::int64_t rebuilds() const { return rebuilds_; }
  std::int64_t upgraded() const { return upgraded_; }

 private:
  /// The ring position of the k-th oldest operation held.
  std::size_t index(int k) const { return static_cast<std::size_t>((head_ + k) % static_cast<int>(ops_.size())); }
  Op& at(int k) { return ops_[index(k)]; }
  void commit_oldest();

  int window_;
  std::optional<EkfSlam> lagged_;
  std::vector<Op> ops_;
  int head_ = 0;
  int count_ = 0;
  bool dirty_ = false;
  std::int64_t rebuilds_ = 0;
  std::int64_t upgraded_ = 0;
};

}  // namespace elaslam

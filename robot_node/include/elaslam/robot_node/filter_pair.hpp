// SPDX-License-Identifier: Apache-2.0
// The robot's two filters, kept in step. The own filter holds the robot's own
// observations only: its map is what the robot reports (events, snapshots), and the
// ELA gate judges against it. With robot.team_map.fuse an aided filter holds the
// same operations on the same landmarks plus the team's increments (team_aid.hpp):
// its pose is the robot's pose. Each filter has its history (FilterHistory,
// candidate_history_frames), so a confirmed candidate's earlier sightings enter
// both as of their frames.
//
// Every operation that changes which landmarks are held, or that every filter must
// see, goes to the own filter first and then, as the same FilterHistory::Op, to the
// aided one; the own filter's result is returned. An operation the aided filter
// refuses is counted as a filter fault, as the own filter's are. Only the team's
// increments and a relocalisation treat the two differently. No allocation after
// construction.
#pragma once

#include <Eigen/Core>

#include <optional>

#include "elaslam/common/geometry.hpp"
#include "elaslam/robot_node/ekf_slam.hpp"
#include "elaslam/robot_node/filter_history.hpp"

namespace elaslam {

class FilterPair {
 public:
  /// `aided`: keep the aided filter (robot.team_map.fuse). `history_frames`,
  /// `history_ops`: each history's window and operation capacity (0 frames: off).
  FilterPair(const EkfOptions& options, bool aided, int history_frames, int history_ops);

  // ---- operations on both (the own filter's result returned) -----------------------
  // `faults` (never null) counts the operations a filter refused.
  /// Both filters start at `odometer` with covariance P0; the histories start over.
  void reset(const Pose2& odometer, const Eigen::Matrix3d& P0);
  /// A prediction; a refusal by the own filter is counted too.
  EkfStatus predict(int frame, const Pose2& increment, const Eigen::Matrix3d& U, double dt, int* faults);
  /// A sighting that corrects both filters; `gate`: the own filter's innovation gate
  /// (the aided one never gates again: the decision was taken). Nothing happens to
  /// the aided filter when the own one refuses or gates it.
  UpdateReport update(int frame, int id, const RangeBearing& z, bool gate, int* faults);
  /// A followed mover's own prediction in both filters (EkfSlam::move_landmark).
  EkfStatus move_landmark(int frame, int id, const Eigen::Vector2d& delta, const Eigen::Matrix2d& Q, int* faults);
  /// A sighting that refines the landmark alone (a candidate's: Schmidt update).
  void update_landmark_only(int frame, int id, const RangeBearing& z, int* faults);
  /// A landmark into both filters at its sighting; nothing to the aided filter when
  /// the own one refuses (the status says why).
  EkfStatus add(int frame, int id, const RangeBearing& z, int* faults);
  /// A landmark out of both. The aided filter's refusal is not a fault: its add had
  /// failed, there is nothing to remove.
  EkfStatus remove(int frame, int id);
  /// End of a frame: confirmed candidates' earlier sightings into both filters
  /// (FilterHistory::end_frame); returns the operations refused.
  int end_frame(int frame);
  /// A candidate confirmed (FilterHistory::upgrade): in the own history, and in the
  /// aided one, whose held team estimate of it (if any) comes back in `held`.
  void upgrade(int id, FilterHistory::Op* held);
  /// Both histories start over from the filters as they are now.
  void restart_history();
  /// Move the own filter by (own_rotation, own_translation) and the aided one by its
  /// own motion (a relocalisation); when the own filter refuses, nothing moves.
  EkfStatus apply_rigid_motion(double own_rotation, const Eigen::Vector2d& own_translation, double aided_rotation,
                               const Eigen::Vector2d& aided_translation);

  // ---- the aided filter alone (the team's increments) -------------------------------
  /// A team increment of landmark `id`'s position, recorded in the aided history
  /// when the filter takes it.
  UpdateReport update_aided_position(int frame, int id, const Eigen::Vector2d& z, const Eigen::Matrix2d& R);
  /// A team estimate held for a candidate (FilterHistory::held_position).
  void hold_aided_position(int frame, int id, const Eigen::Vector2d& z, const Eigen::Matrix2d& R);

  // ---- state ---------------------------------------------------------------------
  const EkfSlam& own() const { return own_; }
  bool has_aided() const { return aided_.has_value(); }
  /// The aided filter (has_aided() only).
  const EkfSlam& aided() const { return *aided_; }
  /// The robot's best estimate: the aided filter when there is one, else the own.
  const EkfSlam& estimate() const { return aided_ ? *aided_ : own_; }
  const FilterHistory& own_history() const { return own_history_; }
  const FilterHistory& aided_history() const { return aided_history_; }

 private:
  friend struct RobotStateAccess;  // the state file (robot_state.cpp): saves and restores the members below

  /// The operation on the aided filter (when there is one), recorded in its history
  /// when it succeeds, counted in `faults` (when given) when not.
  void to_aided(const FilterHistory::Op& op, int* faults);

  EkfSlam own_;
  std::optional<EkfSlam> aided_;
  FilterHistory own_history_;
  FilterHistory aided_history_;
};

}  // namespace elaslam

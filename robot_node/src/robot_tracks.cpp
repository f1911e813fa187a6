// SPDX-License-Identifier: Apache-2.0
// The robot's mover tracks (docs/tracking.md): the frame's sightings queued for the
// tracks and applied at its end, and the validated slow movers a robot follows in its
// filter (tracking.correct_pose). Algorithm 1 itself is in robot.cpp.
#include "elaslam/robot_node/robot.hpp"

#include <Eigen/Eigenvalues>

namespace elaslam {

// tracking.correct_pose: a candidate in the filter whose track is validated and
// likeliest static or bounded is followed. Its state in the filter moves as its
// track predicts over the frame's interval: the track's mean displacement, and
// the growth of its position covariance as the landmark's own process noise. The
// state keeps its cross-covariances with the pose and the map, so its sightings
// correct the pose with the uncertainty the motion adds (handle_candidates), and
// the robot never trusts a mover more than its track's model says it may.
void Robot::follow_movers(FrameSummary* s) {
  if (!options_.tracking.correct_pose || !tracks_.enabled()) return;
  for (const int id : tracks_.ids()) {
    const LMapEntry& e = lmap_[id];
    if (e.status != LandmarkStatus::kCandidate || !filters_.own().has_landmark(id)) continue;
    const MoverTrack& t = tracks_.track(id);
    if (!t.validated() || t.likeliest() == MotionModel::kConstantVelocity) continue;
    const Eigen::Vector2d before = t.mean().head<2>();
    const Eigen::Matrix2d before_cov = t.covariance().topLeftCorner<2, 2>();
    tracks_.predict(id, clock_s_);
    const Eigen::Vector2d delta = t.mean().head<2>() - before;
    Eigen::Matrix2d Q = t.covariance().topLeftCorner<2, 2>() - before_cov;
    Q = 0.5 * (Q + Q.transpose()).eval();
    // Mixing can narrow a model's spread: the process noise is the growth's
    // positive part.
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(Q);
    Q = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
    if (filters_.move_landmark(last_frame_, id, delta, Q, &s->filter_faults) != EkfStatus::kOk) {
      ++s->filter_faults;
      continue;
    }
    followed_frame_[static_cast<std::size_t>(id)] = last_frame_;
    ++s->movers_followed;
  }
}

void Robot::queue_track(TrackOp::Kind kind, int id, const RangeBearing& z, const Eigen::Vector2d& anchor,
                        bool may_begin) {
  if (!tracks_.enabled() || track_ops_.size() == track_ops_.capacity()) return;
  TrackOp op;
  op.kind = kind;
  op.id = id;
  op.z = z;
  op.anchor = anchor;
  op.may_begin = may_begin;
  track_ops_.push_back(op);
}

// The frame's track operations, with the pose the frame ends with (the one POSE
// reports) and its covariance; then the tracks unseen lately end.
void Robot::apply_track_ops() {
  if (!tracks_.enabled()) return;
  TrackSighting base;
  if (!track_ops_.empty()) {
    base.R = filters_.own().measurement_cov();
    base.pose = filters_.estimate().pose();
    base.pose_cov = filters_.estimate().pose_cov();
  }
  tracks_.apply(track_ops_, base, clock_s_);
}

}  // namespace elaslam

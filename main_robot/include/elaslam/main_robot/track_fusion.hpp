// SPDX-License-Identifier: Apache-2.0
// main_robot's fusion of the robots' tracks of moving landmarks (TRACKS_<r>) into the
// team's tracks (GLOBAL_TRACKS; docs/tracking.md "On the wire"). Each robot's newest
// TRACKS message replaces its previous one; a message more than `max_age_frames`
// older than the frame fused is left out (its robot stopped tracking, or is not
// heard). Per landmark the robots' tracks are fused by covariance intersection:
// several robots' tracks of one landmark follow the same motion and each carries its
// robot's pose error, so their errors are correlated by an unknown amount, and
// covariance intersection is consistent whatever that correlation is (Julier and
// Uhlmann 1997); a Kalman fusion that assumed them independent would be
// overconfident. The tracks are fused as sent, each at its robot's frame: none is
// predicted to a common time.
//
// Fixed memory: every buffer is sized at construction; take() and fuse() allocate
// nothing.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "elaslam/common/contract.hpp"
#include "elaslam/track_list_t.hpp"

namespace elaslam {

/// One estimate of a landmark's (p_x, p_y, v_x, v_y) in W with its covariance and
/// its motion models' probabilities (static, bounded, constant velocity).
struct TrackEstimate {
  int id = -1;
  Eigen::Vector4d x = Eigen::Vector4d::Zero();
  Eigen::Matrix4d P = Eigen::Matrix4d::Identity();
  std::array<double, 3> probabilities{};
};

/// A fused track: the estimate and the robots whose tracks are in it (bit r-1).
struct FusedTrack {
  TrackEstimate estimate;
  int contributors = 0;
  /// The model of highest probability (track_t::STATIC, BOUNDED, CONSTANT_VELOCITY).
  int likeliest() const;
  /// At rest: the static model holds at least half the probability (MoverTrack's rule).
  bool stopped() const { return estimate.probabilities[0] >= 0.5; }
};

/// Covariance intersection of two estimates a and b of one landmark:
///   P^-1 = w Pa^-1 + (1 - w) Pb^-1,  x = P (w Pa^-1 xa + (1 - w) Pb^-1 xb),
/// consistent for every w in [0, 1] whatever a and b's correlation. w minimises the
/// trace of P (the fused mean squared error): trace(P(w)) is convex in w (the matrix
/// inverse is operator-convex and its argument affine in w), so a golden-section
/// search over [0, 1] finds the minimum, and the ends (a or b alone) are compared
/// too. The model probabilities are averaged with the same weights. Returns w.
double covariance_intersection(const TrackEstimate& a, const TrackEstimate& b, TrackEstimate* fused);

class TrackFusion {
 public:
  /// Tracks of a TRACKS message this many frames older than the frame fused are
  /// left out: 1 s at the simulator's 10 Hz, a few frames of a lost datagram.
  static constexpr int kDefaultMaxAgeFrames = 10;

  explicit TrackFusion(int max_age_frames = kDefaultMaxAgeFrames);

  /// Robot r's TRACKS, validated (check_track_list): its tracks from now on, in
  /// place of those of its previous message.
  void take(const track_list_t& m);
  /// Robot r's tracks dropped (it restarted: its tracks of before are gone).
  void forget(int robot_id);
  /// The frame of robot r's newest TRACKS taken, -1: none.
  int robot_frame(int robot_id) const;

  /// Per landmark tracked by any robot whose newest TRACKS is at most max_age_frames
  /// older than `frame`: its tracks fused, in ascending robot id (covariance
  /// intersection pairwise: the running fusion with the next robot's track). In
  /// ascending landmark id; valid until the next call.
  const std::vector<FusedTrack>& fuse(int frame);

 private:
  struct RobotTracks {
    int frame = -1;
    int count = 0;
    std::array<TrackEstimate, contract::kMaxTracks> tracks;
  };
  int max_age_frames_;
  std::array<RobotTracks, contract::kMaxRobots> robots_;
  std::vector<std::pair<int, int>> order_;  // (landmark id, robot index * kMaxTracks + slot), sorted
  std::vector<FusedTrack> fused_;
};

}  // namespace elaslam

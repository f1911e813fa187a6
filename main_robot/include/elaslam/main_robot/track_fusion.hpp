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
// overconfident. Before fusion each track is predicted to the time of the frame
// fused (predict_track): a robot's tracks of frame k - 1 and another's of frame k
// are then estimates of one moment.
//
// Fixed memory: every buffer is sized at construction; take() and fuse() allocate
// nothing.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "elaslam/common/contract.hpp"
#include "elaslam/common/limits.hpp"
#include "elaslam/common/track_motion.hpp"
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

/// A track predicted dt [s] ahead by constant velocity (constant_velocity_step with
/// the robots' tracks' default white acceleration, kDefaultCvAccelSigma): p += v
/// dt, P <- F P F' + Q. The model
/// probabilities are kept: over the fraction of a second between two robots'
/// frames a mover keeps its motion (the tracks' model_sojourn_s is seconds).
TrackEstimate predict_track(const TrackEstimate& e, double dt);

class TrackFusion {
 public:
  /// Tracks of a TRACKS message this many frames older than the frame fused are
  /// left out: 1 s at the simulator's 10 Hz, a few frames of a lost datagram.
  static constexpr int kDefaultMaxAgeFrames = 10;

  explicit TrackFusion(int max_age_frames = kDefaultMaxAgeFrames);

  /// What take() did with a chunk.
  enum class Take {
    kTaken,    // stored (its publication complete or not yet)
    kStale,    // of an older publication, or a chunk already taken: ignored
    kRefused,  // does not agree with its publication's other chunks: nothing changes
  };
  /// A chunk of robot r's TRACKS, validated (check_track_list). Robot r's chunks of
  /// one frame are its publication; once all have come, their tracks replace those
  /// of its previous publication. A chunk of a newer frame while one is still
  /// missing takes the incomplete publication as it is (the tracks that came): they
  /// are newer than the previous publication's, whose movers may have gone since,
  /// and a lost chunk then costs its own tracks for one frame only. Refused (with
  /// `problem` and `reason`) when its num_chunks differs from its publication's or
  /// it lists a landmark an earlier chunk of the publication listed.
  Take take(const track_list_t& m, std::string* problem = nullptr, Refusal* reason = nullptr);
  /// Robot r's tracks dropped (it restarted: its tracks of before are gone).
  void forget(int robot_id);
  /// The frame of robot r's newest TRACKS chunk taken, -1: none.
  int robot_frame(int robot_id) const;
  /// Tracks of robot r fused from now on: its last complete publication (or the
  /// incomplete one a newer frame superseded).
  int robot_tracks(int robot_id) const;

  /// Per landmark tracked by any robot whose newest TRACKS is at most max_age_frames
  /// older than `frame`: its tracks, each predicted to `frame`'s time, fused in
  /// ascending robot id (covariance intersection pairwise: the running fusion with
  /// the next robot's track). A robot's frame period is measured from its own
  /// publications' stamps (two with different frames); until then its tracks are
  /// fused as sent. In ascending landmark id; valid until the next call.
  const std::vector<FusedTrack>& fuse(int frame);
  /// Robot r's frame period measured from its publications [s], 0: not yet.
  double robot_period_s(int robot_id) const;

 private:
  // Tracks one publication can carry: contract::kMaxTrackChunks chunks of
  // contract::kMaxTracks.
  static constexpr int kCapacity = contract::kMaxTrackChunks * contract::kMaxTracks;
  // One publication: chunk c's tracks at [c * kMaxTracks, c * kMaxTracks + counts[c]).
  struct Publication {
    int frame = -1;
    std::int64_t utime = 0;  // its stamp (the robot's frame's)
    int num_chunks = 0;
    unsigned received = 0;  // bit c: chunk c taken
    std::array<int, contract::kMaxTrackChunks> counts{};
    std::vector<TrackEstimate> tracks;  // kCapacity, sized at construction
    bool complete() const { return num_chunks > 0 && received == (1u << num_chunks) - 1; }
    int count() const;
  };
  struct RobotTracks {
    Publication fused;    // the tracks fuse() uses
    Publication arriving; // the chunks of a newer frame, until all have come
    double period_s = 0.0;  // frame period from two publications' stamps, 0: not yet
  };
  /// r.fused has just replaced `older`: the period between their stamps.
  static void measure_period(RobotTracks* r, const Publication& older);
  int max_age_frames_;
  std::array<RobotTracks, contract::kMaxRobots> robots_;
  std::vector<std::pair<int, int>> order_;  // (landmark id, robot index * kCapacity + slot), sorted
  std::vector<FusedTrack> fused_;
};

}  // namespace elaslam

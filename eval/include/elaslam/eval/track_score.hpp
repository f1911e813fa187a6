// SPDX-License-Identifier: Apache-2.0
// Scores the robots' tracks of moving landmarks against the ground truth
// (docs/tracking.md "Scores"): per frame, each track's position and velocity
// against the landmark's true position and its velocity over the last frame (the
// difference of two truth frames), its stop/go verdict against the truth's, and
// the latency from each true stop to the verdict. No dependency on the robot: the
// caller hands each frame's tracks as TrackSample.
#pragma once

#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace elaslam {

/// One robot's track of one landmark at one frame.
struct TrackSample {
  int robot = 0;        // robot index
  int landmark_id = -1;
  Eigen::Vector4d x = Eigen::Vector4d::Zero();  // (p_x, p_y, v_x, v_y) in W [m, m/s]
  Eigen::Matrix4d P = Eigen::Matrix4d::Zero();  // its covariance
  bool stopped = false;                          // the track's verdict: at rest
  std::int64_t sightings = 0;  // sightings since the track (re)started (fewer than at the last frame: a new track)
};

/// Scores over every scored track sample of a run. Counts of 0 leave their
/// figures at 0 (the report says "none").
struct TrackMetrics {
  /// A true speed at or below this is "at rest" [m/s]; speed and heading are scored above it.
  static constexpr double kMovingSpeedMps = 0.03;
  std::int64_t samples = 0;         // track samples with ground truth (position scored)
  double position_rms_m = 0.0;
  std::int64_t moving_samples = 0;  // ... whose landmark moved faster than kMovingSpeedMps
  double speed_rms_mps = 0.0;       // RMS of |v_est| - |v_true| over them
  double heading_rms_deg = 0.0;     // RMS of the angle between v_est and v_true over them
  // Stop/go: "stopped" verdicts against the truth at rest (a sample each).
  std::int64_t stopped_verdicts = 0;  // samples (with a true velocity) the track found stopped
  std::int64_t at_rest_samples = 0;   // samples (with a true velocity) truly at rest
  double stop_precision = 0.0;  // of the samples found stopped, the share truly at rest
  double stop_recall = 0.0;     // of the samples truly at rest, the share found stopped
  std::int64_t stops = 0;       // true stops (moving, then at rest) while tracked
  std::int64_t stops_found = 0; // ... that the track found stopped before the landmark moved on or the track ended
  double stop_latency_s = 0.0;  // mean time from a true stop to the track's stopped verdict, over those found
  // Consistency: NEES of (p, v), 4 dof, over the samples with a true velocity.
  std::int64_t nees_samples = 0;
  double nees_mean = 0.0;
  double nees_in_band = 0.0;    // the share inside the two-sided 95 % band of chi-square, 4 dof
  // Continuity: a segment is one robot's unbroken track of one landmark (a sample at
  // every frame, no restart in between).
  std::int64_t segments = 0;
  double mean_segment_s = 0.0;  // mean time from a segment's first sample to its last
};

class TrackScorer {
 public:
  /// Scores the samples of tracks with at least `min_sightings` sightings: 0 scores
  /// every sample; kEstablishedSightings scores a burst of sightings from its fifth
  /// on (MoverTrack::sightings counts the first), once the track is past its start
  /// from a zero velocity.
  static constexpr std::int64_t kEstablishedSightings = 5;
  explicit TrackScorer(std::int64_t min_sightings = 0) : min_sightings_(min_sightings) {}

  /// Adds one frame: its time [s], the true landmark positions by id (truth[id],
  /// present[id] != 0 where known) and every track's sample at this frame.
  void add(double time_s, const std::vector<Eigen::Vector2d>& truth, const std::vector<std::uint8_t>& present,
           const std::vector<TrackSample>& tracks);
  TrackMetrics finish() const;

 private:
  struct Open {  // a true stop not yet found by one robot's track
    double since_s = 0.0;
  };
  /// The landmarks' true motion over the last frame, by landmark id.
  struct TrueMotion {
    std::vector<std::uint8_t> has_velocity;  // both frames have the landmark
    std::vector<Eigen::Vector2d> velocity;
    std::vector<std::uint8_t> moving;  // faster than TrackMetrics::kMovingSpeedMps
  };
  TrueMotion true_motion(double dt, const std::vector<Eigen::Vector2d>& truth,
                         const std::vector<std::uint8_t>& present) const;
  /// A sample's velocity, stop verdict and 4-dof NEES against the true velocity `v`.
  void score_velocity(const TrackSample& s, const Eigen::Vector2d& position_error, const Eigen::Vector2d& v,
                      bool moving);
  /// Stops: a landmark that moved at the last frame and rests now has stopped; its
  /// track's first "stopped" verdict from then on ends the wait. A wait ends unfound
  /// when the landmark moves on or its track ends: what still waits goes to *still_open.
  void follow_stop(const std::pair<int, int>& key, const TrackSample& s, double time_s, bool was_moving, bool moving,
                   std::map<std::pair<int, int>, Open>* still_open);
  std::int64_t min_sightings_ = 0;
  double last_time_s_ = 0.0;
  bool have_last_ = false;
  std::vector<Eigen::Vector2d> last_truth_;
  std::vector<std::uint8_t> last_present_;
  std::vector<std::uint8_t> was_moving_;  // by landmark id: moving at the last frame
  std::map<std::pair<int, int>, Open> open_stops_;  // (robot, landmark) -> stop waiting for its verdict
  std::map<std::pair<int, int>, std::int64_t> last_sightings_;  // (robot, landmark) -> sightings, last frame
  std::int64_t segments_ = 0;
  double segment_time_s_ = 0.0;
  std::int64_t n_ = 0, n_moving_ = 0, n_nees_ = 0, nees_in_ = 0;
  double pos2_ = 0.0, speed2_ = 0.0, heading2_ = 0.0, nees_ = 0.0;
  std::int64_t found_stopped_ = 0, found_and_at_rest_ = 0, at_rest_ = 0;
  std::int64_t stops_ = 0, stops_found_ = 0;
  double latency_sum_ = 0.0;
};

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// Metrics of docs/design.md section 7 (paper eqs 17-19), computed from ground truth and
// the team's outputs frame by frame. The same accumulator serves the in-process
// run (run_scenario, sweep) and the evaluation of recorded LCM logs (evaluate), so
// both report the same figures by construction.
//
// Definitions (kept exactly; peers compare against them):
// - Landmark error at frame k (eq 17): (1/n) sum_i ||x_hat_i - x_i(k)|| over the n
//   landmarks in the global map at frame k, against their true positions at k. A
//   mean Euclidean error despite the paper's name; the true RMS is reported beside
//   it, and the mean over truly static landmarks only. Whole run (eq 18): the mean
//   over the frames whose global map is not empty.
// - Robot error: ||p_hat - p|| of each robot's position estimate per frame;
//   `error_mean` is its mean over the run's frames (the paper's Tables 2-4 figure),
//   `error_rms` the root of the mean square.
// - Uncertainty (eq 19): mean(diag(P)) of each robot's filter at the last frame.
// - Detection: a landmark is flagged when it appears in the global map's moving
//   list in any frame. precision = |flagged and moving| / |flagged|; recall =
//   |flagged and moving| / |moving and observed by some robot|; frames to detect =
//   first flagged frame - first observed frame, averaged over detected ones.
//   precision is 1 when nothing is flagged; recall is 1 when nothing could be.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "elaslam/common/geometry.hpp"
#include "elaslam/eval/track_score.hpp"

namespace elaslam {

/// What one frame contributes (a neutral form that both the in-process run and a
/// recorded log can fill).
struct FrameData {
  int frame = 0;
  double time_s = 0.0;  // seconds since the run's first frame
  // Ground truth.
  std::vector<int> robot_ids;                     // 1-based
  std::vector<Pose2> true_poses;                  // by robot index
  std::vector<Eigen::Vector2d> true_landmarks;    // index = landmark id
  std::vector<std::uint8_t> truly_moving;         // index = landmark id
  // Estimates (by robot index; `has_pose` false when a robot published nothing).
  std::vector<std::uint8_t> has_pose;
  std::vector<Pose2> est_poses;
  std::vector<double> mean_diag_p;
  std::vector<std::int64_t> processing_us;
  // Global map at this frame: static landmarks (id, estimate) and moving ids.
  std::vector<std::pair<int, Eigen::Vector2d>> map_landmarks;
  std::vector<int> map_moving;
  // Landmarks observed by any robot in this frame (for detection recall).
  std::vector<int> observed;
};

struct RobotMetrics {
  int id = 0;
  double error_mean = 0.0;        // [m]
  double error_rms = 0.0;         // [m]
  double final_uncertainty = 0.0; // mean(diag(P)) at the last frame (eq 19)
  int frames = 0;                 // frames with an estimate
  // The bounded filter (Robot::make_room), from the robot's counters: in-process runs
  // only (node_counters true; evaluate, reading a log, has no such counters).
  bool node_counters = false;
  std::int64_t filter_full = 0;   // landmarks not added: every slot held something in range
  std::int64_t evictions = 0;     // landmarks that left the full filter to make room
  std::int64_t restored = 0;      // evicted landmarks seen again and back in the filter
  std::int64_t movers_followed = 0;    // candidate-frames followed as their tracks predict (tracking.correct_pose)
  std::int64_t mover_corrections = 0;  // ... sightings of them that corrected the filter
  int final_landmarks = 0;        // landmarks in the filter at the end (candidates included)
  // The team map's verdicts on the robot (Robot::apply_team_map), from its counters.
  std::int64_t team_lost = 0;     // team maps fused untested: the robot was lost and saw it itself
  std::int64_t relocalised = 0;   // team maps whose gauge test moved the robot's whole state
  std::int64_t own_drifted_frames = 0;  // frames its own filter had drifted from the aided one: no MOVING finding
  // The odometer's calibration the robot's own filter estimated, at the end
  // (robot.odometry_calibration with a sigma or walk > 0; in-process runs only).
  bool calibration_estimated = false;
  double turn_scale = 1.0, turn_scale_sigma = 0.0;
  double speed_scale = 1.0, speed_scale_sigma = 0.0;
  double turn_bias_rad_s = 0.0, turn_bias_sigma_rad_s = 0.0;
};

struct RunMetrics {
  int frames = 0;
  double landmark_error_mean = 0.0;   // eq 18 [m]
  double landmark_error_rms = 0.0;    // mean over frames of the per-frame RMS [m]
  double landmark_error_static = 0.0; // eq 18 over truly static landmarks only [m]
  std::vector<RobotMetrics> robots;
  double precision = 1.0;
  double recall = 1.0;
  double mean_frames_to_detect = 0.0;
  int flagged = 0, true_positives = 0, detectable = 0;
  std::int64_t frame_us_p50 = 0, frame_us_p99 = 0, frame_us_max = 0;
  // The robots' tracks of moving landmarks against the truth (track_score.hpp):
  // in-process runs with robot.tracking on; recorded logs with TRACKS_<r> in them.
  bool tracks_scored = false;
  TrackMetrics tracks;              // every sample
  TrackMetrics tracks_established;  // samples from a track's fifth sighting on
  // The same tracks replayed with each observer's true pose and no pose
  // covariance (the robot's own sightings, starts and ends): the tracking's own
  // error, without the observer's localisation error.
  bool tracks_true_pose_scored = false;
  TrackMetrics tracks_true_pose, tracks_true_pose_established;
  // main_robot's fused tracks (GLOBAL_TRACKS) against the truth: recorded logs.
  bool global_tracks_scored = false;
  TrackMetrics global_tracks;
};

/// Per-frame row of frames.csv.
struct FrameMetrics {
  int frame = 0;
  double time_s = 0.0;
  double landmark_error = 0.0, landmark_rms = 0.0, landmark_static_error = 0.0;
  int map_landmarks = 0, map_moving = 0;
  std::vector<double> robot_error;        // by robot index (NaN when no estimate)
  std::vector<double> robot_uncertainty;  // mean(diag(P)) by robot index
};

class MetricsAccumulator {
 public:
  void add(const FrameData& f);
  RunMetrics finish() const;
  const std::vector<FrameMetrics>& frames() const { return frames_; }
  const std::vector<int>& robot_ids() const { return robot_ids_; }

 private:
  std::vector<int> robot_ids_;
  std::vector<FrameMetrics> frames_;
  std::vector<double> err_sum_, err_sq_sum_, last_unc_;
  std::vector<int> err_n_;
  std::vector<std::int64_t> processing_;
  std::map<int, int> first_observed_, first_flagged_;
  std::vector<std::uint8_t> ever_moving_;
};

}  // namespace elaslam

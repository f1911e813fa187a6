// SPDX-License-Identifier: Apache-2.0
// What a run gives the evaluation, however it ran (the team in process, or a
// recorded log assembled by log_frames.hpp): the metrics and their frames, each
// robot's trajectories, and the final map against the ground truth.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "elaslam/common/geometry.hpp"
#include "elaslam/eval/metrics.hpp"

namespace elaslam {

struct TrajectoryPoint {
  double time_s = 0.0;
  Pose2 pose;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();  // the estimate's covariance (POSE; zero for truth)
};

struct RunResult {
  RunMetrics metrics;
  std::vector<FrameMetrics> frames;
  std::vector<int> robot_ids;
  std::vector<std::vector<TrajectoryPoint>> estimated;  // by robot index
  std::vector<std::vector<TrajectoryPoint>> truth;      // by robot index
  // Final global map (id, estimate, covariance) and moving ids, for plots.
  struct MapLandmark {
    int id;
    Eigen::Vector2d p;
    Eigen::Matrix2d cov;
  };
  std::vector<MapLandmark> final_map;
  std::vector<int> final_moving;
  std::vector<Eigen::Vector2d> final_truth;  // true landmark positions at the last frame
  std::vector<std::uint8_t> truly_moving;
  std::vector<std::uint8_t> truth_present;  // ids with ground truth (empty: all of final_truth)
  long long bus_messages = 0;  // messages published on the in-process transport
  // Observations that corrected a robot's pose (all robots), by landmark id.
  std::vector<long> corrections_by_landmark;
  // Landmarks main took as moving because a robot was where they were (main.body_radius_m).
  long long occupied = 0;
  // Rounds of team maps each robot (by robot index) was left out of, its map refused
  // by the others' (main.team_map_check_probability, GlobalMap::check_team).
  std::vector<long long> team_map_left_out;
};

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// The simulated world, frame by frame: true robot poses on their semicircles,
// static and moving landmarks, each robot's odometer and sensor frame.
// No I/O; deterministic for a given ScenarioOptions (random.hpp).
//
// Frame k is the state at time t_k = k / rate_hz. The constructor builds frame 0
// (robots at their known initial poses, odometers equal to those poses, the first
// observations taken there); step() advances to frame k + 1.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "elaslam/common/geometry.hpp"
#include "elaslam/simulator/random.hpp"
#include "elaslam/simulator/scenario.hpp"
#include "elaslam/simulator/sensor.hpp"

namespace elaslam::sim {

/// What one robot's sensors report for one frame (the content of sensor_frame_t).
struct SensorFrame {
  int robot_id = 0;
  int frame = 0;
  Pose2 odometer;                 // T_OB: cumulative noisy pose in the odometry frame O
  OdometryOptions odometry_noise; // the model the odometer's noise follows
  int num_obs = 0;
  ObservationArray obs{};         // first num_obs valid, sorted by landmark id
};

struct WorldCounters {
  std::int64_t truncated_obs = 0;        // observations dropped by sensor.max_observations
  std::int64_t frames_truncated = 0;     // sensor frames that hit the cap
  std::int64_t border_reflections = 0;   // landmark steps that bounced off a world border
};

class World {
 public:
  /// `o` must pass check_scenario (load_scenario guarantees it); otherwise this
  /// throws std::invalid_argument naming the problems (a programming error).
  explicit World(const ScenarioOptions& o);

  /// Advance one frame (1 / rate_hz seconds).
  void step();

  int frame() const { return frame_; }
  const ScenarioOptions& options() const { return options_; }
  int num_robots() const { return static_cast<int>(robot_T_WB_.size()); }
  int num_landmarks() const { return static_cast<int>(p_LinW_.size()); }

  /// True pose T_WB of robot index i (0-based, in the order of options().robots).
  const Pose2& robot_pose(int i) const { return robot_T_WB_[static_cast<std::size_t>(i)]; }
  /// True landmark positions p_LinW at this frame, index = landmark id.
  const std::vector<Eigen::Vector2d>& landmark_positions() const { return p_LinW_; }
  /// Whether landmark id is in the moving set (a stop-and-go mover standing still is).
  bool is_moving(int id) const { return moving_[static_cast<std::size_t>(id)] != 0; }
  /// How landmark id moves: kStatic outside the moving set, else the kind it took
  /// from scenario.movers.kinds (the moving ids ascending take the kinds in turn).
  MotionKind kind(int id) const { return kind_[static_cast<std::size_t>(id)]; }
  /// Whether landmark id stood still over the last step() (always for a static one;
  /// a stop-and-go mover in a stop). At frame 0: whether its first step is a stop.
  bool standing_still(int id) const { return standing_[static_cast<std::size_t>(id)] != 0; }
  /// True velocity of landmark id in W [m/s] over the last step(): its displacement
  /// times rate_hz, zero while it stands still (after a bounce within the step, the
  /// mean over the step, shorter than the speed; direction() is the new heading).
  /// At frame 0: the velocity it starts with, its speed along its initial direction
  /// (zero when static or when its first step is a stop).
  const Eigen::Vector2d& velocity(int id) const { return velocity_[static_cast<std::size_t>(id)]; }
  /// Current unit direction of landmark id in W (defined for static ones too, unused).
  const Eigen::Vector2d& direction(int id) const { return dir_[static_cast<std::size_t>(id)]; }
  /// Whether landmark id bounced off a border during the last step().
  bool reflected_last_step(int id) const { return reflected_[static_cast<std::size_t>(id)] != 0; }

  /// Robot index i's sensor frame for the current frame.
  const SensorFrame& sensor_frame(int i) const { return frames_[static_cast<std::size_t>(i)]; }

  const WorldCounters& counters() const { return counters_; }

 private:
  void sense();
  void pick_moving_set();
  void assign_kinds();
  /// Whether stop-and-go landmark i moves in the step from frame k to k + 1.
  bool moves_in_step(std::size_t i, int k) const;

  ScenarioOptions options_;
  int frame_ = 0;
  std::vector<Pose2> robot_T_WB_;
  std::vector<Pose2> odometer_;        // T_OB per robot
  std::vector<Rng> odometry_rng_;      // per robot
  std::vector<Sensor> sensors_;        // per robot
  std::vector<SensorFrame> frames_;    // per robot, current frame
  std::vector<Eigen::Vector2d> p_LinW_;
  std::vector<Eigen::Vector2d> dir_;
  std::vector<std::uint8_t> moving_;
  std::vector<std::uint8_t> reflected_;
  std::vector<MotionKind> kind_;
  std::vector<std::uint8_t> standing_;
  std::vector<Eigen::Vector2d> velocity_;
  std::vector<std::int64_t> phase_;    // stop-and-go: steps into the cycle at frame 0, in [0, cycle)
  std::int64_t move_frames_ = 1;       // stop-and-go stretches [frames]
  std::int64_t stop_frames_ = 1;
  WorldCounters counters_;
};

}  // namespace elaslam::sim

// SPDX-License-Identifier: Apache-2.0
#include "elaslam/simulator/world.hpp"

#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <string>

#include "elaslam/simulator/layout.hpp"
#include "elaslam/simulator/motion.hpp"

namespace elaslam::sim {

World::World(const ScenarioOptions& o) : options_(o) {
  const std::vector<Problem> problems = check_scenario(o);
  if (!problems.empty()) {
    std::string all = "World: invalid scenario:";
    for (const auto& p : problems) all += " scenario." + p.key + ": " + p.what + ";";
    throw std::invalid_argument(all);
  }
  std::string why;
  generate_layout(o, &p_LinW_, &why);  // cannot fail: check_scenario built it too
  const std::size_t n = p_LinW_.size();
  reflected_.assign(n, 0);
  pick_moving_set();
  assign_kinds();

  const auto seed = static_cast<std::uint64_t>(o.seed);
  for (const RobotPathOptions& path : o.robots) {
    const auto id = static_cast<std::uint64_t>(path.id);
    const Pose2 T0 = path_pose(path, 0.0);
    robot_T_WB_.push_back(T0);
    odometer_.push_back(T0);  // O coincides with W at the start: the initial pose is known
    odometry_rng_.emplace_back(seed, stream::kOdometryNoise + id);
    sensors_.emplace_back(o.sensor, static_cast<int>(n), Rng(seed, stream::kSensorNoise + id),
                          Rng(seed, stream::kDetection + id));
    frames_.emplace_back();
    frames_.back().obs.resize(static_cast<std::size_t>(o.sensor.max_observations));
  }
  sense();
}

// The moving set is a prefix of one seeded permutation of the ids, so a higher
// dynamism moves a superset of the landmarks a lower one moves. Directions are
// drawn for every landmark from their own stream: neither depends on the dynamism.
void World::pick_moving_set() {
  const std::size_t n = p_LinW_.size();
  std::vector<int> perm(n);
  std::iota(perm.begin(), perm.end(), 0);
  Rng pick(static_cast<std::uint64_t>(options_.seed), stream::kMovingSet);
  for (std::size_t i = n; i > 1; --i) std::swap(perm[i - 1], perm[pick.below(i)]);  // Fisher-Yates
  moving_.assign(n, 0);
  const int m = options_.moving_count(static_cast<int>(n));
  for (int i = 0; i < m; ++i) moving_[static_cast<std::size_t>(perm[static_cast<std::size_t>(i)])] = 1;

  Rng dirs(static_cast<std::uint64_t>(options_.seed), stream::kDirections);
  dir_.clear();
  for (std::size_t i = 0; i < n; ++i) dir_.push_back(direction_vector(static_cast<int>(dirs.below(4))));
}

// The moving landmarks take the listed kinds in turn, ids ascending. A stop-and-go
// cycle's starting point is drawn for every landmark from its own stream, one number
// each, so that it depends neither on the dynamism nor on the kinds of the others;
// the streams of the layout, the moving set and the directions are left as they were.
void World::assign_kinds() {
  const std::size_t n = p_LinW_.size();
  const std::vector<MotionKind>& kinds = options_.movers.kinds;
  kind_.assign(n, MotionKind::kStatic);
  std::size_t j = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (moving_[i]) kind_[i] = kinds[j++ % kinds.size()];

  // At least a frame each (check_scenario holds them there when a mover uses them).
  move_frames_ = std::max(1, options_.stop_and_go_move_frames());
  stop_frames_ = std::max(1, options_.stop_and_go_stop_frames());
  const std::int64_t cycle = move_frames_ + stop_frames_;
  Rng phases(static_cast<std::uint64_t>(options_.seed), stream::kMoverPhase);
  phase_.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i)
    phase_[i] = std::min(cycle - 1, static_cast<std::int64_t>(phases.uniform() * static_cast<double>(cycle)));

  // Frame 0: the motion each landmark starts with.
  const double speed = options_.landmark_speed_mps;
  standing_.assign(n, 1);
  velocity_.assign(n, Eigen::Vector2d::Zero());
  for (std::size_t i = 0; i < n; ++i) {
    if (kind_[i] == MotionKind::kStatic || (kind_[i] == MotionKind::kStopAndGo && !moves_in_step(i, 0))) continue;
    standing_[i] = 0;
    velocity_[i] = speed * dir_[i];
  }
}

bool World::moves_in_step(std::size_t i, int k) const {
  return (static_cast<std::int64_t>(k) + phase_[i]) % (move_frames_ + stop_frames_) < move_frames_;
}

void World::step() {
  const int k = frame_;
  // Landmarks: the move from frame k to k + 1. Every reversal period each
  // oscillating landmark turns to the opposite direction (paper section 4); the
  // constant-velocity ones keep theirs, and the stop-and-go ones keep theirs while
  // they move and stand in between. All bounce off the borders and the empty region.
  const double step_m = options_.landmark_speed_mps / options_.rate_hz;
  const bool reverse = k > 0 && k % options_.reversal_period_frames == 0;
  for (std::size_t i = 0; i < p_LinW_.size(); ++i) {
    reflected_[i] = 0;
    if (!moving_[i]) continue;
    if (kind_[i] == MotionKind::kStopAndGo && !moves_in_step(i, k)) {
      standing_[i] = 1;
      velocity_[i].setZero();
      continue;
    }
    if (reverse && kind_[i] == MotionKind::kOscillating) dir_[i] = -dir_[i];
    const Eigen::Vector2d from = p_LinW_[i];
    if (advance_landmark(&p_LinW_[i], &dir_[i], step_m, options_.world, options_.landmarks.empty_region)) {
      reflected_[i] = 1;
      ++counters_.border_reflections;
    }
    standing_[i] = 0;
    velocity_[i] = (p_LinW_[i] - from) * options_.rate_hz;
  }
  // Robots follow their paths exactly; the odometer integrates what it reports of
  // the true increment (its systematic error inverted), with noise on top.
  const double t_next = (k + 1) / options_.rate_hz;
  for (std::size_t r = 0; r < robot_T_WB_.size(); ++r) {
    const RobotPathOptions& robot = options_.robots[r];
    const Pose2 T_next = path_pose(robot, t_next);
    const Pose2 u = between(robot_T_WB_[r], T_next);  // true increment, in B at frame k
    const Pose2 u_reported = reported_increment(u, robot.odometer, options_.dt_s());
    odometer_[r] = compose(odometer_[r], noisy_increment(u_reported, options_.odometry, &odometry_rng_[r]));
    robot_T_WB_[r] = T_next;
  }
  frame_ = k + 1;
  sense();
}

void World::sense() {
  for (std::size_t r = 0; r < robot_T_WB_.size(); ++r) {
    SensorFrame& f = frames_[r];
    f.robot_id = options_.robots[r].id;
    f.frame = frame_;
    f.odometer = odometer_[r];
    f.odometry_noise = options_.odometry;
    int truncated = 0;
    f.num_obs = sensors_[r].observe(robot_T_WB_[r], p_LinW_, &f.obs, &truncated);
    if (truncated > 0) {
      counters_.truncated_obs += truncated;
      ++counters_.frames_truncated;
    }
  }
}

}  // namespace elaslam::sim

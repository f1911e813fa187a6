// SPDX-License-Identifier: Apache-2.0
#include "elaslam/simulator/world.hpp"

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

void World::step() {
  const int k = frame_;
  // Landmarks: the move from frame k to k + 1. Every reversal period each moving
  // landmark turns to the opposite direction (paper section 4).
  const double step_m = options_.landmark_speed_mps / options_.rate_hz;
  const bool reverse = k > 0 && k % options_.reversal_period_frames == 0;
  for (std::size_t i = 0; i < p_LinW_.size(); ++i) {
    reflected_[i] = 0;
    if (!moving_[i]) continue;
    if (reverse) dir_[i] = -dir_[i];
    if (advance_landmark(&p_LinW_[i], &dir_[i], step_m, options_.world, options_.landmarks.empty_region)) {
      reflected_[i] = 1;
      ++counters_.border_reflections;
    }
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

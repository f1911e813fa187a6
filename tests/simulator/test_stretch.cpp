// SPDX-License-Identifier: Apache-2.0
// Landmark-free stretches: config/odometry_bias.yaml's robot 1 turns
// 115 deg in place inside the empty region, sees nothing meanwhile, and sees
// landmarks again afterwards; moving landmarks never enter the region.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "elaslam/simulator/motion.hpp"
#include "elaslam/simulator/world.hpp"
#include "sim_test_util.hpp"

namespace elaslam::sim {
namespace {

const std::string kExample = std::string(ELASLAM_SOURCE_DIR) + "/config/odometry_bias.yaml";

// The example's turn in place: 3.7 s to 6.7 s at 10 Hz, frames 37..67.
constexpr int kSpinFirst = 37, kSpinLast = 67;

TEST(SimStretch, TheExampleConfigSaysWhatItsCommentsSay) {
  const ScenarioOptions o = load_scenario(kExample);
  ASSERT_EQ(o.robots.size(), 3u);
  EXPECT_EQ(o.robots[0].odometer.turn_scale, 0.9);
  EXPECT_EQ(o.robots[0].odometer.speed_scale, 0.95);
  EXPECT_EQ(o.robots[0].odometer.turn_bias_rad_s, 0.0);
  EXPECT_TRUE(o.robots[1].odometer.none());
  EXPECT_TRUE(o.robots[2].odometer.none());
  EXPECT_EQ(o.robots[0].spin.turn_deg, 115.0);
  EXPECT_EQ(std::lround(o.robots[0].spin.start_s * o.rate_hz), kSpinFirst);
  EXPECT_EQ(std::lround((o.robots[0].spin.start_s + o.robots[0].spin.duration_s) * o.rate_hz), kSpinLast);
  EXPECT_EQ(World(o).num_landmarks(), 63);  // 9 of the grid's 72 in the empty region
}

TEST(SimStretch, RobotOneTurnsBlindThenSeesLandmarksAgain) {
  // GIVEN the example in a static world, at its own 50 % at 0.5 m/s, and with every
  // landmark moving at 0.9 m/s; noise-free odometers (the systematic error alone)
  for (const auto& [dynamism, speed] : {std::pair{0.0, 0.5}, std::pair{50.0, 0.5}, std::pair{100.0, 0.9}}) {
    ScenarioOptions o = load_scenario(kExample);
    o.dynamism_percent = dynamism;
    o.landmark_speed_mps = speed;
    o.odometry = {0.0, 0.0, 0.0};
    World w(o);
    Pose2 T_start, odo_start;
    int seen_before = 0, seen_after = 0;
    for (int k = 0; k < o.frames; ++k, w.step()) {
      const SensorFrame& f = w.sensor_frame(0);
      if (k <= 30) seen_before += f.num_obs > 0;
      if (k >= 75) seen_after += f.num_obs > 0;
      if (k == kSpinFirst) {
        T_start = w.robot_pose(0);
        odo_start = f.odometer;
      }
      if (k < kSpinFirst || k > kSpinLast) continue;
      // THEN while it turns robot 1 sees nothing and stays where it is
      EXPECT_EQ(f.num_obs, 0) << "frame " << k << ", dynamism " << dynamism;
      EXPECT_EQ(w.robot_pose(0).x, T_start.x);
      EXPECT_EQ(w.robot_pose(0).y, T_start.y);
      if (k != kSpinLast) continue;
      // AND it has turned by 115 deg, and its odometer says 115 / 0.9 = 127.8 deg
      EXPECT_NEAR(wrap_angle(w.robot_pose(0).theta - T_start.theta), deg2rad(115.0), 1e-12);
      const Pose2 reported = between(odo_start, f.odometer);
      EXPECT_NEAR(reported.theta, deg2rad(115.0) / 0.9, 1e-12);
      EXPECT_NEAR(std::hypot(reported.x, reported.y), 0.0, 1e-12);
    }
    // AND it sees landmarks in every frame before the stretch and after it
    EXPECT_EQ(seen_before, 31) << dynamism;
    EXPECT_EQ(seen_after, o.frames - 75) << dynamism;
  }
}

/// Runs `o` and checks that no landmark is ever strictly inside the empty region or
/// outside the world; returns the reflections that happened next to the region
/// (within a step of its outline, away from the world's border).
int region_bounces(const ScenarioOptions& o) {
  const EmptyRegion& e = o.landmarks.empty_region;
  const double step = o.landmark_speed_mps / o.rate_hz;
  int bounces = 0;
  World w(o);
  for (int k = 1; k < o.frames; ++k) {
    w.step();
    for (int i = 0; i < w.num_landmarks(); ++i) {
      const Eigen::Vector2d& p = w.landmark_positions()[static_cast<std::size_t>(i)];
      EXPECT_FALSE(e.contains(p.x(), p.y())) << "landmark " << i << " at frame " << k << ", seed " << o.seed;
      EXPECT_TRUE(p.x() >= -10.0 && p.x() <= 10.0 && p.y() >= -10.0 && p.y() <= 10.0);
      const bool near_region = p.x() > e.x_min_m - step && p.x() < e.x_max_m + step && p.y() > e.y_min_m - step &&
                               p.y() < e.y_max_m + step;
      const bool near_border = std::abs(std::abs(p.x()) - 10.0) < step || std::abs(std::abs(p.y()) - 10.0) < step;
      bounces += w.reflected_last_step(i) && near_region && !near_border;
    }
  }
  EXPECT_GE(w.counters().border_reflections, bounces);  // counted with the border's
  return bounces;
}

TEST(SimStretch, MovingLandmarksNeverEnterTheEmptyRegion) {
  // GIVEN every landmark moving at 0.9 m/s, in five runs of different seeds
  ScenarioOptions o = load_scenario(kExample);
  o.dynamism_percent = 100.0;
  o.landmark_speed_mps = 0.9;
  int bounces = 0;
  for (int seed = 1; seed <= 5; ++seed) {
    o.seed = seed;
    // THEN none is ever inside the region (nor outside the world)
    bounces += region_bounces(o);
  }
  // AND they do bounce off it
  EXPECT_GT(bounces, 20);
}

}  // namespace
}  // namespace elaslam::sim

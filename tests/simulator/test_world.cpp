// SPDX-License-Identifier: Apache-2.0
// The world over whole runs: determinism, the moving set, landmark motion
// (speed, reversal, borders), robot paths, field of view, message contents.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "elaslam/simulator/messages.hpp"
#include "elaslam/simulator/motion.hpp"
#include "elaslam/simulator/world.hpp"
#include "sim_test_util.hpp"

namespace elaslam::sim {
namespace {

using test::run_bytes;

std::set<int> moving_set(const ScenarioOptions& o) {
  World w(o);
  std::set<int> s;
  for (int i = 0; i < w.num_landmarks(); ++i)
    if (w.is_moving(i)) s.insert(i);
  return s;
}

ScenarioOptions dynamic(double dynamism, double speed) {
  ScenarioOptions o = test::paper();
  o.dynamism_percent = dynamism;
  o.landmark_speed_mps = speed;
  return o;
}

TEST(SimWorld, SameSeedGivesBitIdenticalRun) {
  const ScenarioOptions o = dynamic(50, 0.7);
  const auto a = run_bytes(o), b = run_bytes(o);
  ASSERT_GT(a.size(), 0u);
  EXPECT_EQ(a, b);
  ScenarioOptions other = o;
  other.seed = o.seed + 1;
  EXPECT_NE(run_bytes(other), a);
}

TEST(SimWorld, DifferentSeedsPickDifferentMovingSets) {
  ScenarioOptions o = dynamic(20, 0.5);
  std::set<std::set<int>> sets;
  for (int seed = 1; seed <= 5; ++seed) {
    o.seed = seed;
    sets.insert(moving_set(o));
  }
  EXPECT_EQ(sets.size(), 5u);
}

TEST(SimWorld, MovingCountAndSupersetAcrossDynamism) {
  std::set<int> previous;
  for (double d : {0.0, 5.0, 20.0, 35.0, 50.0, 65.0, 80.0, 100.0}) {
    const ScenarioOptions o = dynamic(d, 0.5);
    const std::set<int> s = moving_set(o);
    EXPECT_EQ(static_cast<long>(s.size()), std::lround(d / 100.0 * 72)) << d << " %";
    EXPECT_TRUE(std::includes(s.begin(), s.end(), previous.begin(), previous.end())) << d << " %";
    previous = s;
  }
}

TEST(SimWorld, DynamismAndSpeedKeepLayoutPathsAndStaticNoise) {
  // GIVEN two runs that differ only in dynamism and speed
  World a(dynamic(5, 0.1)), b(dynamic(80, 0.9));
  // THEN frame 0's layout is the same, and the robots drive the same paths
  EXPECT_EQ(a.landmark_positions(), b.landmark_positions());
  for (int k = 1; k < 150; ++k) {
    a.step();
    b.step();
    for (int r = 0; r < 3; ++r) {
      EXPECT_EQ(a.robot_pose(r).x, b.robot_pose(r).x);
      EXPECT_EQ(a.robot_pose(r).theta, b.robot_pose(r).theta);
      // the odometers too: their noise streams do not depend on the landmarks
      EXPECT_EQ(a.sensor_frame(r).odometer.x, b.sensor_frame(r).odometer.x);
    }
  }
  // AND a landmark static in both runs is observed with the same noise draws
  World c(dynamic(5, 0.1)), d(dynamic(80, 0.9));
  for (int k = 0; k < 40; ++k, c.step(), d.step()) {
    const SensorFrame& fc = c.sensor_frame(0);
    const SensorFrame& fd = d.sensor_frame(0);
    for (int i = 0; i < fc.num_obs; ++i) {
      const auto& zc = fc.obs[static_cast<std::size_t>(i)];
      if (d.is_moving(zc.landmark_id)) continue;
      const auto zd = std::find_if(fd.obs.begin(), fd.obs.begin() + fd.num_obs,
                                    [&](const Observation& z) { return z.landmark_id == zc.landmark_id; });
      ASSERT_NE(zd, fd.obs.begin() + fd.num_obs);
      EXPECT_EQ(zc.range_m, zd->range_m);
      EXPECT_EQ(zc.bearing_rad, zd->bearing_rad);
    }
  }
}

TEST(SimWorld, LandmarkSpeedReversalBordersAndStaticOnes) {
  for (double speed : {0.1, 0.5, 0.9}) {
    const ScenarioOptions o = dynamic(50, speed);
    World w(o);
    const double step = speed / o.rate_hz;
    const auto initial = w.landmark_positions();
    auto prev = initial;
    std::vector<Eigen::Vector2d> prev_disp(prev.size(), Eigen::Vector2d::Zero());
    std::vector<bool> prev_reflected(prev.size(), true);
    int reversals_seen = 0;
    for (int k = 1; k < o.frames; ++k) {
      w.step();
      const auto& p = w.landmark_positions();
      for (int i = 0; i < w.num_landmarks(); ++i) {
        const auto u = static_cast<std::size_t>(i);
        const Eigen::Vector2d disp = p[u] - prev[u];
        EXPECT_TRUE(p[u].x() >= -10.0 && p[u].x() <= 10.0 && p[u].y() >= -10.0 && p[u].y() <= 10.0);
        if (!w.is_moving(i)) {
          EXPECT_EQ(p[u], initial[u]) << "static landmark " << i << " moved";
          continue;
        }
        if (w.reflected_last_step(i)) {
          prev_reflected[u] = true;
          continue;
        }
        EXPECT_NEAR(disp.norm(), step, 1e-9) << "landmark " << i << " frame " << k;
        EXPECT_TRUE(disp.x() == 0.0 || disp.y() == 0.0) << "not along an axis";
        if (!prev_reflected[u]) {
          // The step into frame k follows frame k-1; it turns exactly when k-1 is a multiple of 20.
          const bool turn = (k - 1) > 0 && (k - 1) % o.reversal_period_frames == 0;
          const Eigen::Vector2d expected = turn ? Eigen::Vector2d(-prev_disp[u]) : prev_disp[u];
          EXPECT_NEAR((disp - expected).norm(), 0.0, 1e-9) << "landmark " << i << " frame " << k;
          reversals_seen += turn ? 1 : 0;
        }
        prev_disp[u] = disp;
        prev_reflected[u] = false;
      }
      prev = w.landmark_positions();
    }
    EXPECT_GT(reversals_seen, 0);
  }
}

TEST(SimWorld, BorderReflectionsHappenAtHighSpeed) {
  World w(dynamic(100, 0.9));
  for (int k = 1; k < 150; ++k) w.step();
  EXPECT_GT(w.counters().border_reflections, 0);  // grid landmarks sit 1.1 m from the border
}

TEST(SimWorld, RobotsFollowTheirSemicircles) {
  const ScenarioOptions o = test::paper();
  World w(o);
  for (int r = 0; r < 3; ++r) {
    const auto& path = o.robots[static_cast<std::size_t>(r)];
    // Frame 0: the known initial pose, and the odometer starts there exactly.
    const Pose2 T0 = path_pose(path, 0.0);
    EXPECT_EQ(w.robot_pose(r).x, T0.x);
    EXPECT_EQ(w.sensor_frame(r).odometer.x, T0.x);
    EXPECT_EQ(w.sensor_frame(r).odometer.theta, T0.theta);
    EXPECT_NEAR(std::hypot(T0.x - path.center_x_m, T0.y - path.center_y_m), path.radius_m, 1e-12);
  }
  std::vector<Pose2> prev{w.robot_pose(0), w.robot_pose(1), w.robot_pose(2)};
  for (int k = 1; k < o.frames; ++k) {
    w.step();
    for (int r = 0; r < 3; ++r) {
      const double moved = std::hypot(w.robot_pose(r).x - prev[static_cast<std::size_t>(r)].x,
                                      w.robot_pose(r).y - prev[static_cast<std::size_t>(r)].y);
      EXPECT_LT(moved, o.sensor.fov_diameter_m);  // paper eq 14 and after
      prev[static_cast<std::size_t>(r)] = w.robot_pose(r);
    }
  }
  // Last frame: each robot is at the far end of its semicircle (the default speeds
  // are pi * radius / 14.9 s), heading opposite to its start heading.
  for (int r = 0; r < 3; ++r) {
    const auto& path = o.robots[static_cast<std::size_t>(r)];
    const double end = deg2rad(path.start_angle_deg) + kPi;
    EXPECT_NEAR(w.robot_pose(r).x, path.center_x_m + path.radius_m * std::cos(end), 1e-3);
    EXPECT_NEAR(w.robot_pose(r).y, path.center_y_m + path.radius_m * std::sin(end), 1e-3);
  }
}

TEST(SimWorld, FieldOfViewRespectedAndEveryLandmarkInViewSeen) {
  ScenarioOptions o = dynamic(50, 0.5);
  World w(o);
  const double r_max = o.sensor.max_range_m();
  long checked = 0;
  for (int k = 0; k < o.frames; ++k) {
    if (k > 0) w.step();
    for (int r = 0; r < w.num_robots(); ++r) {
      const SensorFrame& f = w.sensor_frame(r);
      EXPECT_EQ(f.frame, k);
      EXPECT_EQ(f.robot_id, o.robots[static_cast<std::size_t>(r)].id);
      std::set<int> seen;
      for (int i = 0; i < f.num_obs; ++i) {
        const Observation& z = f.obs[static_cast<std::size_t>(i)];
        const double d = (w.landmark_positions()[static_cast<std::size_t>(z.landmark_id)] -
                          w.robot_pose(r).translation()).norm();
        EXPECT_LE(d, r_max) << "observed beyond D/2";
        EXPECT_GT(z.range_m, 0.0);
        EXPECT_TRUE(z.bearing_rad >= -kPi && z.bearing_rad < kPi);
        if (i > 0) {
          EXPECT_LT(f.obs[static_cast<std::size_t>(i - 1)].landmark_id, z.landmark_id);
        }
        seen.insert(z.landmark_id);
      }
      for (int id = 0; id < w.num_landmarks(); ++id) {
        const double d =
            (w.landmark_positions()[static_cast<std::size_t>(id)] - w.robot_pose(r).translation()).norm();
        const bool in_view = d <= r_max && d >= o.sensor.min_range_m;
        EXPECT_EQ(seen.count(id) == 1, in_view) << "landmark " << id << " at " << d << " m, frame " << k;
        ++checked;
      }
      EXPECT_GE(f.num_obs, 3) << "too few landmarks in view for the default scenario";
    }
  }
  EXPECT_EQ(checked, 150L * 3 * 72);
}

TEST(SimWorld, NoiseFreeObservationsMatchTheTruePoseAtFrameZero) {
  ScenarioOptions o = test::paper();
  o.sensor.range_sigma_m = 0.0;
  o.sensor.bearing_sigma_deg = 0.0;
  World w(o);
  for (int r = 0; r < 3; ++r) {
    const SensorFrame& f = w.sensor_frame(r);
    ASSERT_GT(f.num_obs, 0);
    for (int i = 0; i < f.num_obs; ++i) {
      const Observation& z = f.obs[static_cast<std::size_t>(i)];
      const Observation t = true_observation(path_pose(o.robots[static_cast<std::size_t>(r)], 0.0),
                                             w.landmark_positions()[static_cast<std::size_t>(z.landmark_id)],
                                             z.landmark_id);
      EXPECT_NEAR(z.range_m, t.range_m, 1e-12);
      EXPECT_NEAR(z.bearing_rad, t.bearing_rad, 1e-12);
    }
  }
}

// The cap is configuration (scenario.sensor.max_observations): 10 here, and a
// frame of the same world with room for all 72 holds them all.
TEST(SimWorld, TheObservationCapIsTheConfiguredOne) {
  ScenarioOptions o = test::paper();
  o.sensor.fov_diameter_m = 60.0;  // every landmark in view
  o.sensor.max_observations = 10;
  World w(o);
  EXPECT_EQ(w.sensor_frame(0).num_obs, 10);
  EXPECT_EQ(w.counters().truncated_obs, 3 * (72 - 10));
  o.sensor.max_observations = 100;
  World all(o);
  EXPECT_EQ(all.sensor_frame(0).num_obs, 72);
  EXPECT_EQ(all.counters().truncated_obs, 0);
  EXPECT_EQ(to_message(all.sensor_frame(0), 0).num_obs, 72);
}

TEST(SimWorld, MoreThan64InViewKeepsTheNearest) {
  ScenarioOptions o = test::paper();
  o.sensor.fov_diameter_m = 60.0;  // every landmark in view
  World w(o);
  const SensorFrame& f = w.sensor_frame(0);
  EXPECT_EQ(f.num_obs, 64);
  EXPECT_EQ(w.counters().truncated_obs, 3 * (72 - 64));
  EXPECT_EQ(w.counters().frames_truncated, 3);
  double max_kept = 0.0;
  std::set<int> kept;
  for (int i = 0; i < f.num_obs; ++i) {
    const auto id = f.obs[static_cast<std::size_t>(i)].landmark_id;
    kept.insert(id);
    max_kept = std::max(max_kept, (w.landmark_positions()[static_cast<std::size_t>(id)] -
                                   w.robot_pose(0).translation()).norm());
  }
  for (int id = 0; id < 72; ++id) {
    if (kept.count(id)) continue;
    EXPECT_GE((w.landmark_positions()[static_cast<std::size_t>(id)] - w.robot_pose(0).translation()).norm(),
              max_kept);
  }
}

TEST(SimWorld, GroundTruthMessage) {
  World w(dynamic(50, 0.5));
  w.step();
  const auto m = to_message(w, 1234);
  EXPECT_EQ(m.utime, 1234);
  EXPECT_EQ(m.frame, 1);
  EXPECT_EQ(m.num_robots, 3);
  EXPECT_EQ(m.num_landmarks, 72);
  int moving = 0;
  for (int i = 0; i < 72; ++i) {
    EXPECT_EQ(m.landmarks[i].id, i);
    EXPECT_EQ(m.landmarks[i].x, w.landmark_positions()[static_cast<std::size_t>(i)].x());
    moving += m.landmarks[i].moving ? 1 : 0;
  }
  EXPECT_EQ(moving, 36);
  for (int r = 0; r < 3; ++r) {
    EXPECT_EQ(m.robot_ids[r], r + 1);
    EXPECT_EQ(m.robots[r].theta, w.robot_pose(r).theta);
  }
  const auto s = to_message(w.sensor_frame(2), 99);
  EXPECT_EQ(s.robot_id, 3);
  EXPECT_EQ(s.frame, 1);
  EXPECT_EQ(s.num_obs, w.sensor_frame(2).num_obs);
  EXPECT_EQ(s.odom_var_rot_per_m, 3.0e-4);
}

// LCM's decoder, kept out of line: inlined into a test body at -O3, g++ 12 warns
// that the generated code's fingerprint may be read uninitialised (it is not).
[[gnu::noinline]] int decode(const std::vector<std::uint8_t>& buf, ground_truth_t* m) {
  return m->decode(buf.data(), 0, static_cast<int>(buf.size()));
}

// The large world (config/large.yaml): 16 robots and 1,024 landmarks fit
// one GROUND_TRUTH, which survives LCM's encoding whole; filling it again in place
// keeps the arrays sized to the world.
TEST(SimWorld, GroundTruthOfTheLargeWorldRoundTrips) {
  const ScenarioOptions o = load_scenario(std::string(ELASLAM_SOURCE_DIR) + "/config/large.yaml");
  ASSERT_EQ(o.robots.size(), 16u);
  ASSERT_EQ(o.landmarks.count, 1024);
  World w(o);
  for (int k = 0; k < 3; ++k) w.step();
  ground_truth_t m = to_message(w, 77);
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  ASSERT_EQ(m.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  ground_truth_t d;
  ASSERT_EQ(decode(buf, &d), static_cast<int>(buf.size()));
  ASSERT_EQ(d.num_robots, 16);
  ASSERT_EQ(d.num_landmarks, 1024);
  for (int r = 0; r < 16; ++r) {
    EXPECT_EQ(d.robot_ids[static_cast<std::size_t>(r)], r + 1);
    EXPECT_EQ(d.robots[static_cast<std::size_t>(r)].x, w.robot_pose(r).x);
  }
  int moving = 0;
  for (int i = 0; i < 1024; ++i) {
    const auto& l = d.landmarks[static_cast<std::size_t>(i)];
    EXPECT_EQ(l.id, i);
    EXPECT_EQ(l.y, w.landmark_positions()[static_cast<std::size_t>(i)].y());
    moving += l.moving ? 1 : 0;
  }
  EXPECT_EQ(moving, 205);  // round(20 % of 1,024)
  w.step();
  to_message(w, 78, &d);
  EXPECT_EQ(d.landmarks.size(), 1024u);
  EXPECT_EQ(d.frame, 4);
}

TEST(SimWorld, InvalidOptionsAreAProgrammingError) {
  ScenarioOptions o = test::paper();
  o.reversal_period_frames = 0;
  EXPECT_THROW(World w(o), std::invalid_argument);
}

}  // namespace
}  // namespace elaslam::sim

// SPDX-License-Identifier: Apache-2.0
// Robot paths, landmark steps, odometry noise, random streams.
#include <cmath>
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "elaslam/simulator/motion.hpp"
#include "elaslam/simulator/random.hpp"
#include "elaslam/simulator/world.hpp"
#include "sim_test_util.hpp"

namespace elaslam::sim {
namespace {

// First output of Rng(1, stream::kLayout): pins splitmix64 seeding + mt19937_64.
constexpr std::uint64_t kGoldenFirstBits = 15506592668586656617ULL;

TEST(SimMotion, PathStartsOnTheCircleWithTangentHeadingAndStopsAtTheEnd) {
  RobotPathOptions p;
  p.center_x_m = 1.0;
  p.center_y_m = -2.0;
  p.radius_m = 4.0;
  p.start_angle_deg = 90.0;
  p.speed_mps = 2.0;
  for (bool ccw : {true, false}) {
    p.ccw = ccw;
    const Pose2 T0 = path_pose(p, 0.0);
    EXPECT_NEAR(T0.x, 1.0, 1e-12);
    EXPECT_NEAR(T0.y, 2.0, 1e-12);
    EXPECT_NEAR(wrap_angle(T0.theta - (ccw ? kPi : 0.0)), 0.0, 1e-12);  // ccw: along -x, cw: along +x
    // Heading equals the direction of the finite-difference velocity.
    const Pose2 T1 = path_pose(p, 1e-4);
    EXPECT_NEAR(wrap_angle(std::atan2(T1.y - T0.y, T1.x - T0.x) - T0.theta), 0.0, 1e-4);
    // After pi * r / v seconds the robot is at the far end, and stays there.
    const double t_end = kPi * p.radius_m / p.speed_mps;
    const Pose2 Te = path_pose(p, t_end), Tl = path_pose(p, 10.0 * t_end);
    EXPECT_NEAR(Te.x, 1.0, 1e-9);
    EXPECT_NEAR(Te.y, -6.0, 1e-9);
    EXPECT_EQ(Tl.x, Te.x);
    EXPECT_EQ(Tl.y, Te.y);
  }
}

TEST(SimMotion, LandmarkReflectsAtTheBorder) {
  const WorldBounds w;
  Eigen::Vector2d p(9.95, 0.0), d(1.0, 0.0);
  EXPECT_TRUE(advance_landmark(&p, &d, 0.1, w));
  EXPECT_NEAR(p.x(), 9.95, 1e-12);  // 10.05 mirrored about x = 10
  EXPECT_EQ(d, Eigen::Vector2d(-1.0, 0.0));
  EXPECT_FALSE(advance_landmark(&p, &d, 0.1, w));
  EXPECT_NEAR(p.x(), 9.85, 1e-12);
  Eigen::Vector2d q(0.0, -9.99), e(0.0, -1.0);
  EXPECT_TRUE(advance_landmark(&q, &e, 0.05, w));
  EXPECT_NEAR(q.y(), -9.96, 1e-12);
  EXPECT_EQ(e, Eigen::Vector2d(0.0, 1.0));
}

TEST(SimMotion, SpinTurnsInPlaceThenRotatesTheRestOfThePath) {
  // GIVEN a semicircle and the same with a 115 deg turn in place from 2 s to 5 s
  RobotPathOptions plain;
  plain.center_x_m = 1.0;
  plain.center_y_m = -2.0;
  plain.radius_m = 4.0;
  plain.start_angle_deg = -90.0;
  plain.speed_mps = 1.0;
  RobotPathOptions spun = plain;
  spun.spin = {2.0, 3.0, 115.0};
  const double turn = deg2rad(115.0);
  // THEN before the turn the paths are the same, bit for bit
  for (double t : {-1.0, 0.0, 1.0, 2.0}) {
    EXPECT_EQ(path_pose(spun, t).x, path_pose(plain, t).x) << t;
    EXPECT_EQ(path_pose(spun, t).theta, path_pose(plain, t).theta) << t;
  }
  // AND during it the robot stands at P and turns at a constant rate
  const Pose2 P = path_pose(plain, 2.0);
  for (double t : {2.5, 3.0, 4.9}) {
    const Pose2 T = path_pose(spun, t);
    EXPECT_EQ(T.x, P.x);
    EXPECT_EQ(T.y, P.y);
    EXPECT_NEAR(wrap_angle(T.theta - P.theta - turn * (t - 2.0) / 3.0), 0.0, 1e-12) << t;
  }
  EXPECT_DOUBLE_EQ(drive_time(spun, 4.0), 2.0);
  EXPECT_DOUBLE_EQ(drive_time(spun, 7.0), 4.0);
  // AND afterwards it drives the rest of the semicircle rotated by the turn about P:
  // the same distance from P, the bearing from P and the heading turned by 115 deg
  for (double t : {5.0, 6.0, 8.0, 20.0}) {
    const Pose2 T = path_pose(spun, t), U = path_pose(plain, t - 3.0);
    const Eigen::Vector2d d_T = T.translation() - P.translation(), d_U = U.translation() - P.translation();
    EXPECT_NEAR(d_T.norm(), d_U.norm(), 1e-12) << t;
    if (d_U.norm() > 1e-9) {
      EXPECT_NEAR(wrap_angle(std::atan2(d_T.y(), d_T.x()) - std::atan2(d_U.y(), d_U.x()) - turn), 0.0, 1e-12) << t;
    }
    EXPECT_NEAR(wrap_angle(T.theta - U.theta - turn), 0.0, 1e-12) << t;
  }
  // AND it drives on at the same speed, heading along its motion
  const Pose2 A = path_pose(spun, 6.0), B = path_pose(spun, 6.0 + 1e-4);
  EXPECT_NEAR(std::hypot(B.x - A.x, B.y - A.y) / 1e-4, 1.0, 1e-6);
  EXPECT_NEAR(wrap_angle(std::atan2(B.y - A.y, B.x - A.x) - A.theta), 0.0, 1e-4);
}

TEST(SimMotion, ReportedIncrementInvertsTheOdometerConvention) {
  // The convention (OdometerError): true = (s_v dx_r, s_v dy_r, s_w dtheta_r + b dt).
  const OdometerError e{0.9, 0.95, 0.02};
  const double dt = 0.1;
  const Pose2 u{0.12, -0.01, 0.05};
  const Pose2 r = reported_increment(u, e, dt);
  EXPECT_DOUBLE_EQ(r.x, 0.12 / 0.95);
  EXPECT_DOUBLE_EQ(r.y, -0.01 / 0.95);
  EXPECT_DOUBLE_EQ(r.theta, (0.05 - 0.002) / 0.9);  // 0.05333... rad
  const Pose2 back = true_increment(r, e, dt);
  EXPECT_NEAR(back.x, u.x, 1e-15);
  EXPECT_NEAR(back.y, u.y, 1e-15);
  EXPECT_NEAR(back.theta, u.theta, 1e-15);
  // A standing robot's odometer reports the bias, turned back: -b dt / s_w.
  EXPECT_DOUBLE_EQ(reported_increment(Pose2{}, e, dt).theta, -0.002 / 0.9);
  // No error: the increment itself, bit for bit.
  const Pose2 same = reported_increment(u, OdometerError{}, dt);
  EXPECT_EQ(same.x, u.x);
  EXPECT_EQ(same.y, u.y);
  EXPECT_EQ(same.theta, u.theta);
}

TEST(SimMotion, LandmarksBounceOffTheEmptyRegion) {
  const WorldBounds w;
  EmptyRegion e;
  e.enabled = true;
  e.x_min_m = 0.0, e.x_max_m = 2.0, e.y_min_m = 0.0, e.y_max_m = 2.0;
  // Into the left side: 0.05 m inside, mirrored to 0.05 m outside, heading back.
  Eigen::Vector2d p(-0.05, 1.0), d(1.0, 0.0);
  EXPECT_TRUE(advance_landmark(&p, &d, 0.1, w, e));
  EXPECT_NEAR(p.x(), -0.05, 1e-12);
  EXPECT_EQ(d, Eigen::Vector2d(-1.0, 0.0));
  // Down into the top side.
  Eigen::Vector2d q(1.0, 2.03), f(0.0, -1.0);
  EXPECT_TRUE(advance_landmark(&q, &f, 0.05, w, e));
  EXPECT_NEAR(q.y(), 2.02, 1e-12);
  EXPECT_EQ(f, Eigen::Vector2d(0.0, 1.0));
  // Passing beside it, or sitting on a side, is not a bounce.
  Eigen::Vector2d s(-0.5, 2.0), g(1.0, 0.0);
  EXPECT_FALSE(advance_landmark(&s, &g, 0.1, w, e));
  EXPECT_NEAR(s.x(), -0.4, 1e-12);
  // A gap to the world's border narrower than a step: it stays in the gap.
  EmptyRegion wall = e;
  wall.x_min_m = -9.97, wall.x_max_m = 0.0;
  Eigen::Vector2d a(-9.99, 1.0), h(-1.0, 0.0);
  for (int i = 0; i < 20; ++i) {
    advance_landmark(&a, &h, 0.1, w, wall);
    EXPECT_TRUE(a.x() >= -10.0 && a.x() <= -9.97) << a.x();
  }
}

TEST(SimMotion, NoisyIncrementHasTheConfiguredVariance) {
  OdometryOptions o;  // defaults: 4e-4 m^2/m, 1e-3 rad^2/rad, 3e-4 rad^2/m
  const Pose2 u{0.12, 0.01, 0.05};
  const Eigen::Vector3d var = increment_variances(u, o);
  const double d = std::hypot(u.x, u.y);
  EXPECT_DOUBLE_EQ(var.x(), 4e-4 * d);
  EXPECT_DOUBLE_EQ(var.z(), 1e-3 * 0.05 + 3e-4 * d);
  Rng rng(11, stream::kOdometryNoise + 1);
  test::Moments ex, ey, et;
  const int n = 40000;
  for (int i = 0; i < n; ++i) {
    const Pose2 v = noisy_increment(u, o, &rng);
    ex.add(v.x - u.x);
    ey.add(v.y - u.y);
    et.add(v.theta - u.theta);
  }
  const double rel = 4.5 * std::sqrt(2.0 / n);
  EXPECT_NEAR(ex.var() / var.x(), 1.0, rel);
  EXPECT_NEAR(ey.var() / var.y(), 1.0, rel);
  EXPECT_NEAR(et.var() / var.z(), 1.0, rel);
  EXPECT_NEAR(ex.mean, 0.0, 4.5 * std::sqrt(var.x() / n));
  EXPECT_NEAR(et.mean, 0.0, 4.5 * std::sqrt(var.z() / n));
  // A robot standing still gets no noise.
  const Pose2 still = noisy_increment(Pose2{}, o, &rng);
  EXPECT_EQ(still.x, 0.0);
  EXPECT_EQ(still.theta, 0.0);
}

TEST(SimMotion, OdometerIncrementsErrorsOverWholeRuns) {
  // GIVEN many runs of the default scenario WHEN comparing consecutive odometer
  // readings with the true motion THEN the normalised errors have unit variance.
  test::Moments nx, ny, nt;
  for (int seed = 1; seed <= 30; ++seed) {
    ScenarioOptions o = test::paper();
    o.seed = seed;
    World w(o);
    test::for_each_increment(w, o.frames, [&](int, int, const Pose2& u_true, const Pose2& u_odo) {
      const Eigen::Vector3d var = increment_variances(u_true, o.odometry);
      nx.add((u_odo.x - u_true.x) / std::sqrt(var.x()));
      ny.add((u_odo.y - u_true.y) / std::sqrt(var.y()));
      nt.add(wrap_angle(u_odo.theta - u_true.theta) / std::sqrt(var.z()));
    });
  }
  const double rel = 4.5 * std::sqrt(2.0 / static_cast<double>(nx.n));
  EXPECT_NEAR(nx.var(), 1.0, rel);
  EXPECT_NEAR(ny.var(), 1.0, rel);
  EXPECT_NEAR(nt.var(), 1.0, rel);
  EXPECT_NEAR(nx.mean, 0.0, 4.5 / std::sqrt(static_cast<double>(nx.n)));
}

TEST(SimRandom, StreamsAreFixedAndIndependent) {
  // Golden values: a change here changes every recorded experiment.
  Rng a(1, stream::kLayout);
  EXPECT_EQ(a.bits(), kGoldenFirstBits);
  Rng b(1, stream::kLayout), c(1, stream::kMovingSet), d(2, stream::kLayout);
  const std::uint64_t vb = b.bits();
  EXPECT_NE(vb, c.bits());
  EXPECT_NE(vb, d.bits());
}

TEST(SimRandom, UniformAndNormalMoments) {
  Rng rng(5, 42);
  test::Moments u, g;
  const int n = 100000;
  for (int i = 0; i < n; ++i) {
    const double x = rng.uniform();
    ASSERT_TRUE(x >= 0.0 && x < 1.0);
    u.add(x);
    g.add(rng.normal());
  }
  EXPECT_NEAR(u.mean, 0.5, 4.5 * std::sqrt(1.0 / 12.0 / n));
  EXPECT_NEAR(u.var(), 1.0 / 12.0, 0.002);
  EXPECT_NEAR(g.mean, 0.0, 4.5 / std::sqrt(n));
  EXPECT_NEAR(g.var(), 1.0, 4.5 * std::sqrt(2.0 / n));
  std::vector<int> counts(4, 0);
  for (int i = 0; i < 40000; ++i) ++counts[static_cast<std::size_t>(rng.below(4))];
  for (int c : counts) EXPECT_NEAR(c, 10000, 4.5 * std::sqrt(40000 * 0.25 * 0.75));
}

}  // namespace
}  // namespace elaslam::sim

// SPDX-License-Identifier: Apache-2.0
// Motion and observation models: analytic Jacobians against central differences at
// random and at singular points, and the odometry noise model against hand-computed
// numbers.
#include "elaslam/robot_node/models.hpp"

#include <cmath>
#include <random>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <gtest/gtest.h>

#include "jacobian_check.hpp"

namespace elaslam {
namespace {

using test::check_jacobian;
using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Mat23 = Eigen::Matrix<double, 2, 3>;

constexpr int kRandomPoints = 200;
constexpr unsigned kThetaOutput = 1u << 2;    // output 2 of motion() is an angle
constexpr unsigned kBearingOutput = 1u << 1;  // output 1 of observe() is an angle

Pose2 to_pose(const Vec3& v) { return {v(0), v(1), v(2)}; }
Vec3 to_vec(const Pose2& p) { return {p.x, p.y, p.theta}; }
Vec2 to_vec(const RangeBearing& z) { return {z.range, z.bearing}; }
RangeBearing to_rb(const Vec2& v) { return {v(0), v(1)}; }

// Random test points: poses anywhere in a 100 m square with any heading, odometry
// increments of a few metres, landmarks 0.5 to 30 m from the robot.
struct Sampler {
  std::mt19937_64 rng{20240611};
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }
  Pose2 pose() { return {uniform(-50, 50), uniform(-50, 50), uniform(-kPi, kPi)}; }
  Pose2 increment() { return {uniform(-2, 2), uniform(-2, 2), uniform(-1, 1)}; }
  Vec2 landmark_near(const Pose2& p) {
    const double r = uniform(0.5, 30), a = uniform(-kPi, kPi);
    return {p.x + r * std::cos(a), p.y + r * std::sin(a)};
  }
  RangeBearing observation() { return {uniform(0.2, 30), uniform(-kPi, kPi)}; }
};

// ---- the checked functions, one per Jacobian ---------------------------------------

// The analytic Jacobian `analytic` of f at x against central differences, named in
// the failure.
template <class F, class X, class J>
void expect_jacobian(const char* name, const F& f, const X& x, const J& analytic, unsigned angle_outputs = 0u) {
  const auto c = check_jacobian(f, x, analytic, angle_outputs);
  EXPECT_TRUE(c.ok) << name << ": " << c.message;
}

void expect_motion_jacobians(const Pose2& pose, const Pose2& u) {
  Eigen::Matrix3d F_x, F_u;
  motion(pose, u, &F_x, &F_u);
  expect_jacobian("F_x", [&](const Vec3& r) { return to_vec(motion(to_pose(r), u)); }, to_vec(pose), F_x, kThetaOutput);
  expect_jacobian("F_u", [&](const Vec3& v) { return to_vec(motion(pose, to_pose(v))); }, to_vec(u), F_u, kThetaOutput);
}

void expect_observe_jacobians(const Pose2& pose, const Vec2& l) {
  Mat23 H_x;
  Eigen::Matrix2d H_l;
  observe(pose, l, &H_x, &H_l);
  expect_jacobian("H_x", [&](const Vec3& r) { return to_vec(observe(to_pose(r), l)); }, to_vec(pose), H_x,
                  kBearingOutput);
  expect_jacobian("H_l", [&](const Vec2& p) { return to_vec(observe(pose, p)); }, l, H_l, kBearingOutput);
}

void expect_inverse_observe_jacobians(const Pose2& pose, const RangeBearing& z) {
  Mat23 G_x;
  Eigen::Matrix2d G_z;
  inverse_observe(pose, z, &G_x, &G_z);
  expect_jacobian("G_x", [&](const Vec3& r) { return inverse_observe(to_pose(r), z); }, to_vec(pose), G_x);
  expect_jacobian("G_z", [&](const Vec2& y) { return inverse_observe(pose, to_rb(y)); }, to_vec(z), G_z);
}

// ---- the checker itself ---------------------------------------------------------------

TEST(EkfJacobianChecker, ReportsAWrongJacobian) {
  // GIVEN the correct F_u at a heading where every entry is far from zero
  const Pose2 pose{1.0, 2.0, 0.3}, u{0.5, -0.2, 0.1};
  Eigen::Matrix3d F_x, F_u;
  motion(pose, u, &F_x, &F_u);
  const auto f_u = [&](const Vec3& v) { return to_vec(motion(pose, to_pose(v))); };
  ASSERT_TRUE(check_jacobian(f_u, to_vec(u), F_u, kThetaOutput).ok);
  // WHEN one sign is flipped THEN the checker fails and says by how much
  Eigen::Matrix3d wrong = F_u;
  wrong(0, 1) = -wrong(0, 1);
  const auto c = check_jacobian(f_u, to_vec(u), wrong, kThetaOutput);
  EXPECT_FALSE(c.ok);
  EXPECT_GT(c.max_error, 0.1);
  EXPECT_NE(c.message.find("mismatch"), std::string::npos);
}

TEST(EkfJacobianChecker, ReportsNaNAsFailure) {
  const auto f = [](const Vec2& v) { return Vec2(v(0) * v(1), v(0)); };
  Eigen::Matrix2d J;
  J << 2.0, 1.0, 1.0, 0.0;  // correct at (1, 2)
  EXPECT_TRUE(check_jacobian(f, Vec2(1.0, 2.0), J).ok);
  J(1, 1) = std::nan("");
  EXPECT_FALSE(check_jacobian(f, Vec2(1.0, 2.0), J).ok);
}

TEST(EkfJacobianChecker, WrapsAngleOutputs) {
  // An output sitting on the +-pi seam: without wrapping, the difference is ~2 pi.
  const auto f = [](const Vec2& v) { return Vec2(v(0), wrap_angle(kPi + v(1))); };
  Eigen::Matrix2d J = Eigen::Matrix2d::Identity();
  EXPECT_TRUE(check_jacobian(f, Vec2(0.0, 0.0), J, 1u << 1).ok);
  EXPECT_FALSE(check_jacobian(f, Vec2(0.0, 0.0), J, 0u).ok);
}

// ---- motion (eqs 3, 6) -----------------------------------------------------------------

TEST(EkfModels, MotionJacobiansAtRandomPoints) {
  Sampler s;
  for (int k = 0; k < kRandomPoints; ++k) expect_motion_jacobians(s.pose(), s.increment());
}

TEST(EkfModels, MotionJacobiansAcrossThePiSeam) {
  // Heading just below +pi, turning left: the new heading wraps to about -pi.
  expect_motion_jacobians({1.0, -2.0, kPi - 1e-9}, {0.3, 0.1, 1e-7});
  expect_motion_jacobians({1.0, -2.0, -kPi + 1e-9}, {0.3, 0.1, -1e-7});
  expect_motion_jacobians({0.0, 0.0, kPi - 1e-9}, {0.0, 0.0, 0.0});
}

TEST(EkfModels, MotionIsCompose) {
  const Pose2 pose{1.0, 2.0, kPi / 2}, u{1.0, 0.5, kPi};
  const Pose2 next = motion(pose, u);
  EXPECT_NEAR(next.x, 0.5, 1e-12);
  EXPECT_NEAR(next.y, 3.0, 1e-12);
  EXPECT_NEAR(next.theta, -kPi / 2, 1e-12);  // wrapped into [-pi, pi)
}

// ---- the odometer's calibration ------------------------------------------------------

Vec3 to_vec(const OdometryCalibration& c) { return {c.turn_scale, c.speed_scale, c.turn_bias}; }
OdometryCalibration to_calibration(const Vec3& v) { return {v(0), v(1), v(2)}; }

// du/dc and du/du_r of calibrated_increment, and the prediction's F_c = F_u du/dc:
// the pose after the step, motion(R, u(c)), differentiated by c directly.
void expect_calibration_jacobians(const Pose2& pose, const Pose2& u_r, const OdometryCalibration& c, double dt) {
  Eigen::Matrix3d J_c, J_r, F_x, F_u;
  const Pose2 u = calibrated_increment(u_r, c, dt, &J_c, &J_r);
  motion(pose, u, &F_x, &F_u);
  const Eigen::Matrix3d F_c = F_u * J_c;
  const auto u_of_c = [&](const Vec3& v) { return to_vec(calibrated_increment(u_r, to_calibration(v), dt)); };
  const auto u_of_r = [&](const Vec3& v) { return to_vec(calibrated_increment(to_pose(v), c, dt)); };
  const auto pose_of_c = [&](const Vec3& v) {
    return to_vec(motion(pose, calibrated_increment(u_r, to_calibration(v), dt)));
  };
  const auto cc = check_jacobian(u_of_c, to_vec(c), J_c);
  const auto cr = check_jacobian(u_of_r, to_vec(u_r), J_r);
  const auto cf = check_jacobian(pose_of_c, to_vec(c), F_c, kThetaOutput);
  EXPECT_TRUE(cc.ok) << "du/dc: " << cc.message;
  EXPECT_TRUE(cr.ok) << "du/du_r: " << cr.message;
  EXPECT_TRUE(cf.ok) << "F_c: " << cf.message;
}

TEST(EkfModels, CalibrationJacobiansAtRandomPoints) {
  Sampler s;
  for (int k = 0; k < kRandomPoints; ++k) {
    const OdometryCalibration c{s.uniform(0.7, 1.3), s.uniform(0.7, 1.3), s.uniform(-0.2, 0.2)};
    expect_calibration_jacobians(s.pose(), s.increment(), c, s.uniform(0.0, 2.0));
  }
  // Across the pi seam, and a standing robot (only the bias moves it).
  expect_calibration_jacobians({1.0, -2.0, kPi - 1e-9}, {0.3, 0.1, 1e-7}, {0.9, 0.95, 0.01}, 0.1);
  expect_calibration_jacobians({0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.9, 0.95, 0.01}, 0.1);
}

TEST(EkfModels, CalibratedIncrementIsTheConvention) {
  // true = (s_v dx_r, s_v dy_r, s_w dtheta_r + b dt), as the simulator produces it.
  const Pose2 u = calibrated_increment({0.2, -0.05, 0.1}, {0.9, 0.95, 0.02}, 0.1);
  EXPECT_DOUBLE_EQ(u.x, 0.95 * 0.2);
  EXPECT_DOUBLE_EQ(u.y, 0.95 * -0.05);
  EXPECT_DOUBLE_EQ(u.theta, 0.9 * 0.1 + 0.02 * 0.1);
  // The identity leaves the increment's bits as they are.
  const Pose2 r{0.123456789, -0.987654321, 0.314159};
  const Pose2 same = calibrated_increment(r, OdometryCalibration{}, 0.1);
  EXPECT_EQ(same.x, r.x);
  EXPECT_EQ(same.y, r.y);
  EXPECT_EQ(same.theta, r.theta);
}

TEST(EkfJacobianChecker, ReportsAWrongCalibrationJacobian) {
  // du/dc with the bias column's dt left out is caught.
  const Pose2 u_r{0.3, 0.02, 0.1};
  const OdometryCalibration c{0.9, 0.95, 0.01};
  Eigen::Matrix3d J_c;
  calibrated_increment(u_r, c, 0.5, &J_c);
  J_c(2, 2) = 1.0;
  const auto u_of_c = [&](const Vec3& v) { return to_vec(calibrated_increment(u_r, to_calibration(v), 0.5)); };
  EXPECT_FALSE(check_jacobian(u_of_c, to_vec(c), J_c).ok);
}

// ---- observation (eqs 7, 13) -----------------------------------------------------------

TEST(EkfModels, ObserveJacobiansAtRandomPoints) {
  Sampler s;
  for (int k = 0; k < kRandomPoints; ++k) {
    const Pose2 pose = s.pose();
    expect_observe_jacobians(pose, s.landmark_near(pose));
  }
}

TEST(EkfModels, ObserveJacobiansWithTheLandmarkBehind) {
  // Landmark straight behind: bearing at +-pi, perturbations flip its sign.
  expect_observe_jacobians({0.0, 0.0, 0.0}, {-5.0, 0.0});
  expect_observe_jacobians({0.0, 0.0, 0.0}, {-5.0, 1e-9});
  expect_observe_jacobians({0.0, 0.0, 0.0}, {-5.0, -1e-9});
  expect_observe_jacobians({3.0, 4.0, kPi - 1e-9}, {8.0, 4.0});
}

TEST(EkfModels, ObserveValues) {
  const RangeBearing z = observe({1.0, 1.0, kPi / 2}, {1.0, 3.0});
  EXPECT_NEAR(z.range, 2.0, 1e-12);
  EXPECT_NEAR(z.bearing, 0.0, 1e-12);
  const RangeBearing behind = observe({0.0, 0.0, 0.0}, {-2.0, 0.0});
  EXPECT_NEAR(std::abs(behind.bearing), kPi, 1e-12);
  EXPECT_GE(behind.bearing, -kPi);
  EXPECT_LT(behind.bearing, kPi);
}

TEST(EkfModels, ObserveAtTheRobotCentreIsFinite) {
  Mat23 H_x;
  Eigen::Matrix2d H_l;
  // Exactly at the centre: documented singular point, range 0 and zero Jacobians.
  const RangeBearing z0 = observe({2.0, 3.0, 0.4}, {2.0, 3.0}, &H_x, &H_l);
  EXPECT_EQ(z0.range, 0.0);
  EXPECT_TRUE(std::isfinite(z0.bearing));
  EXPECT_TRUE(H_x.isZero(0.0));
  EXPECT_TRUE(H_l.isZero(0.0));
  // Very close: large but finite values, no NaN anywhere.
  for (const double d : {1e-13, 1e-11, 1e-8, 1e-5}) {
    const RangeBearing z = observe({2.0, 3.0, 0.4}, {2.0 + d, 3.0 - d}, &H_x, &H_l);
    EXPECT_TRUE(std::isfinite(z.range) && std::isfinite(z.bearing)) << "d = " << d;
    EXPECT_TRUE(H_x.allFinite() && H_l.allFinite()) << "d = " << d;
  }
}

// ---- inverse observation (eq 15) -------------------------------------------------------

TEST(EkfModels, InverseObserveJacobiansAtRandomPoints) {
  Sampler s;
  for (int k = 0; k < kRandomPoints; ++k) expect_inverse_observe_jacobians(s.pose(), s.observation());
}

TEST(EkfModels, InverseObserveJacobiansAcrossThePiSeam) {
  expect_inverse_observe_jacobians({0.0, 0.0, kPi - 1e-9}, {5.0, kPi - 1e-9});
  expect_inverse_observe_jacobians({0.0, 0.0, 0.0}, {5.0, -kPi});
  expect_inverse_observe_jacobians({0.0, 0.0, 0.0}, {1e-9, 0.3});  // near-zero range
}

TEST(EkfModels, InverseObserveInvertsObserve) {
  Sampler s;
  for (int k = 0; k < kRandomPoints; ++k) {
    const Pose2 pose = s.pose();
    const Vec2 l = s.landmark_near(pose);
    EXPECT_LT((inverse_observe(pose, observe(pose, l)) - l).norm(), 1e-9);
  }
}

TEST(EkfModels, ObservationToLocal) {
  Sampler s;
  for (int k = 0; k < kRandomPoints; ++k) {
    const RangeBearing z = s.observation();
    Eigen::Matrix2d J;
    const Vec2 p = observation_to_local(z, &J);
    EXPECT_LT((p - transform_to(Pose2{1.0, -2.0, 0.7},
                                inverse_observe({1.0, -2.0, 0.7}, z))).norm(), 1e-9);
    const auto f = [](const Vec2& y) { return observation_to_local(to_rb(y)); };
    const auto c = check_jacobian(f, to_vec(z), J);
    EXPECT_TRUE(c.ok) << c.message;
  }
}

// ---- odometry noise --------------------------------------------------------------------

TEST(EkfModels, OdometryCovarianceHandComputed) {
  const OdometryNoise noise{0.01, 0.02, 0.003};
  // d = hypot(3, 4) = 5 m, |dtheta| = 0.5 rad:
  //   v_t = 0.01 * 5 = 0.05 m^2,  v_r = 0.02 * 0.5 + 0.003 * 5 = 0.025 rad^2.
  const Eigen::Matrix3d U = odometry_covariance({3.0, 4.0, -0.5}, noise);
  Eigen::Matrix3d expected = Eigen::Matrix3d::Zero();
  expected.diagonal() << 0.05, 0.05, 0.025;
  EXPECT_LT((U - expected).cwiseAbs().maxCoeff(), 1e-15) << U;
  // A pure turn: no translation variance beyond the floor.
  const Eigen::Matrix3d turn = odometry_covariance({0.0, 0.0, 2.0}, noise);
  EXPECT_EQ(turn(0, 0), 1e-12);
  EXPECT_NEAR(turn(2, 2), 0.04, 1e-15);
}

TEST(EkfModels, OdometryCovarianceFlooredWhenStanding) {
  const Eigen::Matrix3d U = odometry_covariance({0.0, 0.0, 0.0}, {0.01, 0.02, 0.003});
  EXPECT_EQ(U(0, 0), 1e-12);
  EXPECT_EQ(U(1, 1), 1e-12);
  EXPECT_EQ(U(2, 2), 1e-12);
  EXPECT_EQ(U(0, 1), 0.0);
  EXPECT_GT(U.determinant(), 0.0);  // positive definite
  // Zero noise model also gives the floor, not a singular U.
  EXPECT_EQ(odometry_covariance({1.0, 0.0, 0.1}, OdometryNoise{})(2, 2), 1e-12);
}

// Frames missed: one increment spans k frames. Its covariance is the k steps'
// noise compounded along the arc, checked against 20,000 dead-reckoned arcs whose
// every step has the model's noise (what the simulator and a real odometer do):
// 10 s missed at 10 Hz with config/mrclam.yaml's noise, driving 1.5 m and turning
// 1 rad. The single-step covariance of the whole chord, used before, misses half
// the lateral variance and all of its correlation with the heading.
TEST(EkfModels, GapOdometryCovarianceIsTheStepsCompounded) {
  const OdometryNoise noise{0.0085, 0.0094, 0.0079};  // config/mrclam.yaml's
  const int k = 100;
  const Pose2 step{0.015, 0.0, 0.01};  // 10 s at 10 Hz: 1.5 m, turning 1 rad
  Pose2 increment;
  for (int i = 0; i < k; ++i) increment = compose(increment, step);
  const Eigen::Matrix3d G = gap_odometry_covariance(increment, k, noise);
  const Eigen::Matrix3d chord = odometry_covariance(increment, noise);
  // Monte Carlo: each step measured with noise N(0, U(step)).
  std::mt19937_64 rng(20261204);
  std::normal_distribution<double> n01;
  const Eigen::Matrix3d L = odometry_covariance(step, noise).llt().matrixL();
  const int samples = 20000;
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (int s = 0; s < samples; ++s) {
    Pose2 measured;
    for (int i = 0; i < k; ++i) {
      const Eigen::Vector3d e = L * Eigen::Vector3d(n01(rng), n01(rng), n01(rng));
      measured = compose(measured, Pose2{step.x + e.x(), step.y + e.y(), step.theta + e.z()});
    }
    const Eigen::Vector3d d(measured.x - increment.x, measured.y - increment.y, wrap_angle(measured.theta - increment.theta));
    C += d * d.transpose() / samples;
  }
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(G(r, c), C(r, c), 0.04 * std::sqrt(C(r, r) * C(c, c))) << r << c << "\n" << G << "\n" << C;
  // What one step over the chord misses: 54 % of the lateral variance, and the
  // lateral error's correlation with the heading's (0.55).
  EXPECT_LT(chord(1, 1), 0.6 * C(1, 1));
  EXPECT_GT(C(1, 2), 0.4 * std::sqrt(C(1, 1) * C(2, 2)));
  EXPECT_EQ(chord(1, 2), 0.0);
  // One frame: the step's own covariance, exactly.
  EXPECT_EQ(gap_odometry_covariance(increment, 1, noise), chord);
  EXPECT_EQ(gap_odometry_covariance(increment, 0, noise), chord);
  // Standing still through a gap: the floor, k times, still positive definite.
  EXPECT_GT(gap_odometry_covariance(Pose2{}, 50, noise).determinant(), 0.0);
}

}  // namespace
}  // namespace elaslam

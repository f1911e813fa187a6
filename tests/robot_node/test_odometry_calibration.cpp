// SPDX-License-Identifier: Apache-2.0
// The odometer's systematic error estimated online: a robot whose
// odometer reports 11 % more turn and 5 % more distance than it drives (turn scale
// 0.9, speed scale 0.95: the MRCLAM robots' kind of error) estimates both and ends
// as well placed as the same robot with a true odometer; the time each prediction
// spans (gaps, re-anchors, a late start); STATUS's fields.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

#include "elaslam/robot_node/robot.hpp"
#include "elaslam/robot_node/robot_node.hpp"
#include "scene.hpp"

namespace elaslam {
namespace {

constexpr double kDt = 0.1;        // [s] frames at 10 Hz
constexpr int kFrames = 1200;      // 2 min
constexpr double kSpeed = 0.5;     // [m/s]
constexpr double kRange = 3.5;     // [m] what the sensor reports
constexpr OdometryNoise kNoise{2e-4, 5e-4, 1e-4};  // the odometer's random error, as its frames say

// Loops of varying curvature (turn rate 0.05-0.55 rad/s, period 15 s) among a grid
// of 42 landmarks 2.5 m apart: every landmark is seen again and again, and the
// turn rate varies, so that a turn scale and a turn-rate bias can be told apart.
struct LoopWorld {
  std::vector<Eigen::Vector2d> landmarks;
  LoopWorld() {
    for (int i = 0; i < 7; ++i)
      for (int j = 0; j < 6; ++j) landmarks.emplace_back(-9.0 + 2.5 * i, -6.0 + 2.6 * j);
  }
  static double turn_rate(int k) { return 0.3 + 0.25 * std::sin(2.0 * kPi * k * kDt / 15.0); }
};

struct Outcome {
  OdometryCalibration estimate;
  Eigen::Vector3d sigma = Eigen::Vector3d::Zero();
  double end_error = 0.0;  // [m] mean position error over the last 10 s
};

// One run: the true path, an odometer with the systematic error `error` (reported
// increment = (dx / s_v, dy / s_v, (dtheta - b dt) / s_w) plus its random error),
// a sensor with the filter's noise; the robot with calibration options `k`.
Outcome run(std::uint64_t seed, const OdometryCalibration& error, const CalibrationOptions& k) {
  const LoopWorld w;
  RobotOptions o = test::robot_options(Mode::kEla);
  o.sensor_range = 4.0;
  o.ekf.calibration = k;
  Robot robot(o, 1);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  Pose2 truth, odometer;
  Outcome out;
  int tail = 0;
  for (int f = 0; f < kFrames; ++f) {
    if (f > 0) {
      // The commanded increment, in B; the robot drives it with a random error (a
      // slip: the noise is on the true side, as on MRCLAM, whose odometer is the
      // integrated commands); the odometer reports the command with the systematic error.
      const Pose2 d{kSpeed * kDt, 0.0, LoopWorld::turn_rate(f) * kDt};
      const double dist = std::hypot(d.x, d.y);
      const double sd_t = std::sqrt(kNoise.var_trans_per_m * dist);
      const double sd_r = std::sqrt(kNoise.var_rot_per_rad * std::fabs(d.theta) + kNoise.var_rot_per_m * dist);
      truth = compose(truth, {d.x + sd_t * n01(rng), d.y + sd_t * n01(rng), d.theta + sd_r * n01(rng)});
      const Pose2 reported{d.x / error.speed_scale, d.y / error.speed_scale,
                           (d.theta - error.turn_bias * kDt) / error.turn_scale};
      odometer = compose(odometer, reported);
    }
    std::vector<int> seen;
    for (std::size_t id = 0; id < w.landmarks.size(); ++id)
      if ((w.landmarks[id] - truth.translation()).norm() < kRange) seen.push_back(static_cast<int>(id));
    FrameInput in = test::frame_from(f, truth, odometer, w.landmarks, seen, &rng, o.ekf);
    in.utime = static_cast<std::int64_t>(f) * 100000;
    in.noise = kNoise;
    robot.process(in);
    if (f >= kFrames - 100) {
      out.end_error += (robot.filter().pose().translation() - truth.translation()).norm();
      ++tail;
    }
  }
  out.end_error /= tail;
  out.estimate = robot.filter().calibration();
  out.sigma = robot.filter().calibration_cov().diagonal().cwiseSqrt();
  return out;
}

// The rule of docs/adr/0024-odometry-calibration.md, not
// fitted to this test: scales 1 +- 0.1, bias 0 +- 0.02 rad/s, random walks 1e-3 and
// 1e-4 per sqrt(s).
CalibrationOptions the_rule() {
  CalibrationOptions k;
  k.turn_scale_sigma = k.speed_scale_sigma = 0.1;
  k.turn_bias_sigma = 0.02;
  k.turn_scale_walk = k.speed_scale_walk = 1e-3;
  k.turn_bias_walk = 1e-4;
  return k;
}

// GIVEN an odometer with turn scale 0.9 and speed scale 0.95 WHEN the robot
// estimates its calibration (the rule's priors) THEN it ends within 2 % of 0.9 and
// 0.95, and its position error over the last 10 s is within 1.2x that of the same
// robot on the same seed with a true odometer and no calibration states.
TEST(OdometryCalibration, AMiscalibratedOdometerIsCalibratedOnline) {
  const OdometryCalibration error{0.9, 0.95, 0.0};
  for (std::uint64_t seed : {1, 2, 3}) {
    SCOPED_TRACE(seed);
    const Outcome online = run(seed, error, the_rule());
    const Outcome unbiased = run(seed, OdometryCalibration{}, CalibrationOptions{});
    const Outcome unmodelled = run(seed, error, CalibrationOptions{});
    std::printf("seed %d: turn scale %.4f +- %.4f, speed scale %.4f +- %.4f, bias %.5f +- %.5f rad/s; end error "
                "%.3f m (true odometer %.3f m, %.2fx; the error unmodelled %.3f m)\n",
                static_cast<int>(seed), online.estimate.turn_scale, online.sigma(0), online.estimate.speed_scale,
                online.sigma(1), online.estimate.turn_bias, online.sigma(2), online.end_error, unbiased.end_error,
                online.end_error / unbiased.end_error, unmodelled.end_error);
    EXPECT_NEAR(online.estimate.turn_scale, 0.9, 0.02 * 0.9);
    EXPECT_NEAR(online.estimate.speed_scale, 0.95, 0.02 * 0.95);
    EXPECT_LE(online.end_error, 1.2 * unbiased.end_error);
    EXPECT_GT(unmodelled.end_error, online.end_error);  // what it is for
  }
}

// A turn-rate bias is told apart from a turn scale when the turn rate varies.
TEST(OdometryCalibration, ATurnRateBiasIsEstimatedToo) {
  const OdometryCalibration error{0.92, 1.04, 0.02};
  const Outcome online = run(4, error, the_rule());
  std::printf("turn scale %.4f +- %.4f, speed scale %.4f +- %.4f, bias %.5f +- %.5f rad/s\n",
              online.estimate.turn_scale, online.sigma(0), online.estimate.speed_scale, online.sigma(1),
              online.estimate.turn_bias, online.sigma(2));
  EXPECT_NEAR(online.estimate.turn_scale, 0.92, 0.02 * 0.92);
  EXPECT_NEAR(online.estimate.speed_scale, 1.04, 0.02 * 1.04);
  EXPECT_NEAR(online.estimate.turn_bias, 0.02, 0.005);
}

// ---- the time a prediction spans -----------------------------------------------------

FrameInput empty_frame(int frame, std::int64_t utime, const Pose2& odometer = {}) {
  FrameInput in = test::frame_from(frame, odometer, odometer, {}, {});
  in.utime = utime;
  return in;
}

// The frames' utime difference [s], 0 when a stamp does not advance, at most
// Robot::kMaxFramePeriodS per frame elapsed.
TEST(OdometryCalibration, AStepSpansTheFramesTime) {
  Robot robot(test::robot_options(Mode::kEla), 1);
  robot.process(empty_frame(0, 1'000'000));
  EXPECT_NEAR(robot.step_seconds(empty_frame(1, 1'100'000)), 0.1, 1e-12);
  EXPECT_NEAR(robot.step_seconds(empty_frame(6, 1'600'000)), 0.6, 1e-12);  // a gap
  EXPECT_EQ(robot.step_seconds(empty_frame(1, 900'000)), 0.0);             // a stamp that goes back
  EXPECT_EQ(robot.step_seconds(empty_frame(1, 1'000'000)), 0.0);
  EXPECT_EQ(robot.step_seconds(empty_frame(3, 1'000'000 + 3'600'000'000)), 3.0 * Robot::kMaxFramePeriodS);
  EXPECT_EQ(robot.step_seconds(empty_frame(1, std::numeric_limits<std::int64_t>::max())), Robot::kMaxFramePeriodS);
  EXPECT_EQ(robot.step_seconds(empty_frame(1, std::numeric_limits<std::int64_t>::min())), 0.0);
}

// Without observations nothing corrects the calibration states: their variance is
// the prior's plus the random walk over every second the predictions span: frame
// by frame, over a gap of frames, and over a re-anchor (no increment, the time
// still passes); their means stay. A robot that starts late starts them at the prior.
TEST(OdometryCalibration, TheRandomWalkSpansGapsAndReanchors) {
  RobotOptions o = test::robot_options(Mode::kEla);
  o.ekf.calibration = the_rule();
  const CalibrationOptions& k = o.ekf.calibration;
  Robot robot(o, 1);
  Pose2 odo;
  const auto frame = [&](int f, bool reanchor = false) {
    odo = compose(odo, {0.05, 0.0, 0.02});
    FrameInput in = empty_frame(f, 5'000'000 + 100'000LL * f, odo);
    in.reanchor = reanchor;
    EXPECT_EQ(robot.process(in).filter_faults, 0) << "frame " << f;
  };
  for (int f = 0; f < 5; ++f) frame(f);  // 0.4 s
  frame(10);                             // a gap: 0.6 s
  frame(11, /*reanchor=*/true);          // 0.1 s
  const double seconds = 1.1;
  const Eigen::Matrix3d C = robot.filter().calibration_cov();
  EXPECT_NEAR(C(0, 0), k.turn_scale_sigma * k.turn_scale_sigma + k.turn_scale_walk * k.turn_scale_walk * seconds, 1e-15);
  EXPECT_NEAR(C(1, 1), k.speed_scale_sigma * k.speed_scale_sigma + k.speed_scale_walk * k.speed_scale_walk * seconds,
              1e-15);
  EXPECT_NEAR(C(2, 2), k.turn_bias_sigma * k.turn_bias_sigma + k.turn_bias_walk * k.turn_bias_walk * seconds, 1e-15);
  EXPECT_EQ(robot.filter().calibration().turn_scale, 1.0);
  EXPECT_EQ(robot.filter().calibration().speed_scale, 1.0);
  EXPECT_EQ(robot.filter().calibration().turn_bias, 0.0);
  // The pose's uncertainty took the scales' in: a turn of uncertain scale.
  EXPECT_GT(robot.filter().pose_cov()(StateLayout::kTheta, StateLayout::kTheta), 0.0);
  Robot late(o, 1);
  late.process(empty_frame(50, 5'000'000));
  EXPECT_NEAR(late.filter().calibration_cov()(0, 0), k.turn_scale_sigma * k.turn_scale_sigma, 1e-15);
}

// STATUS carries the own filter's estimate and sigmas; frozen (the default): the
// configured constants, sigma 0.
TEST(OdometryCalibration, StatusCarriesTheEstimate) {
  for (const bool estimated : {false, true}) {
    SCOPED_TRACE(estimated ? "estimated" : "frozen");
    RobotOptions o = test::robot_options(Mode::kEla);
    if (estimated) o.ekf.calibration = the_rule();
    RobotNode node(o, 2);
    const auto lms = test::ring(6, 3.0);
    Pose2 truth, odo;
    for (int f = 0; f < 30; ++f) {
      truth = compose(truth, {0.1, 0.0, 0.05});
      odo = compose(odo, {0.1 / 0.95, 0.0, 0.05 / 0.9});
      sensor_frame_t m = test::to_msg(test::frame_from(f, truth, odo, lms, test::all_ids(lms.size())), 2);
      m.utime = 100'000LL * f;
      ASSERT_EQ(node.on_sensor(m, 0), RobotNode::Verdict::kProcessed);
    }
    const node_status_t s = node.status_msg(0);
    const OdometryCalibration c = node.robot().filter().calibration();
    const Eigen::Matrix3d C = node.robot().filter().calibration_cov();
    // The six calibration fields of STATUS: turn scale, speed scale, turn bias, and their sigmas.
    using Six = std::array<float, 6>;
    const Six in_status{s.odom_turn_scale,       s.odom_speed_scale,       s.odom_turn_bias_rad_s,
                        s.odom_turn_scale_sigma, s.odom_speed_scale_sigma, s.odom_turn_bias_sigma_rad_s};
    EXPECT_EQ(in_status, (Six{static_cast<float>(c.turn_scale), static_cast<float>(c.speed_scale),
                              static_cast<float>(c.turn_bias), static_cast<float>(std::sqrt(C(0, 0))),
                              static_cast<float>(std::sqrt(C(1, 1))), static_cast<float>(std::sqrt(C(2, 2)))}));
    if (estimated) {
      EXPECT_GT(s.odom_turn_scale_sigma, 0.0f);
      EXPECT_LT(s.odom_turn_scale, 1.0f);  // on its way to 0.9
    } else {
      EXPECT_EQ(in_status, (Six{1.0f, 1.0f, 0.0f, 0.0f, 0.0f, 0.0f}));
    }
  }
}

}  // namespace
}  // namespace elaslam

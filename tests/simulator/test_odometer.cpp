// SPDX-License-Identifier: Apache-2.0
// The odometers' systematic error (OdometerError): what a robot's
// odometer reports against the true motion, per robot, and nothing else changed.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "elaslam/simulator/messages.hpp"
#include "elaslam/simulator/motion.hpp"
#include "elaslam/simulator/world.hpp"
#include "sim_test_util.hpp"

namespace elaslam::sim {
namespace {

/// The default scenario with noise-free odometers: what they report is the
/// systematic error alone.
ScenarioOptions noise_free() {
  ScenarioOptions o = test::paper();
  o.odometry = {0.0, 0.0, 0.0};
  return o;
}

TEST(SimOdometer, ReportedIncrementsTimesTheScalesAreTheTrueOnes) {
  // GIVEN robot 1 with turn scale 0.9, speed scale 0.95 and a turn rate bias of
  // 0.02 rad/s, robot 3 with other values, robot 2 with none; no odometry noise
  ScenarioOptions o = noise_free();
  o.robots[0].odometer = {0.9, 0.95, 0.02};
  o.robots[2].odometer = {1.1, 0.97, -0.01};
  const double dt = o.dt_s();
  World w(o);
  std::vector<double> turned(3, 0.0), reported_turn(3, 0.0);  // summed, unwrapped [rad]
  // u: true, in B at frame k - 1; u_r: reported
  test::for_each_increment(w, o.frames, [&](int k, int r, const Pose2& u, const Pose2& u_r) {
    const auto i = static_cast<std::size_t>(r);
    const OdometerError& e = o.robots[i].odometer;
    // THEN each frame: dx = s_v dx_r, dy = s_v dy_r, dtheta = s_w dtheta_r + b dt
    EXPECT_NEAR(e.speed_scale * u_r.x, u.x, 1e-12) << "robot " << r + 1 << " frame " << k;
    EXPECT_NEAR(e.speed_scale * u_r.y, u.y, 1e-12) << "robot " << r + 1 << " frame " << k;
    EXPECT_NEAR(e.turn_scale * u_r.theta + e.turn_bias_rad_s * dt, u.theta, 1e-12)
        << "robot " << r + 1 << " frame " << k;
    turned[i] += u.theta;
    reported_turn[i] += u_r.theta;
  });
  // AND over the whole semicircle (pi rad in 14.9 s): robot 1 reports
  // (pi - 0.02 x 14.9) / 0.9 = 3.1596 rad, robot 2 exactly pi, robot 3
  // (pi + 0.01 x 14.9) / 1.1 = 2.9915 rad
  const double T = (o.frames - 1) * dt;
  EXPECT_NEAR(turned[0], kPi, 1e-9);
  EXPECT_NEAR(reported_turn[0], (kPi - 0.02 * T) / 0.9, 1e-9);
  EXPECT_NEAR(reported_turn[1], kPi, 1e-9);
  EXPECT_NEAR(reported_turn[2], (kPi + 0.01 * T) / 1.1, 1e-9);
  // AND the integrated odometer's heading differs from the truth by exactly that
  EXPECT_NEAR(wrap_angle(w.sensor_frame(0).odometer.theta - w.robot_pose(0).theta), (kPi - 0.02 * T) / 0.9 - kPi,
              1e-9);
}

TEST(SimOdometer, TheNoiseModelInTheFrameStaysTheConfiguredOne) {
  // The filter is not told about the error: sensor_frame_t carries the three
  // configured variances, the same as without it.
  ScenarioOptions o = test::paper();
  o.robots[0].odometer = {0.9, 0.95, 0.02};
  World w(o);
  w.step();
  const elaslam::sensor_frame_t m = to_message(w.sensor_frame(0), 1);
  EXPECT_EQ(m.odom_var_trans_per_m, o.odometry.var_trans_per_m);
  EXPECT_EQ(m.odom_var_rot_per_rad, o.odometry.var_rot_per_rad);
  EXPECT_EQ(m.odom_var_rot_per_m, o.odometry.var_rot_per_m);
}

TEST(SimOdometer, AnOverrideChangesOnlyThatRobotsOdometer) {
  // GIVEN two runs, the second with robot 1's odometer miscalibrated
  const ScenarioOptions a_options = test::paper();
  ScenarioOptions b_options = a_options;
  b_options.robots[0].odometer = {0.9, 0.95, 0.0};
  World a(a_options), b(b_options);
  bool robot1_differs = false;
  for (int k = 1; k < a_options.frames; ++k) {
    a.step();
    b.step();
    // THEN robot 1 drives and sees the same, only its odometer reads differently
    EXPECT_EQ(a.robot_pose(0).x, b.robot_pose(0).x);
    EXPECT_EQ(a.robot_pose(0).theta, b.robot_pose(0).theta);
    EXPECT_EQ(a.sensor_frame(0).num_obs, b.sensor_frame(0).num_obs);
    robot1_differs = robot1_differs || a.sensor_frame(0).odometer.theta != b.sensor_frame(0).odometer.theta;
    // AND robots 2 and 3 are bit-identical
    for (int r = 1; r < 3; ++r) {
      EXPECT_EQ(a.sensor_frame(r).odometer.x, b.sensor_frame(r).odometer.x);
      EXPECT_EQ(a.sensor_frame(r).odometer.y, b.sensor_frame(r).odometer.y);
      EXPECT_EQ(a.sensor_frame(r).odometer.theta, b.sensor_frame(r).odometer.theta);
    }
  }
  EXPECT_TRUE(robot1_differs);
}

TEST(SimOdometer, AbsentKeysAndNeutralValuesGiveBitIdenticalRuns) {
  // GIVEN config/paper.yaml as it is, and with every odometer key written out at its
  // neutral value, scenario-wide and per robot
  std::string text = test::read_text(test::paper_yaml_path());
  const std::string noise = "    var_rot_per_m: 3.0e-4\n";
  ASSERT_NE(text.find(noise), std::string::npos);
  text.replace(text.find(noise), noise.size(),
               noise + "    turn_scale: 1.0\n    speed_scale: 1.0\n    turn_bias_rad_s: 0.0\n");
  for (const std::string speed : {"speed_mps: 1.26508}", "speed_mps: 0.63254}"}) {
    for (auto at = text.find(speed); at != std::string::npos; at = text.find(speed, at + 1))
      text.replace(at, speed.size(),
                   speed.substr(0, speed.size() - 1) +
                       ", odometry: {turn_scale: 1.0, speed_scale: 1.0, turn_bias_rad_s: 0.0}}");
  }
  ScenarioOptions written = load_scenario_text(text);
  ScenarioOptions absent = test::paper();
  // THEN every message of the run is the same, bit for bit, also with moving landmarks
  for (double dynamism : {0.0, 50.0}) {
    written.dynamism_percent = absent.dynamism_percent = dynamism;
    EXPECT_EQ(test::run_bytes(written), test::run_bytes(absent)) << dynamism << " %";
  }
}

}  // namespace
}  // namespace elaslam::sim

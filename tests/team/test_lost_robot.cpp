// SPDX-License-Identifier: Apache-2.0
// A robot that loses its heading (a 25 deg kick in its odometer, unmodelled) in a
// team: what it does to itself and to the others, with and without the team map.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "elaslam/common/geometry.hpp"
#include "elaslam/team/team_run.hpp"
#include "edited_frames.hpp"
#include "paper_team.hpp"

namespace elaslam {
namespace {

struct Outcome {
  double kicked_error = 0.0;   // robot 1's mean position error after the kick [m]
  double others_error = 0.0;   // robots 2 and 3
  double landmark_error = 0.0; // eq 18 over the run
  double precision = 0.0;
  int flagged = 0;
};

Outcome run_kicked(bool team_map, int seed, double gate = 0.9999) {
  TeamConfig c = test::paper();
  c.robot.team_map_gate_probability = gate;
  c.scenario.seed = seed;
  c.scenario.dynamism_percent = 0.0;
  c.robot.team_map_fuse = team_map;
  c.main.team_map_period_frames = team_map ? 10 : 0;
  // Robot index 0's odometer turned by 25 deg from frame `at` on (its odometry says it
  // turned that much more than it did).
  const int at = 50;
  const double kick = deg2rad(25.0);
  Pose2 at_odo;
  test::EditedFrames frames(c.scenario, [&](int k, std::vector<sensor_frame_t>* sensors) {
    sensor_frame_t& s = (*sensors)[0];
    const Pose2 odo{s.odom_x, s.odom_y, s.odom_theta};
    if (k == at) at_odo = odo;
    if (k >= at) {
      const Pose2 kicked = compose(compose(at_odo, Pose2{0.0, 0.0, kick}), between(at_odo, odo));
      s.odom_x = kicked.x;
      s.odom_y = kicked.y;
      s.odom_theta = kicked.theta;
    }
  });
  const RunResult r = run_team(c.robot, c.main, frames);
  Outcome o;
  for (std::size_t i = 0; i < r.estimated.size(); ++i) {
    double sum = 0.0;
    int n = 0;
    for (std::size_t k = static_cast<std::size_t>(at); k < r.estimated[i].size(); ++k, ++n)
      sum += std::hypot(r.estimated[i][k].pose.x - r.truth[i][k].pose.x, r.estimated[i][k].pose.y - r.truth[i][k].pose.y);
    (i == 0 ? o.kicked_error : o.others_error) += sum / n / (i == 0 ? 1.0 : 2.0);
  }
  o.landmark_error = r.metrics.landmark_error_mean;
  o.precision = r.metrics.precision;
  o.flagged = r.metrics.flagged;
  return o;
}

// Robot 1's odometer reports a 25 deg turn it never made at frame 50 (static world,
// paper robots). Alone it is lost for the rest of the run (2.5 m) and drops the
// landmarks in view as moving. With the team map, most of the next map disagrees
// with it, so it takes the team's side (Robot::apply_team_map) and its pose comes
// back; the others, whose maps do not agree with its after the kick, are not pulled.
TEST(LostRobot, TheTeamMapBringsBackARobotThatLostItsHeading) {
  for (int seed : {1, 2, 3}) {
    SCOPED_TRACE(seed);
    const Outcome alone = run_kicked(false, seed);
    const Outcome team = run_kicked(true, seed);
    std::printf("seed %d after the kick: robot 1 %.3f m alone, %.3f m with the team map; robots 2-3 %.3f / %.3f m\n",
                seed, alone.kicked_error, team.kicked_error, alone.others_error, team.others_error);
    EXPECT_GT(alone.kicked_error, 2.0);
    EXPECT_LT(team.kicked_error, 0.25 * alone.kicked_error);
    EXPECT_LT(team.others_error, 0.03);
    EXPECT_LE(team.others_error, alone.others_error + 0.005);
  }
}

// The gauge test never fires on a simulated team whose maps are right: the paper's
// scenario with the team map every 10 frames, static and with half the landmarks
// moving at 0.5 m/s, five seeds each: no robot relocalised, and the runs are those
// without the test to the digit (nothing it did).
TEST(LostRobot, TheGaugeTestNeverMovesARobotOfATeamWhoseMapsAreRight) {
  for (const double dynamism : {0.0, 50.0}) {
    for (int seed = 1; seed <= 5; ++seed) {
      SCOPED_TRACE("dynamism " + std::to_string(dynamism) + " seed " + std::to_string(seed));
      TeamConfig c = test::paper();
      c.scenario.seed = seed;
      c.scenario.dynamism_percent = dynamism;
      c.robot.team_map_fuse = true;
      c.main.team_map_period_frames = 10;
      const RunResult with = run_team(c);
      c.robot.team_map_gauge_test = false;
      const RunResult without = run_team(c);
      for (std::size_t i = 0; i < with.metrics.robots.size(); ++i) {
        EXPECT_EQ(with.metrics.robots[i].relocalised, 0) << "robot " << i + 1;
        EXPECT_EQ(with.metrics.robots[i].error_mean, without.metrics.robots[i].error_mean) << "robot " << i + 1;
      }
    }
  }
}

// The simulated form of the real failure (config/odometry_bias.yaml): robot 1's
// odometer overstates its turns by 1/0.9 and its speed by 1/0.95, and it turns 115
// deg where it sees nothing, so it comes out turned by some 13 deg and maps on from
// there. With the team map and the gauge test it is moved back once and ends at a
// quarter of its error without the test (which then never finds it: it sees no
// trouble of its own); the other robots are untouched by it.
TEST(LostRobot, ABiasedRobotThatTurnedWhereItSawNothingIsMovedBackByTheTeamMap) {
  const TeamConfig base = load_team_config(std::string(ELASLAM_SOURCE_DIR) + "/config/odometry_bias.yaml");
  for (const int seed : {1, 2, 3}) {
    SCOPED_TRACE(seed);
    TeamConfig c = base;
    c.scenario.seed = seed;
    c.scenario.dynamism_percent = 0.0;
    c.robot.team_map_fuse = true;
    c.main.team_map_period_frames = 10;
    const RunResult with = run_team(c);
    c.robot.team_map_gauge_test = false;
    const RunResult without = run_team(c);
    std::printf("seed %d: robot 1 %.3f m with the gauge test (%lld relocalisation), %.3f m without\n", seed,
                with.metrics.robots[0].error_mean, static_cast<long long>(with.metrics.robots[0].relocalised),
                without.metrics.robots[0].error_mean);
    EXPECT_EQ(with.metrics.robots[0].relocalised, 1);
    EXPECT_EQ(without.metrics.robots[0].relocalised, 0);
    EXPECT_GT(without.metrics.robots[0].error_mean, 0.5);
    EXPECT_LT(with.metrics.robots[0].error_mean, 0.3 * without.metrics.robots[0].error_mean);
    for (std::size_t i = 1; i < with.metrics.robots.size(); ++i) {
      EXPECT_EQ(with.metrics.robots[i].relocalised, 0);
      EXPECT_LT(with.metrics.robots[i].error_mean, 0.06);
    }
  }
}

}  // namespace
}  // namespace elaslam

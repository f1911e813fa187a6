// SPDX-License-Identifier: Apache-2.0
// The team's map back to its robots (robot.team_map, team_aid.hpp; docs/adr/0025-team-map-two-filters.md):
// no double counting, shown by the NEES of the
// channel filter in a linear world and of the robots' poses in the simulated team,
// and better poses.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "elaslam/common/geometry.hpp"
#include "elaslam/main_robot/main_node.hpp"
#include "elaslam/robot_node/robot_node.hpp"
#include "elaslam/robot_node/team_aid.hpp"
#include "elaslam/simulator/messages.hpp"
#include "elaslam/simulator/world.hpp"
#include "elaslam/team/team_run.hpp"

#include "../robot_node/scene.hpp"
#include "paper_team.hpp"

namespace elaslam {
namespace {

// ---- the channel filter in a linear Gaussian world ------------------------------
//
// One static landmark l. Robot 0 holds its own estimate from its own measurements;
// the "team" (the other robots) learns about l over time from independent
// measurements, and sends its current estimate (g_t, G_t) every step. Robot 0 fuses
// what the channel offers. Exact Bayes says the result is N(l; fused) with the
// information of all measurements: NEES ~ chi2(2), mean 2. Fusing each team estimate
// whole (no channel) counts the team's early measurements again every step.
struct LinearRun {
  double nees = 0.0;       // final (x - l)^T P^-1 (x - l)
  double info_trace = 0.0; // tr(P^-1): what the robot thinks it knows
};

LinearRun linear_run(std::mt19937& rng, bool channel, int steps) {
  std::normal_distribution<double> n01;
  const Eigen::Vector2d l(3.0, -2.0);
  const auto measure = [&](double sigma) { return Eigen::Vector2d(l.x() + sigma * n01(rng), l.y() + sigma * n01(rng)); };
  // Robot 0's own estimate: one measurement with sigma 0.5.
  Eigen::Matrix2d Y = Eigen::Matrix2d::Identity() / 0.25;
  Eigen::Vector2d y = Y * measure(0.5);
  // The team: information form, one measurement with sigma 0.3 per step.
  Eigen::Matrix2d Yt = Eigen::Matrix2d::Zero();
  Eigen::Vector2d yt = Eigen::Vector2d::Zero();
  TeamChannel ch(4, 0.0);
  for (int t = 0; t < steps; ++t) {
    const Eigen::Matrix2d Ym = Eigen::Matrix2d::Identity() / 0.09;
    Yt += Ym;
    yt += Ym * measure(0.3);
    const Eigen::Matrix2d G = Yt.inverse();
    const Eigen::Vector2d g = G * yt;
    const Eigen::Matrix2d P = Y.inverse();
    const Eigen::Vector2d x = P * y;
    TeamIncrement inc;
    if (channel) {
      if (!ch.offer(1, 0, g, G, x, P, &inc)) continue;
      ch.commit(1, inc);
    } else {
      inc.z = g;
      inc.R = G;
    }
    const Eigen::Matrix2d Rinv = inc.R.inverse();
    Y += Rinv;
    y += Rinv * inc.z;
  }
  const Eigen::Matrix2d P = Y.inverse();
  const Eigen::Vector2d e = P * y - l;
  return {e.dot(Y * e), Y.trace()};
}

TEST(TeamChannel, FusedIncrementsAreExactBayesInALinearWorld) {
  std::mt19937 rng(11);
  const int runs = 2000;
  double with = 0.0, without = 0.0;
  for (int k = 0; k < runs; ++k) {
    with += linear_run(rng, true, 10).nees / runs;
    without += linear_run(rng, false, 10).nees / runs;
  }
  // chi2(2) mean 2; the mean of 2000 has a std of 2 / sqrt(2000) = 0.045.
  EXPECT_NEAR(with, 2.0, 0.2);
  // Without the channel the same data is counted up to ten times: far overconfident.
  EXPECT_GT(without, 4.0);
}

TEST(TeamChannel, OffersOnlyWhatIsNewAndNeverWhatFell) {
  TeamChannel ch(8, 0.05);
  const Eigen::Vector2d l(1.0, 1.0);
  const Eigen::Matrix2d P = 0.04 * Eigen::Matrix2d::Identity();
  const Eigen::Matrix2d G = 0.01 * Eigen::Matrix2d::Identity();
  TeamIncrement inc;
  ASSERT_TRUE(ch.offer(3, 0, Eigen::Vector2d(1.1, 0.9), G, l, P, &inc));
  EXPECT_TRUE(inc.R.isApprox(G, 1e-12));
  EXPECT_TRUE(inc.z.isApprox(Eigen::Vector2d(1.1, 0.9), 1e-12));
  ch.commit(3, inc);
  // The same estimate again adds nothing.
  EXPECT_FALSE(ch.offer(3, 0, Eigen::Vector2d(1.1, 0.9), G, l, P, &inc));
  // Less information (a robot's estimate dropped out): nothing.
  EXPECT_FALSE(ch.offer(3, 0, Eigen::Vector2d(1.0, 1.0), 2.0 * G, l, P, &inc));
  // Twice the information: the increment is the difference, 100 m^-2 more.
  ASSERT_TRUE(ch.offer(3, 0, Eigen::Vector2d(1.1, 0.9), 0.5 * G, l, P, &inc));
  EXPECT_TRUE(inc.Y.isApprox(100.0 * Eigen::Matrix2d::Identity(), 1e-9));
  // More information along x only: fused along x; along y no innovation.
  ch.commit(3, inc);
  Eigen::Matrix2d G2 = 0.5 * G;
  G2(0, 0) = 0.25 * G(0, 0);
  ASSERT_TRUE(ch.offer(3, 0, Eigen::Vector2d(1.2, 0.5), G2, l, P, &inc));
  EXPECT_NEAR(inc.Y(0, 0), 200.0, 1e-6);
  EXPECT_LT(inc.Y(1, 1), 1e-6);
  EXPECT_NEAR(inc.z.y(), l.y(), 1e-9);
  // A new epoch (main started the landmark afresh: it moved and came back): the
  // channel starts again, the estimate is fused whole, and counted under its epoch.
  ASSERT_TRUE(ch.offer(3, 40, Eigen::Vector2d(1.1, 0.9), G, l, P, &inc));
  EXPECT_TRUE(inc.R.isApprox(G, 1e-12));
  EXPECT_EQ(inc.epoch, 40);
  ch.commit(3, inc);
  EXPECT_EQ(ch.epoch(3), 40);
  EXPECT_TRUE(ch.fused_information(3).isApprox(100.0 * Eigen::Matrix2d::Identity(), 1e-9));
  EXPECT_FALSE(ch.offer(3, 40, Eigen::Vector2d(1.1, 0.9), G, l, P, &inc));
  // forget: the next estimate is fused whole.
  ch.forget(3);
  EXPECT_EQ(ch.epoch(3), -1);
  ASSERT_TRUE(ch.offer(3, 0, Eigen::Vector2d(1.1, 0.9), G, l, P, &inc));
  EXPECT_TRUE(inc.R.isApprox(G, 1e-12));
  // Not a covariance: nothing, and ids outside the range are ignored.
  EXPECT_FALSE(ch.offer(3, 0, Eigen::Vector2d(1.1, 0.9), -G, l, P, &inc));
  EXPECT_FALSE(ch.offer(8, 0, Eigen::Vector2d(1.1, 0.9), G, l, P, &inc));
}

// ---- main_robot: the map without one robot ----------------------------------------

TEST(TeamMap, MainSendsEachRobotTheOthersInformationOnly) {
  GlobalMapOptions o;
  o.team_map_period_frames = 1;
  MainNode main(o);
  const auto event = [&](int robot, std::int64_t seq, int id, double x, double var) {
    landmark_event_t e{};
    e.utime = 1;
    e.frame = 0;
    e.robot_id = static_cast<std::int16_t>(robot);
    e.incarnation = 1;
    e.seq = seq;
    e.kind = landmark_event_t::ADD;
    e.landmark_id = id;
    e.x = x;
    e.y = 0.0;
    e.cov[0][0] = e.cov[1][1] = var;
    std::string why;
    ASSERT_TRUE(main.on_event(e, &why)) << why;
  };
  event(1, 1, 5, 1.0, 0.04);
  event(2, 1, 5, 2.0, 0.01);
  event(3, 1, 5, 3.0, 0.01);
  event(1, 2, 6, 1.0, 0.04);  // robot 1 alone holds landmark 6
  const int n = main.make_team_map(1, 10, 0);
  ASSERT_EQ(n, 1);
  const global_map_t& c = main.map_chunk(0);
  ASSERT_EQ(c.num_landmarks, 1);  // landmark 6 has no other robot's estimate
  EXPECT_EQ(c.landmarks[0].id, 5);
  EXPECT_NEAR(c.landmarks[0].x, 2.5, 1e-12);          // robots 2 and 3, equal weights
  EXPECT_NEAR(c.landmarks[0].cov[0][0], 0.005, 1e-12);
  EXPECT_EQ(c.landmarks[0].contributors, 0b110);
  EXPECT_EQ(c.num_moving, 0);
  ASSERT_EQ(main.make_team_map(2, 10, 0), 1);
  const global_map_t& c2 = main.map_chunk(0);
  ASSERT_EQ(c2.num_landmarks, 2);
  // Robots 1 (0.04) and 3 (0.01): information 25 + 100.
  EXPECT_NEAR(c2.landmarks[0].cov[0][0], 1.0 / 125.0, 1e-12);
  EXPECT_NEAR(c2.landmarks[0].x, (25.0 * 1.0 + 100.0 * 3.0) / 125.0, 1e-12);
  EXPECT_EQ(c2.landmarks[1].id, 6);
  EXPECT_EQ(c2.landmarks[1].contributors, 0b001);
  // Due once per frame, every team_map_period_frames.
  EXPECT_TRUE(main.team_map_due(0));
  EXPECT_FALSE(main.team_map_due(0));
  EXPECT_FALSE(main.team_map_due(-1));
}

// Team maps go out once per period of team_map_period_frames, at the first frame the
// team finishes in it: a period whose multiple of the period was never finished (its
// POSEs lost, the team's finished frame jumping over it) still gets its team maps.
TEST(TeamMap, DueOncePerPeriodAlsoWhenTheFinishedFrameJumpsOverItsMultiple) {
  GlobalMapOptions o;
  o.team_map_period_frames = 10;
  MainNode main(o);
  EXPECT_TRUE(main.team_map_due(0));
  EXPECT_FALSE(main.team_map_due(5));
  EXPECT_FALSE(main.team_map_due(8));
  EXPECT_TRUE(main.team_map_due(11));  // frames 9 and 10 never finished
  EXPECT_FALSE(main.team_map_due(12));
  EXPECT_FALSE(main.team_map_due(19));
  EXPECT_TRUE(main.team_map_due(20));
  EXPECT_FALSE(main.team_map_due(20));
  EXPECT_FALSE(main.team_map_due(15));  // an older frame never makes one again
  EXPECT_TRUE(main.team_map_due(47));
  EXPECT_FALSE(main.team_map_due(-1));
}

// ---- a landmark that leaves the aided filter and comes back ------------------------

// A corridor: landmarks every 2 m on both sides, a robot that drives 20 m out and
// back with a filter of 12 slots, so the landmarks behind it are evicted for room
// (archived) and come back on the way home. The team's map (every landmark at its
// true position, 3 mm) is fused at the start; the same map again at the end (main's
// estimate went on from the same data) must not be fused into a landmark that was
// evicted and came back: its first fusion taught the pose, which kept it. A channel
// that forgot a landmark when it left the aided filter would fuse the whole
// estimate a second time.
TEST(TeamMap, ALandmarkEvictedAndBackIsNotFusedTwice) {
  RobotOptions o = test::robot_options(Mode::kEla);
  o.ekf.capacity = 12;
  o.sensor_range = 4.0;
  o.team_map_fuse = true;
  std::vector<Eigen::Vector2d> lms;
  for (int i = 0; i <= 10; ++i) {
    lms.emplace_back(2.0 * i, 2.0);
    lms.emplace_back(2.0 * i, -2.0);
  }
  std::vector<TeamEstimate> team;
  for (int id = 0; id < static_cast<int>(lms.size()); ++id)
    team.push_back({id, lms[static_cast<std::size_t>(id)], 1e-5 * Eigen::Matrix2d::Identity()});
  Robot robot(o, 1);
  std::vector<Pose2> path;
  for (int k = 0; k <= 80; ++k) path.push_back({0.25 * k, 0.0, 0.0});
  for (int k = 1; k <= 8; ++k) path.push_back({20.0, 0.0, wrap_angle(kPi / 8.0 * k)});
  for (int k = 1; k <= 80; ++k) path.push_back({20.0 - 0.25 * k, 0.0, wrap_angle(kPi)});
  constexpr int kLeft = 0;  // the landmark at (0, 2)
  bool evicted = false;
  std::mt19937_64 rng(7);
  for (int k = 0; k < static_cast<int>(path.size()); ++k) {
    const Pose2& p = path[static_cast<std::size_t>(k)];
    std::vector<int> ids;
    for (int id = 0; id < static_cast<int>(lms.size()); ++id)
      if ((lms[static_cast<std::size_t>(id)] - Eigen::Vector2d(p.x, p.y)).norm() < 3.8) ids.push_back(id);
    robot.process(test::frame_from(k, p, p, lms, ids, &rng));
    if (k == 8) {
      robot.apply_team_map(team.data(), static_cast<int>(team.size()));
      ASSERT_LT(robot.estimate().landmark_cov(kLeft).trace(), 3e-5) << "the team's estimate was fused";
    }
    evicted = evicted || robot.lmap()[kLeft].archived;
  }
  ASSERT_TRUE(evicted);
  ASSERT_TRUE(robot.estimate().has_landmark(kLeft)) << "it came back";
  const double own = robot.estimate().landmark_cov(kLeft).trace();
  EXPECT_GT(own, 1e-4);  // its own sightings since it came back
  // Its team estimate again (alone: the others' first fusions would shrink it
  // through the correlations).
  const std::int64_t fused = robot.team_counters().fused;
  robot.apply_team_map(&team[kLeft], 1);
  EXPECT_EQ(robot.team_counters().fused, fused) << "fused a second time";
  EXPECT_EQ(robot.estimate().landmark_cov(kLeft).trace(), own);
  EXPECT_EQ(robot.lmap()[kLeft].times_moving, 0);
}

// team_map.hold_candidates: a team map that comes while the robot's landmarks are
// candidates is held in the aided filter's history and fused, as of its team map,
// when they are confirmed. After the confirming frame the aided filter of `ela` is
// that of `ekf` (which maps at first sighting and so fused the team map at once) to
// rounding, and the channel counts the held increments once: the same team map
// again fuses nothing. Without the rule the candidates missed the team map.
TEST(TeamMap, ACandidatesTeamEstimateIsFusedAsOfItsTeamMapOnceConfirmed) {
  const std::vector<Eigen::Vector2d> lms = test::ring(6, 3.0);
  std::vector<TeamEstimate> team;
  for (int id = 0; id < 6; ++id)
    team.push_back({id, lms[static_cast<std::size_t>(id)] + Eigen::Vector2d(0.004 * id, -0.003),
                    Eigen::Vector2d(1e-4, 2e-4).asDiagonal()});
  for (const bool hold : {true, false}) {
    SCOPED_TRACE(hold ? "hold_candidates" : "without");
    RobotOptions o = test::robot_options(Mode::kEla);
    o.candidate_history_frames = 2;
    o.team_map_fuse = true;
    o.team_map_hold_candidates = hold;
    RobotOptions oe = test::robot_options(Mode::kEkf);
    oe.team_map_fuse = true;
    Robot ela(o, 1), ekf(oe, 1);
    std::mt19937_64 rng_a(11), rng_b(11);
    Pose2 truth{0.0, 0.0, 0.0}, odometer{0.0, 0.0, 0.0};
    for (int k = 0; k < 3; ++k) {
      ela.process(test::frame_from(k, truth, odometer, lms, test::all_ids(6), &rng_a));
      ekf.process(test::frame_from(k, truth, odometer, lms, test::all_ids(6), &rng_b));
      if (k == 1) {  // the landmarks are candidates in ela, STATIC in ekf
        ASSERT_EQ(ela.lmap()[0].status, LandmarkStatus::kCandidate);
        ela.apply_team_map(team.data(), 6);
        ekf.apply_team_map(team.data(), 6);
        EXPECT_EQ(ela.team_counters().held, hold ? 6 : 0);
        EXPECT_EQ(ela.team_counters().fused, 0);
        EXPECT_EQ(ekf.team_counters().fused, 6);
      }
      truth = compose(truth, Pose2{0.1, 0.0, 0.05});
      odometer = compose(odometer, Pose2{0.1, 0.002, 0.048});  // the odometer errs
    }
    for (int i = 0; i < 6; ++i) ASSERT_EQ(ela.lmap()[i].status, LandmarkStatus::kStatic) << "landmark " << i;
    const EkfSlam& a = ela.estimate();
    const EkfSlam& b = ekf.estimate();
    const double d = test::max_difference_by_id(a, b, 6);
    if (hold) {
      EXPECT_LT(d, 1e-12);
      EXPECT_EQ(ela.team_counters().fused, 6);
      // Counted once: the same team map again is nothing new, as for ekf.
      ela.apply_team_map(team.data(), 6);
      ekf.apply_team_map(team.data(), 6);
      EXPECT_EQ(ela.team_counters().fused, 6);
      EXPECT_EQ(ekf.team_counters().fused, 6);
    } else {
      EXPECT_GT(d, 1e-4);
      EXPECT_EQ(ela.team_counters().fused, 0);
    }
  }
}

// A candidate that starts over before it is confirmed drops its held team estimate:
// the landmark jumps after the team map, is re-anchored, and its confirmation later
// fuses nothing held (the channel has counted nothing for it).
TEST(TeamMap, ACandidateThatStartsOverDropsItsHeldTeamEstimate) {
  std::vector<Eigen::Vector2d> lms = test::ring(6, 3.0);
  std::vector<TeamEstimate> team;
  for (int id = 0; id < 6; ++id) team.push_back({id, lms[static_cast<std::size_t>(id)], 1e-4 * Eigen::Matrix2d::Identity()});
  RobotOptions o = test::robot_options(Mode::kEla);
  o.candidate_history_frames = 2;
  o.team_map_fuse = true;
  o.team_map_hold_candidates = true;
  Robot r(o, 1);
  const Pose2 p{0.0, 0.0, 0.0};
  r.process(test::frame_from(0, p, p, lms, test::all_ids(6)));
  r.apply_team_map(team.data(), 6);
  EXPECT_EQ(r.team_counters().held, 6);
  lms[0] += Eigen::Vector2d(1.0, 0.0);  // jumps: re-anchored at frame 1
  for (int k = 1; k <= 3; ++k) r.process(test::frame_from(k, p, p, lms, test::all_ids(6)));
  EXPECT_EQ(r.lmap()[0].status, LandmarkStatus::kStatic);  // confirmed at frame 3, from its new anchor
  EXPECT_EQ(r.team_counters().fused, 5);                    // the other five's held estimates
  EXPECT_NEAR(r.estimate().landmark(0).x(), lms[0].x(), 1e-6);  // the old team estimate never pulled it
}

// A landmark the robot learns has moved (a notice) comes back as a new epoch: main
// dropped every robot's estimate of it when it moved and started it afresh, so the
// team's estimate is data the robot never had, and it is fused whole.
TEST(TeamMap, ALandmarkThatMovedStartsItsChannelAgain) {
  TeamConfig c = test::paper();
  c.scenario.dynamism_percent = 0.0;
  c.scenario.seed = 3;
  c.robot.team_map_fuse = true;
  constexpr int kRobot = 2;
  sim::World world(c.scenario);
  RobotNode node(c.robot, kRobot);
  const auto& truth = world.landmark_positions();
  std::int64_t version = 0;
  const auto team_map = [&] {
    global_map_t m{};
    m.frame = node.counters().frames - 1;
    m.incarnation = 1;
    m.version = ++version;
    m.num_chunks = 1;
    m.id_end = c.robot.ekf.max_landmark_id;
    for (int id = 0; id < static_cast<int>(truth.size()); ++id) {
      global_landmark_t l{};
      l.id = id;
      l.x = truth[static_cast<std::size_t>(id)].x();
      l.y = truth[static_cast<std::size_t>(id)].y();
      l.cov[0][0] = l.cov[1][1] = 1e-4;
      l.contributors = 1;  // robot 1's
      l.status = global_landmark_t::STATIC;
      m.landmarks.push_back(l);
    }
    m.num_landmarks = static_cast<int16_t>(m.landmarks.size());
    std::string why;
    EXPECT_TRUE(node.on_team_map(m, &why)) << why;
  };
  int frame = 0;
  const auto next = [&] {
    if (frame > 0) world.step();
    ASSERT_EQ(node.on_sensor(sim::to_message(world.sensor_frame(kRobot - 1), frame), 1000 + frame), RobotNode::Verdict::kProcessed);
    ++frame;
  };
  for (int k = 0; k < 20; ++k) next();
  team_map();
  next();  // applied after the frame that follows the map's
  const EkfSlam& aided = node.robot().estimate();
  int moved = -1;  // one fused and in view
  for (int id = 0; id < static_cast<int>(truth.size()) && moved < 0; ++id)
    if (aided.has_landmark(id) && node.robot().lmap()[id].last_seen_frame == frame - 1 && aided.landmark_cov(id).trace() < 2.5e-4)
      moved = id;
  ASSERT_GE(moved, 0);
  dynamic_notice_t n{};
  n.frame = frame - 1;
  n.incarnation = 1;
  n.seq = 1;
  n.landmark_id = moved;
  n.detected_by = 1;
  ASSERT_TRUE(node.on_notice(n));
  ASSERT_FALSE(aided.has_landmark(moved));
  while (frame < c.scenario.frames && !(aided.has_landmark(moved) && node.robot().lmap()[moved].status == LandmarkStatus::kStatic))
    next();
  ASSERT_TRUE(aided.has_landmark(moved)) << "landmark " << moved << " never came back";
  EXPECT_GT(aided.landmark_cov(moved).trace(), 4e-4);  // its own sightings
  team_map();
  next();
  EXPECT_LT(aided.landmark_cov(moved).trace(), 2.5e-4);
  EXPECT_EQ(node.robot().team_channel().epoch(moved), 1);
}

// ---- the team: NEES and accuracy --------------------------------------------------

TeamConfig team_config(bool team_map, double dynamism, int seed) {
  RunOverrides o;
  o.dynamism_percent = dynamism;
  o.landmark_speed_mps = 0.5;
  o.seed = seed;
  TeamConfig c = apply_overrides(test::paper(), o);
  c.robot.team_map_fuse = team_map;
  c.main.team_map_period_frames = team_map ? 10 : 0;
  return c;
}

struct PoseStats {
  double nees = 0.0;   // mean of e^T P^-1 e over robots, frames and seeds (3 dof)
  double error = 0.0;  // mean position error [m]
  long samples = 0;
};

PoseStats pose_stats(bool team_map, double dynamism, const std::vector<int>& seeds) {
  PoseStats s;
  for (int seed : seeds) {
    const RunResult r = run_team(team_config(team_map, dynamism, seed));
    for (std::size_t i = 0; i < r.estimated.size(); ++i)
      for (std::size_t k = 1; k < r.estimated[i].size() && k < r.truth[i].size(); ++k) {
        const TrajectoryPoint& e = r.estimated[i][k];
        const Pose2& t = r.truth[i][k].pose;
        const Eigen::Vector3d d(e.pose.x - t.x, e.pose.y - t.y, wrap_angle(e.pose.theta - t.theta));
        const Eigen::LDLT<Eigen::Matrix3d> ldlt(e.cov);
        s.nees += d.dot(ldlt.solve(d));
        s.error += d.head<2>().norm();
        ++s.samples;
      }
  }
  s.nees /= static_cast<double>(s.samples);
  s.error /= static_cast<double>(s.samples);
  return s;
}

// In a static world the own filters are the paper's EKF-SLAM; the aided ones add the
// other robots' information. Double counting would show as a NEES well above the own
// filters' (the linear test above: twice as high after ten maps); the aided poses
// must be no less consistent and more accurate.
TEST(TeamMap, AidedPosesAreConsistentAndBetterInAStaticWorld) {
  const std::vector<int> seeds = {21, 22, 23, 24, 25, 26};
  const PoseStats own = pose_stats(false, 0.0, seeds);
  const PoseStats aided = pose_stats(true, 0.0, seeds);
  std::printf("static world, %ld samples: own NEES %.3f error %.4f m; aided NEES %.3f error %.4f m\n", own.samples,
              own.nees, own.error, aided.nees, aided.error);
  // Measured (docs/experiments/team-map.md): own 2.37, aided 3.49; fusing each team map whole
  // (no channel filter) gives 4.66 on these seeds. 3 is nominal; the aided filters'
  // excess comes from the team map's landmarks fused as independent (main keeps
  // marginals only).
  EXPECT_LT(aided.nees, 4.2);
  EXPECT_LT(aided.nees - own.nees, 1.5);
  EXPECT_LT(aided.error, 0.8 * own.error);
}

TEST(TeamMap, AidedPosesAreBetterUnderDynamism) {
  const std::vector<int> seeds = {31, 32, 33};
  const PoseStats own = pose_stats(false, 50.0, seeds);
  const PoseStats aided = pose_stats(true, 50.0, seeds);
  std::printf("50 %% dynamism: own NEES %.3f error %.4f m; aided NEES %.3f error %.4f m\n", own.nees, own.error,
              aided.nees, aided.error);
  EXPECT_LT(aided.error, 0.8 * own.error);
}

// The reported maps are the own filters': the global map is the same with or
// without the team map (what main fuses never contains what it sent).
TEST(TeamMap, GlobalMapIsUnchangedByTheTeamMap) {
  const RunResult own = run_team(team_config(false, 30.0, 41));
  const RunResult aided = run_team(team_config(true, 30.0, 41));
  ASSERT_EQ(own.final_map.size(), aided.final_map.size());
  for (std::size_t k = 0; k < own.final_map.size(); ++k) {
    EXPECT_EQ(own.final_map[k].id, aided.final_map[k].id);
    EXPECT_NEAR((own.final_map[k].p - aided.final_map[k].p).norm(), 0.0, 1e-12);
  }
  EXPECT_DOUBLE_EQ(own.metrics.landmark_error_mean, aided.metrics.landmark_error_mean);
  EXPECT_DOUBLE_EQ(own.metrics.precision, aided.metrics.precision);
}

}  // namespace
}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// Algorithm 1, path by path, on constructed frames (no simulator).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "elaslam/common/stats.hpp"
#include "elaslam/robot_node/robot_node.hpp"
#include "elaslam/simulator/messages.hpp"
#include "elaslam/simulator/world.hpp"
#include "elaslam/team/team_config.hpp"
#include "scene.hpp"

namespace elaslam {
namespace {

int count_events(const Robot& r, EventKind k, int id = -1) {
  return static_cast<int>(std::count_if(r.events().begin(), r.events().end(), [&](const MapEvent& e) {
    return e.kind == k && (id < 0 || e.landmark_id == id);
  }));
}

class RobotPaths : public ::testing::Test {
 protected:
  // A robot standing still among 6 landmarks 3 m away; noise-free frames unless said.
  void SetUp() override { lms_ = test::ring(6, 3.0); }
  FrameSummary step(Robot& r, const std::vector<int>& ids, std::mt19937_64* noise = nullptr) {
    return r.process(test::frame_from(frame_++, pose_, pose_, lms_, ids, noise));
  }
  void confirm_all(Robot& r) {
    for (int k = 0; k < 3; ++k) step(r, test::all_ids(lms_.size()));
  }
  Pose2 pose_{0.0, 0.0, 0.0};
  std::vector<Eigen::Vector2d> lms_;
  int frame_ = 0;
};

TEST_F(RobotPaths, NewBecomesCandidateThenStaticAfterConfirmFrames) {
  Robot r(test::robot_options(Mode::kEla), 1);
  // Frame 0: every landmark is new -> CANDIDATE: an inert state in the filter.
  FrameSummary s = step(r, test::all_ids(6));
  EXPECT_EQ(s.num_candidates, 6);
  EXPECT_EQ(s.num_accepted, 0);
  EXPECT_EQ(r.filter().num_landmarks(), 6);
  EXPECT_EQ(r.lmap()[0].status, LandmarkStatus::kCandidate);
  EXPECT_EQ(r.lmap()[0].consistent_sightings, 1);
  EXPECT_TRUE(r.events().empty());
  // Frame 1: consistent again, still a candidate; it corrects nothing.
  const Eigen::Vector3d pose_before(r.filter().pose().x, r.filter().pose().y, r.filter().pose().theta);
  s = step(r, test::all_ids(6));
  EXPECT_EQ(r.lmap()[0].consistent_sightings, 2);
  EXPECT_EQ(s.num_accepted, 0);
  EXPECT_EQ(Eigen::Vector3d(r.filter().pose().x, r.filter().pose().y, r.filter().pose().theta), pose_before);
  EXPECT_EQ(count_events(r, EventKind::kAdd), 0);
  // Frame 2: the third consistent sighting confirms: STATIC, ADD sent, and its
  // sighting corrects the filter.
  s = step(r, test::all_ids(6));
  EXPECT_EQ(s.num_added, 6);
  EXPECT_EQ(s.num_accepted, 6);
  EXPECT_EQ(r.lmap()[3].status, LandmarkStatus::kStatic);
  EXPECT_EQ(count_events(r, EventKind::kAdd), 6);
  // Frame 3: observations go through the ELA gate and are reported as UPDATEs.
  s = step(r, test::all_ids(6));
  EXPECT_EQ(s.num_accepted, 6);
  EXPECT_EQ(count_events(r, EventKind::kUpdate), 6);
}

// candidate_history_frames (FilterHistory): once confirmed, a candidate's earlier
// sightings correct the robot as they would have had it been mapped at once. Six
// landmarks seen from frame 0, noisy, on a moving robot: after the confirming frame
// ela's filter is ekf's (which maps at first sighting) to rounding; without the
// history it is not (the candidates' first sightings corrected only themselves).
TEST_F(RobotPaths, WithHistoryAConfirmedCandidateCorrectsAsIfMappedAtOnce) {
  for (const int history : {2, 0}) {
    SCOPED_TRACE("candidate_history_frames " + std::to_string(history));
    RobotOptions o = test::robot_options(Mode::kEla);
    o.candidate_history_frames = history;
    Robot ela(o, 1), ekf(test::robot_options(Mode::kEkf), 1);
    std::mt19937_64 rng_a(11), rng_b(11);
    Pose2 truth{0.0, 0.0, 0.0}, odometer{0.0, 0.0, 0.0};
    for (int k = 0; k < 3; ++k) {
      ela.process(test::frame_from(k, truth, odometer, lms_, test::all_ids(6), &rng_a));
      ekf.process(test::frame_from(k, truth, odometer, lms_, test::all_ids(6), &rng_b));
      truth = compose(truth, Pose2{0.1, 0.0, 0.05});
      odometer = compose(odometer, Pose2{0.1, 0.002, 0.048});  // the odometer errs
    }
    for (int i = 0; i < 6; ++i) ASSERT_EQ(ela.lmap()[i].status, LandmarkStatus::kStatic) << "landmark " << i;
    // Compared by id (the two filters' slots may differ).
    const EkfSlam& a = ela.filter();
    const EkfSlam& b = ekf.filter();
    ASSERT_EQ(a.num_landmarks(), 6);
    ASSERT_EQ(b.num_landmarks(), 6);
    const double d = test::max_difference_by_id(a, b, 6);
    if (history > 0) {
      EXPECT_LT(d, 1e-12);
      EXPECT_EQ(ela.history().rebuilds(), 1);
      EXPECT_EQ(ela.history().upgraded(), 6);  // one earlier sighting each (frame 1)
    } else {
      EXPECT_GT(d, 1e-4);
    }
  }
}

TEST_F(RobotPaths, InconsistentCandidateIsReanchored) {
  Robot r(test::robot_options(Mode::kEla), 1);
  step(r, {0});
  step(r, {0});
  lms_[0] += Eigen::Vector2d(1.0, 0.0);  // jumps: the candidate starts over there
  step(r, {0});
  EXPECT_EQ(r.lmap()[0].consistent_sightings, 1);
  EXPECT_NEAR(r.lmap()[0].position.x(), lms_[0].x(), 1e-6);
  EXPECT_NEAR(r.filter().landmark(0).x(), lms_[0].x(), 1e-6);  // re-anchored in the filter
  EXPECT_EQ(r.lmap()[0].status, LandmarkStatus::kCandidate);
  // It keeps jumping: after moving_after inconsistent sightings it is reported MOVING.
  lms_[0] += Eigen::Vector2d(1.0, 0.0);
  step(r, {0});
  EXPECT_EQ(count_events(r, EventKind::kMoving, 0), 1);
  EXPECT_TRUE(r.lmap()[0].was_moving);
  lms_[0] += Eigen::Vector2d(1.0, 0.0);
  step(r, {0});
  EXPECT_EQ(count_events(r, EventKind::kMoving, 0), 0);  // reported once
}

TEST_F(RobotPaths, CandidateUnseenForAFrameLeavesTheFilterAndStartsOver) {
  Robot r(test::robot_options(Mode::kEla), 1);
  step(r, {0, 1});
  step(r, {0, 1});
  step(r, {0});
  EXPECT_FALSE(r.filter().has_landmark(1));
  EXPECT_EQ(r.lmap()[1].consistent_sightings, 0);
  step(r, {0, 1});
  EXPECT_EQ(r.lmap()[1].consistent_sightings, 1);
  EXPECT_TRUE(r.filter().has_landmark(1));
}

TEST_F(RobotPaths, CandidateKeepsItsStreakThroughGapsUpToCandidateGapFrames) {
  RobotOptions o = test::robot_options(Mode::kEla);
  o.candidate_gap_frames = 3;  // a sensor that reports a landmark only every few frames
  Robot r(o, 1);
  step(r, {0, 1});
  step(r, {0});
  step(r, {0});  // landmark 1 unseen for 2 frames: still a candidate
  EXPECT_TRUE(r.filter().has_landmark(1));
  step(r, {0, 1});
  EXPECT_EQ(r.lmap()[1].consistent_sightings, 2);
  for (int k = 0; k < 3; ++k) step(r, {0});  // unseen for 3 frames: starts over
  EXPECT_FALSE(r.filter().has_landmark(1));
  step(r, {0, 1});
  EXPECT_EQ(r.lmap()[1].consistent_sightings, 1);
}

TEST_F(RobotPaths, CandidateSightingsRefineTheCandidateButNotThePose) {
  for (const bool updates : {true, false}) {
    SCOPED_TRACE(updates ? "candidate_updates" : "inert candidates");
    RobotOptions o = test::robot_options(Mode::kEla);
    o.candidate_updates = updates;
    o.confirm_frames = 10;
    Robot r(o, 1);
    std::mt19937_64 rng(5);
    step(r, {0}, &rng);
    const double first = r.filter().landmark_cov(0).trace();
    const Pose2 pose = r.filter().pose();
    for (int k = 0; k < 5; ++k) step(r, {0}, &rng);
    EXPECT_EQ(r.lmap()[0].status, LandmarkStatus::kCandidate);
    EXPECT_EQ(r.filter().pose().x, pose.x);
    EXPECT_EQ(r.filter().pose().theta, pose.theta);
    if (updates) {
      // Six sightings: the candidate's variance falls towards 1/6 of one sighting's.
      EXPECT_LT(r.filter().landmark_cov(0).trace(), 0.3 * first);
      EXPECT_LT((r.filter().landmark(0) - lms_[0]).norm(), 0.05);
    } else {
      EXPECT_NEAR(r.filter().landmark_cov(0).trace(), first, 1e-12);
    }
  }
}

TEST_F(RobotPaths, LoneLandmarkThatFailsIsOnlySkippedWithoutLoneVerdicts) {
  for (const bool lone : {true, false}) {
    SCOPED_TRACE(lone ? "lone_verdicts on" : "lone_verdicts off");
    frame_ = 0;
    lms_ = test::ring(6, 3.0);
    RobotOptions o = test::robot_options(Mode::kEla);
    o.lone_verdicts = lone;
    o.missing_frames = 0;
    Robot r(o, 1);
    for (int k = 0; k < 3; ++k) step(r, {0});
    ASSERT_EQ(r.lmap()[0].status, LandmarkStatus::kStatic);
    // The only landmark in view jumps: it cannot be told from a pose error.
    lms_[0] += Eigen::Vector2d(0.0, 0.8);
    FrameSummary s = step(r, {0});
    EXPECT_EQ(s.num_rejected, 1);
    s = step(r, {0});
    EXPECT_EQ(s.num_rejected, 1);
    EXPECT_EQ(s.num_moving, lone ? 1 : 0);
    EXPECT_EQ(r.lmap()[0].status == LandmarkStatus::kStatic, !lone);
  }
}

TEST_F(RobotPaths, ReturnBackoffDoublesTheProbationOfARepeatMover) {
  RobotOptions o = test::robot_options(Mode::kEla);
  o.return_backoff = true;
  Robot r(o, 1);
  confirm_all(r);
  auto move_and_return = [&]() {
    lms_[2] += Eigen::Vector2d(0.0, 0.8);
    step(r, test::all_ids(6));
    lms_[2] += Eigen::Vector2d(0.0, 0.1);
    step(r, test::all_ids(6));
    EXPECT_EQ(count_events(r, EventKind::kMoving, 2), 1);
    for (int k = 0; k < 40; ++k) {
      step(r, test::all_ids(6));
      if (count_events(r, EventKind::kReturn, 2) == 1) return k;
    }
    return -1;
  };
  EXPECT_EQ(move_and_return(), 4);   // return_frames = 6 sightings (1 at the MOVING frame)
  EXPECT_EQ(r.lmap()[2].times_moving, 1);
  EXPECT_EQ(move_and_return(), 10);  // the second time: 12
  EXPECT_EQ(move_and_return(), 22);  // the third time: 24
}

// Robot 1 of `o` standing at the origin among 6 landmarks 3 m away, seeing them in
// frames 0, 1, 2, ... with noise drawn from a generator seeded with `seed`.
struct StandingRobot {
  StandingRobot(const RobotOptions& o, std::uint64_t seed) : robot(o, 1), rng(seed) {}
  FrameSummary step(const std::vector<int>& ids = test::all_ids(6)) {
    return robot.process(test::frame_from(frame++, pose, pose, lms, ids, &rng));
  }
  Robot robot;
  std::vector<Eigen::Vector2d> lms = test::ring(6, 3.0);
  std::mt19937_64 rng;
  const Pose2 pose{0.0, 0.0, 0.0};
  int frame = 0;
};

// The ELA options with the drift test of `drift_memory` (for candidates too when
// `candidate_drift`) and the missing rule off.
RobotOptions drift_options(double drift_memory, bool candidate_drift) {
  RobotOptions o = test::robot_options(Mode::kEla);
  o.drift_memory = drift_memory;
  o.candidate_drift_test = candidate_drift;
  o.missing_frames = 0;
  return o;
}

// A landmark creeping at 3 mm per frame (a tenth of the bearing noise at 3 m):
// every single test lets it through for a long time while the filter follows it;
// the drift test of its innovations catches it much sooner.
int frames_to_flag_creeper(double drift_memory, bool candidate_drift, int* flagged_static, double step = 0.003) {
  StandingRobot s(drift_options(drift_memory, candidate_drift), 11);
  const Robot& r = s.robot;
  while (s.frame < 10) s.step();
  const Eigen::Vector2d tangent = Eigen::Vector2d(-s.lms[2].y(), s.lms[2].x()).normalized();
  *flagged_static = 0;
  int found = -1;
  for (int k = 0; k < 150; ++k) {
    s.lms[2] += step * tangent;
    s.step();
    for (const MapEvent& e : r.events())
      if (e.kind == EventKind::kMoving) {
        if (e.landmark_id == 2 && found < 0) found = k;
        if (e.landmark_id != 2) ++*flagged_static;
      }
  }
  return found;
}

TEST(DriftTest, CatchesASlowMoverThatSingleTestsLetThrough) {
  int false_alarms = 0;
  const int single_only = frames_to_flag_creeper(0.0, false, &false_alarms);
  EXPECT_EQ(false_alarms, 0);
  const int with_drift = frames_to_flag_creeper(0.9, true, &false_alarms);
  EXPECT_EQ(false_alarms, 0);
  ASSERT_GE(with_drift, 0);
  RecordProperty("single_only", single_only);
  RecordProperty("with_drift", with_drift);
  // Measured: single tests only after 44 frames (0.13 m); the drift test after 21.
  EXPECT_TRUE(single_only < 0 || with_drift * 2 <= single_only) << single_only << " vs " << with_drift;
}

// The record of a sighting rejected by the drift test is the drift test's (its
// statistic |s|^2 (1 - lambda^2) and threshold), not the eq 16 test it passed.
TEST(DriftTest, ARejectionByTheDriftTestIsRecordedAsSuch) {
  const RobotOptions o = drift_options(0.9, true);
  StandingRobot s(o, 11);
  const Robot& r = s.robot;
  const Eigen::Vector2d tangent = Eigen::Vector2d(-s.lms[2].y(), s.lms[2].x()).normalized();
  int drift_records = 0;
  for (int frame = 0; frame < 60; ++frame) {
    if (frame >= 10) s.lms[2] += 0.003 * tangent;
    s.step();
    for (const GateRecord& g : r.gate_records()) {
      EXPECT_EQ(g.inside, g.d2 <= g.threshold) << to_string(g.kind) << " frame " << frame;
      if (g.kind != GateKind::kDrift) continue;
      ++drift_records;
      EXPECT_EQ(g.landmark_id, 2);
      EXPECT_DOUBLE_EQ(g.threshold, chi2_quantile(o.drift_gate_probability, 2));
    }
  }
  EXPECT_GT(drift_records, 0);
}

TEST(DriftTest, StaticLandmarksAreNotFlaggedByTheDriftTest) {
  // 6 static landmarks, noisy sightings for 1,000 frames: 6,000 drift tests at a
  // 1e-4 gate, strongly correlated over ~10 frames: no landmark may be flagged.
  StandingRobot s(drift_options(0.9, true), 3);
  const Robot& r = s.robot;
  int moving = 0;
  for (int k = 0; k < 1000; ++k) {
    s.step();
    for (const MapEvent& e : r.events()) moving += e.kind == EventKind::kMoving ? 1 : 0;
  }
  EXPECT_EQ(moving, 0);
  for (int id = 0; id < 6; ++id) EXPECT_EQ(r.lmap()[id].status, LandmarkStatus::kStatic);
}

// The paper's robots (config/paper.yaml, mode ela) in a static world, seeds
// first..last, every frame to every node; `tune` edits the config first, `each`
// sees every node after each of its frames.
template <class Tune, class Each>
void static_paper_world(int first, int last, Tune tune, Each each) {
  for (int seed = first; seed <= last; ++seed) {
    TeamConfig c = load_team_config(std::string(ELASLAM_SOURCE_DIR) + "/config/paper.yaml");
    c.robot.mode = Mode::kEla;
    c.scenario.seed = static_cast<std::uint64_t>(seed);
    c.scenario.dynamism_percent = 0.0;
    tune(&c);
    sim::World world(c.scenario);
    std::vector<RobotNode> nodes;
    for (int i = 0; i < world.num_robots(); ++i) nodes.emplace_back(c.robot, world.sensor_frame(i).robot_id);
    for (int k = 0; k < c.scenario.frames; ++k) {
      if (k > 0) world.step();
      for (int i = 0; i < world.num_robots(); ++i) {
        RobotNode& n = nodes[static_cast<std::size_t>(i)];
        n.on_sensor(sim::to_message(world.sensor_frame(i), k), 0);
        each(n, k == c.scenario.frames - 1);
      }
    }
  }
}

// The candidate's drift test sums its whitened innovations over its
// consistent sightings, and a candidate is refined by landmark-only (Schmidt)
// updates, under which the innovations need not be white (they share the pose's
// error): the sum's d2 need not be chi-square. Measured instead: the paper's robots
// in a static world (20 seeds x 3 robots x 300 frames, config/paper.yaml), every
// candidate and static test's record. No test may fire above its nominal rate
// (1 - ela_gate_probability = 1 %) by more than 4 binomial sigma; the eq-16 and
// single tests of static landmarks fire at it. Measured: candidate single test
// 1.30 %, candidate drift test 0.40 % (conservative), static tests 0.99 %.
TEST(DriftTest, InAStaticWorldNoTestFiresAboveItsNominalRate) {
  long cand = 0, cand_fail = 0, drift_fail = 0, stat = 0, stat_fail = 0;
  static_paper_world(101, 120, [](TeamConfig*) {}, [&](const RobotNode& n, bool) {
    for (const GateRecord& g : n.robot().gate_records()) {
      if (g.kind == GateKind::kCandidate) ++cand, cand_fail += !g.inside;
      if (g.kind == GateKind::kCandidateDrift) ++cand, ++drift_fail;
      if (g.kind == GateKind::kMulti || g.kind == GateKind::kInnovation || g.kind == GateKind::kDrift)
        ++stat, stat_fail += !g.inside;
    }
  });
  const double nominal = 1.0 - load_team_config(std::string(ELASLAM_SOURCE_DIR) + "/config/paper.yaml").robot.ela_gate_probability;
  const auto limit = [nominal](long n) { return nominal + 4.0 * std::sqrt(nominal * (1.0 - nominal) / static_cast<double>(n)); };
  ASSERT_GT(cand, 2000);
  const double cand_rate = static_cast<double>(cand_fail) / cand, drift_rate = static_cast<double>(drift_fail) / cand;
  const double stat_rate = static_cast<double>(stat_fail) / stat;
  EXPECT_LE(cand_rate, limit(cand));
  EXPECT_LE(drift_rate, limit(cand));
  EXPECT_NEAR(stat_rate, nominal, limit(stat) - nominal);
  RecordProperty("candidate_rate", std::to_string(cand_rate));
  RecordProperty("candidate_drift_rate", std::to_string(drift_rate));
  RecordProperty("static_rate", std::to_string(stat_rate));
}

TEST(DriftTest, ACreepingCandidateIsNotConfirmed) {
  for (const bool drift : {false, true}) {
    SCOPED_TRACE(drift ? "candidate drift test" : "single tests");
    RobotOptions o = test::robot_options(Mode::kEla);
    o.candidate_drift_test = drift;
    o.confirm_frames = 12;
    StandingRobot s(o, 4);
    bool confirmed = false;
    for (int k = 0; k < 12; ++k) {
      s.lms[0] += Eigen::Vector2d(0.0, 0.012);
      s.step({0});
      confirmed = confirmed || s.robot.lmap()[0].status == LandmarkStatus::kStatic;
    }
    EXPECT_EQ(confirmed, !drift);
  }
}

TEST_F(RobotPaths, StaticToMovingToCandidateAndBackAfterItStops) {
  for (Mode mode : {Mode::kEla, Mode::kConsensus}) {
    SCOPED_TRACE(to_string(mode));
    frame_ = 0;
    lms_ = test::ring(6, 3.0);
    Robot r(test::robot_options(mode), 1);
    confirm_all(r);
    // Landmark 2 moves 0.8 m: the first out-of-ELA verdict only rejects it ...
    lms_[2] += Eigen::Vector2d(0.0, 0.8);
    FrameSummary s = step(r, test::all_ids(6));
    EXPECT_EQ(s.num_rejected, 1);
    EXPECT_EQ(s.num_accepted, 5);
    EXPECT_TRUE(r.filter().has_landmark(2));
    // ... it keeps moving: the second makes it MOVING, out of the filter.
    lms_[2] += Eigen::Vector2d(0.0, 0.1);
    s = step(r, test::all_ids(6));
    EXPECT_EQ(s.num_moving, 1);
    EXPECT_NE(r.lmap()[2].status, LandmarkStatus::kStatic);
    EXPECT_EQ(count_events(r, EventKind::kMoving, 2), 1);
    EXPECT_EQ(r.lmap()[2].status, LandmarkStatus::kCandidate);
    EXPECT_TRUE(r.lmap()[2].was_moving);
    // It stops. After return_frames consistent sightings it comes back: RETURN.
    int returned_at = -1;
    for (int k = 0; k < 10 && returned_at < 0; ++k) {
      step(r, test::all_ids(6));
      if (count_events(r, EventKind::kReturn, 2) == 1) returned_at = k;
    }
    EXPECT_EQ(returned_at, 4);  // the MOVING frame anchored sighting 1; +5 more = 6
    EXPECT_EQ(r.lmap()[2].status, LandmarkStatus::kStatic);
    EXPECT_NEAR(r.filter().landmark(2).y(), lms_[2].y(), 0.05);
  }
}

TEST_F(RobotPaths, ExpectedButMissingIsMoving) {
  Robot r(test::robot_options(Mode::kEla), 1);
  confirm_all(r);
  // Landmark 4 (3 m away, inside 6 - 0.5 m) is not reported for 3 frames.
  std::vector<int> without = {0, 1, 2, 3, 5};
  step(r, without);
  step(r, without);
  EXPECT_TRUE(r.filter().has_landmark(4));
  const FrameSummary s = step(r, without);
  EXPECT_EQ(s.num_moving, 1);
  EXPECT_FALSE(r.filter().has_landmark(4));
  EXPECT_EQ(r.lmap()[4].status, LandmarkStatus::kMoving);
  EXPECT_EQ(count_events(r, EventKind::kMoving, 4), 1);
}

TEST_F(RobotPaths, MissingRuleIgnoresLandmarksOutsideTheExpectedView) {
  RobotOptions o = test::robot_options(Mode::kEla);
  o.sensor_range = 3.2;  // 3 m away is beyond 3.2 - 0.5: not expected in view
  Robot r(o, 1);
  confirm_all(r);
  for (int k = 0; k < 5; ++k) step(r, {0, 1, 2, 3, 5});
  EXPECT_TRUE(r.filter().has_landmark(4));
}

// A camera: the expected-but-missing rule looks only inside its cone, and with a
// detection probability below 1 waits until a miss run that long is as unlikely as
// a gate false alarm: (1 - 0.5)^n <= 0.01 -> n = 7 frames.
TEST_F(RobotPaths, MissingRuleWithAConeAndADetectionProbability) {
  RobotOptions o = test::robot_options(Mode::kEla);
  o.fov_half_angle = deg2rad(60.0);
  o.detection_probability = 0.5;
  Robot r(o, 1);
  confirm_all(r);  // the ring's landmarks at 0.1 + k * 60 deg: 0 (5.7 deg) ahead, 3 behind
  std::vector<int> without_0_and_3 = {1, 2, 4, 5};
  int moving_at = -1;
  for (int k = 0; k < 12 && moving_at < 0; ++k) {
    step(r, without_0_and_3);
    if (count_events(r, EventKind::kMoving, 0) == 1) moving_at = k;
  }
  EXPECT_EQ(moving_at, 6);  // the 7th frame without it
  EXPECT_TRUE(r.filter().has_landmark(3));  // behind the camera: never expected
  EXPECT_EQ(r.lmap()[3].status, LandmarkStatus::kStatic);
}

// ekf is the baseline that takes every landmark as static: a notice (another robot's
// finding, or main's body rule, main.body_radius_m) changes nothing in it.
TEST_F(RobotPaths, EkfIgnoresEveryNotice) {
  Robot r(test::robot_options(Mode::kEkf), 1);
  confirm_all(r);
  ASSERT_TRUE(r.filter().has_landmark(1));
  EXPECT_FALSE(r.apply_notice(1, frame_));
  EXPECT_TRUE(r.filter().has_landmark(1));
  EXPECT_EQ(r.lmap()[1].status, LandmarkStatus::kStatic);
}

TEST_F(RobotPaths, DynamicNoticeRemovesWithoutEventAndReturnNeedsReturnFrames) {
  Robot r(test::robot_options(Mode::kEla), 1);
  confirm_all(r);
  EXPECT_TRUE(r.apply_notice(1, frame_));
  EXPECT_FALSE(r.filter().has_landmark(1));
  EXPECT_EQ(r.lmap()[1].status, LandmarkStatus::kMoving);
  EXPECT_TRUE(r.events().empty() || count_events(r, EventKind::kMoving, 1) == 0);
  EXPECT_FALSE(r.apply_notice(1, frame_));  // not held any more
  int returned_at = -1;
  for (int k = 0; k < 10 && returned_at < 0; ++k) {
    step(r, test::all_ids(6));
    if (count_events(r, EventKind::kReturn, 1) == 1) returned_at = k;
  }
  EXPECT_EQ(returned_at, 5);  // six consistent sightings
}

// The bounded filter (Robot::make_room): two clusters of six landmarks 20 m apart
// and a filter of eight slots. The robot maps cluster A, drives to B (observing
// what is within its sensor range on the way), maps B, and drives back.
class BoundedFilter : public ::testing::Test {
 protected:
  BoundedFilter() : options_(test::robot_options(Mode::kEla)) {
    options_.ekf.capacity = 8;
    lms_ = test::ring(6, 3.0);
    for (const Eigen::Vector2d& p : test::ring(6, 3.0)) lms_.push_back(p + Eigen::Vector2d(20.0, 0.0));
  }
  /// One frame at x (true pose = odometer), observing every landmark within range.
  FrameSummary at(Robot& r, double x) {
    const Pose2 pose{x, 0.0, 0.0};
    std::vector<int> ids;
    for (std::size_t i = 0; i < lms_.size(); ++i)
      if ((lms_[i] - pose.translation()).norm() < options_.sensor_range) ids.push_back(static_cast<int>(i));
    const FrameSummary s = r.process(test::frame_from(frame_++, pose, pose, lms_, ids));
    EXPECT_LE(r.filter().num_landmarks(), 8) << "frame " << frame_ - 1;
    evicted_ += s.evicted;
    restored_ += s.restored;
    return s;
  }
  /// Stand at x for four frames (three confirm a candidate), then drive to x_to in 1 m steps.
  void map_then_drive(Robot& r, double x, double x_to) {
    for (int k = 0; k < 4; ++k) at(r, x);
    const double step = x_to > x ? 1.0 : -1.0;
    for (double p = x + step; step * (x_to - p) >= 0.0; p += step) at(r, p);
  }
  /// The highest id of cluster A that is archived, -1 when none is.
  static int an_archived(const Robot& r) {
    int id = -1;
    for (int k = 0; k < 6; ++k)
      if (r.lmap()[k].archived) id = k;
    return id;
  }
  RobotOptions options_;
  std::vector<Eigen::Vector2d> lms_;
  int frame_ = 0, evicted_ = 0, restored_ = 0;
};

TEST_F(BoundedFilter, TheFarthestLandmarksMakeRoomAndComeBackWhenSeenAgain) {
  Robot r(options_, 1);
  map_then_drive(r, 0.0, 20.0);
  // B's six arrive with two slots free: four of A left, each with an UPDATE of its
  // last estimate, and A stays STATIC in the L-map, archived with that estimate.
  EXPECT_EQ(evicted_, 4);
  int archived = 0;
  for (int id = 0; id < 6; ++id) {
    const LMapEntry& e = r.lmap()[id];
    EXPECT_EQ(e.status, LandmarkStatus::kStatic) << id;
    if (!e.archived) continue;
    ++archived;
    EXPECT_FALSE(r.filter().has_landmark(id));
    EXPECT_LT((e.position - lms_[static_cast<std::size_t>(id)]).norm(), 0.05) << id;
    EXPECT_GT(e.cov.trace(), 0.0);
  }
  EXPECT_EQ(archived, 4);
  for (int k = 0; k < 4; ++k) at(r, 20.0);  // B confirmed
  for (int id = 6; id < 12; ++id) EXPECT_EQ(r.lmap()[id].status, LandmarkStatus::kStatic) << id;
  // Back at A: the archived four re-enter the filter (B's farthest make room),
  // consistent with where they were: STATIC, no MOVING.
  int moving = 0;
  for (double p = 19.0; p >= 0.0; p -= 1.0) {
    at(r, p);
    moving += count_events(r, EventKind::kMoving);
  }
  EXPECT_EQ(restored_, 4);
  EXPECT_EQ(moving, 0);
  for (int id = 0; id < 6; ++id) {
    EXPECT_TRUE(r.filter().has_landmark(id)) << id;
    EXPECT_FALSE(r.lmap()[id].archived) << id;
    EXPECT_EQ(r.lmap()[id].status, LandmarkStatus::kStatic) << id;
  }
  EXPECT_GE(evicted_, 8);  // B's made room in turn
  EXPECT_LT((r.filter().pose().translation() - Eigen::Vector2d(0.0, 0.0)).norm(), 0.05);
}

TEST_F(BoundedFilter, ALandmarkThatMovedWhileArchivedIsFoundMovingWhenSeenAgain) {
  Robot r(options_, 1);
  map_then_drive(r, 0.0, 20.0);
  const int moved = an_archived(r);
  ASSERT_GE(moved, 0);
  lms_[static_cast<std::size_t>(moved)] += Eigen::Vector2d(0.0, 0.8);  // while the robot is away
  for (int k = 0; k < 4; ++k) at(r, 20.0);
  int found = 0;
  for (double p = 19.0; p >= 0.0; p -= 1.0) {
    at(r, p);
    found += count_events(r, EventKind::kMoving, moved);
    EXPECT_EQ(count_events(r, EventKind::kMoving) - count_events(r, EventKind::kMoving, moved), 0);
  }
  EXPECT_EQ(found, 1);
  EXPECT_FALSE(r.lmap()[moved].archived);
  EXPECT_EQ(r.lmap()[moved].status, LandmarkStatus::kCandidate);  // re-anchored where it is now
}

TEST_F(BoundedFilter, ANoticeAboutAnArchivedLandmarkTakesItOutOfTheMap) {
  Robot r(options_, 1);
  map_then_drive(r, 0.0, 20.0);
  const int id = an_archived(r);
  ASSERT_GE(id, 0);
  EXPECT_FALSE(r.apply_notice(id, frame_));  // not in the filter
  EXPECT_EQ(r.lmap()[id].status, LandmarkStatus::kMoving);
  EXPECT_FALSE(r.lmap()[id].archived);
}

// Nothing in view is ever given up: with every held landmark within sensor range,
// an add fails and says so (filter_full), the filter unchanged.
TEST_F(BoundedFilter, WhenEverythingHeldIsInRangeTheAddFailsLoudly) {
  options_.ekf.capacity = 4;
  Robot r(options_, 1);
  const FrameSummary s = at(r, 0.0);  // six new candidates, four slots, all in view
  EXPECT_EQ(s.evicted, 0);
  EXPECT_EQ(s.filter_full, 2);
  EXPECT_EQ(r.filter().num_landmarks(), 4);
}

TEST_F(RobotPaths, EkfModeAddsAtOnceAndNeverRemoves) {
  Robot r(test::robot_options(Mode::kEkf), 1);
  FrameSummary s = step(r, test::all_ids(6));
  EXPECT_EQ(s.num_added, 6);
  lms_[2] += Eigen::Vector2d(2.0, 0.0);
  s = step(r, test::all_ids(6));
  EXPECT_EQ(s.num_accepted, 6);
  EXPECT_EQ(s.num_rejected, 0);
  EXPECT_TRUE(r.filter().has_landmark(2));
}

TEST_F(RobotPaths, GatedModeRejectsAnOutlierButKeepsTheLandmark) {
  Robot r(test::robot_options(Mode::kGated), 1);
  step(r, test::all_ids(6));
  lms_[2] += Eigen::Vector2d(2.0, 0.0);
  const FrameSummary s = step(r, test::all_ids(6));
  EXPECT_EQ(s.num_rejected, 1);
  EXPECT_EQ(s.num_accepted, 5);
  EXPECT_TRUE(r.filter().has_landmark(2));
  const auto& g = r.gate_records();
  const auto it = std::find_if(g.begin(), g.end(), [](const GateRecord& x) { return x.landmark_id == 2; });
  ASSERT_NE(it, g.end());
  EXPECT_FALSE(it->inside);
  EXPECT_GT(it->d2, it->threshold);
}

TEST_F(RobotPaths, EveryTestedObservationKeepsItsNumbers) {
  Robot r(test::robot_options(Mode::kEla), 1);
  confirm_all(r);
  std::mt19937_64 rng(2);
  step(r, test::all_ids(6), &rng);
  ASSERT_EQ(r.gate_records().size(), 6u);
  for (const GateRecord& g : r.gate_records()) {
    EXPECT_EQ(g.kind, GateKind::kMulti);
    EXPECT_GT(g.threshold, 9.0);  // chi2(0.99, 2) = 9.21
    EXPECT_EQ(g.inside, g.d2 <= g.threshold);
  }
}

}  // namespace
}  // namespace elaslam

namespace elaslam {
namespace {

// The consistency monitor: a robot whose odometer lies (a 0.5 m jump it
// did not drive, with the confidence of a normal increment) keeps correcting with
// innovations far beyond their covariance (eq 16 cancels a position error, so the
// landmarks are accepted). The monitor finds the filter inconsistent within its
// window; with recovery the pose covariance widens once and the landmarks pull the
// pose back at once, where without it the error decays over tens of frames.
TEST(Consistency, ALostRobotSaysSoAndRecovers) {
  double error_at_45[2] = {0, 0};
  for (bool recover : {false, true}) {
    RobotOptions o = test::robot_options(Mode::kEla);
    o.consistency_window_frames = 20;
    o.consistency_recover = recover;
    Robot r(o, 1);
    const Pose2 truth{0.0, 0.0, 0.0};
    const auto lms = test::ring(8, 4.0);
    std::mt19937_64 rng(3);
    Pose2 odometer = truth;
    int inconsistent = 0, recovered = 0, first = -1;
    for (int f = 0; f < 80; ++f) {
      if (f == 30) odometer = Pose2{0.4, 0.3, 0.0};
      const FrameSummary s = r.process(test::frame_from(f, truth, odometer, lms, test::all_ids(8), &rng));
      inconsistent += s.inconsistent;
      recovered += s.recovered;
      if (s.inconsistent && first < 0) first = f;
      if (f < 30) {
        EXPECT_FALSE(s.inconsistent) << f;  // consistent until the lie
      }
      if (f == 45) error_at_45[recover ? 1 : 0] = std::hypot(r.filter().pose().x, r.filter().pose().y);
    }
    EXPECT_GE(first, 30);
    EXPECT_LE(first, 35) << "found within a few frames of the lie";
    if (recover) {
      EXPECT_EQ(recovered, 1);  // once: the window starts over and stays consistent
      EXPECT_EQ(inconsistent, 1);
    } else {
      EXPECT_EQ(recovered, 0);
      EXPECT_GT(inconsistent, 20);  // it stays inconsistent while the error decays
    }
  }
  EXPECT_GT(error_at_45[0], 0.1);   // without recovery: still 0.14 m off
  EXPECT_LT(error_at_45[1], 0.03);  // with it: back within 1 cm
}

// The node says it: FAULT_INCONSISTENT in STATUS and one alert line, with the counters.
TEST(Consistency, TheNodeRaisesFaultInconsistentAndAlertsOnce) {
  RobotOptions o = test::robot_options(Mode::kEla);
  o.consistency_window_frames = 20;
  o.consistency_recover = true;
  RobotNode node(o, 1);
  const auto lms = test::ring(8, 4.0);
  std::mt19937_64 rng(3);
  Pose2 odometer{0.0, 0.0, 0.0};
  std::string alert;
  for (int f = 0; f < 40; ++f) {
    if (f == 30) odometer = Pose2{0.4, 0.3, 0.0};
    node.on_sensor(test::to_msg(test::frame_from(f, Pose2{}, odometer, lms, test::all_ids(8), &rng), 1), 0);
    const std::string a = node.take_alert();
    if (!a.empty()) alert += a + "\n";
    if (f == 29) {
      EXPECT_EQ(node.status_msg(0).fault_flags & node_status_t::FAULT_INCONSISTENT, 0);
    }
  }
  EXPECT_NE(node.status_msg(0).fault_flags & node_status_t::FAULT_INCONSISTENT, 0);
  EXPECT_EQ(node.counters().inconsistent_frames, 1);
  EXPECT_EQ(node.counters().recoveries, 1);
  EXPECT_NE(alert.find("robot 1 filter inconsistent"), std::string::npos) << alert;
  EXPECT_NE(alert.find("pose covariance widened"), std::string::npos) << alert;
}

// In a static world the monitor stays quiet: the paper's robots, 10 seeds x 3
// robots x 300 frames, a 50-frame window at 0.9999: no frame found inconsistent
// (measured: 0 of 4,500). (With movers it fires: 2.8 % of frames at 50 %
// dynamism, 44 % at 80 %, the movers' innovations being accepted before they are
// found; so config/paper.yaml leaves it off, docs/adr/0017-consistency-monitor.md.)
TEST(Consistency, InAStaticWorldTheMonitorStaysQuiet) {
  long frames = 0, inconsistent = 0;
  const auto tune = [](TeamConfig* c) {
    c->robot.consistency_window_frames = 50;
    c->robot.consistency_probability = 0.9999;
  };
  static_paper_world(101, 110, tune, [&](const RobotNode& n, bool last) {
    if (!last) return;
    frames += n.counters().frames;
    inconsistent += n.counters().inconsistent_frames;
    EXPECT_EQ(n.status_msg(0).fault_flags & node_status_t::FAULT_INCONSISTENT, 0);
  });
  EXPECT_EQ(frames, 4500);
  EXPECT_LE(inconsistent, frames / 200);
}

// The frame's NIS that POSE carries (nis, nis_dof): in a static world the paper's
// robots' corrections are consistent, so sum(nis) / sum(nis_dof) is about 1
// (5 seeds x 3 robots, config/paper.yaml; measured 0.970 over 38,258 dof); each frame
// counts 2 dof per correction of a mapped landmark, at most 2 x num_accepted.
TEST(Consistency, ThePoseCarriesTheFramesNisAndItIsConsistentInAStaticWorld) {
  double nis = 0.0;
  long dof = 0, frames_with = 0;
  static_paper_world(101, 105, [](TeamConfig*) {}, [&](const RobotNode& n, bool) {
    const pose_estimate_t& p = n.pose_msg();
    EXPECT_EQ(p.nis_dof % 2, 0);
    EXPECT_LE(p.nis_dof, 2 * p.num_accepted);
    EXPECT_GE(p.nis, 0.0);
    if (p.nis_dof == 0) {
      EXPECT_EQ(p.nis, 0.0);
    }
    nis += p.nis;
    dof += p.nis_dof;
    frames_with += p.nis_dof > 0;
  });
  ASSERT_GT(frames_with, 2000);
  ASSERT_GT(dof, 30000);
  EXPECT_GT(nis / static_cast<double>(dof), 0.85);
  EXPECT_LT(nis / static_cast<double>(dof), 1.2);
}

// After an odometer lie the frame's NIS jumps far beyond its degrees of freedom.
TEST(Consistency, AnOdometerLieShowsInTheFramesNis) {
  Robot r(test::robot_options(Mode::kEla), 1);
  const auto lms = test::ring(8, 4.0);
  std::mt19937_64 rng(3);
  Pose2 odometer{0.0, 0.0, 0.0};
  for (int f = 0; f < 31; ++f) {
    if (f == 30) odometer = Pose2{0.4, 0.3, 0.0};
    const FrameSummary s = r.process(test::frame_from(f, Pose2{}, odometer, lms, test::all_ids(8), &rng));
    EXPECT_EQ(s.nis, r.consistency().frame_nis());
    EXPECT_EQ(s.nis_dof, r.consistency().frame_dof());
    if (f >= 5 && f < 30) {
      EXPECT_EQ(s.num_accepted + s.num_rejected, 8) << f;  // the eight landmarks, mapped
      EXPECT_EQ(s.nis_dof, 2 * s.num_accepted) << f;
      EXPECT_LT(s.nis, 40.0) << f;  // chi-square with 16 dof: 40 is its 0.9992 quantile
    }
    if (f == 30) {
      EXPECT_GT(s.nis, 500.0) << s.nis_dof;
    }
  }
}

// Frames 1-9 missed: frame 10's odometer increment spans ten frames, and the
// prediction adds their noise compounded along the arc (gap_odometry_covariance),
// not one frame's noise over the chord.
TEST(RobotGap, AnIncrementOverMissedFramesCarriesTheirCompoundedNoise) {
  const OdometryNoise noise{0.0085, 0.0094, 0.0079};
  const Pose2 start{1.0, 2.0, 0.5};
  Pose2 odometer = start;
  for (int i = 0; i < 10; ++i) odometer = compose(odometer, Pose2{0.1, 0.0, 0.05});
  for (int gap : {1, 10}) {
    Robot r(test::robot_options(Mode::kEla), 1);
    FrameInput in = test::frame_from(0, start, start, {}, {});
    in.noise = noise;
    r.process(in);
    const Eigen::Matrix3d P0 = r.filter().pose_cov();
    in.frame = gap;
    in.odometer = odometer;
    r.process(in);
    const Pose2 increment = between(start, odometer);
    Eigen::Matrix3d F_x, F_u;
    motion(start, increment, &F_x, &F_u);
    const Eigen::Matrix3d expected = F_x * P0 * F_x.transpose() + F_u * gap_odometry_covariance(increment, gap, noise) * F_u.transpose();
    EXPECT_LT((r.filter().pose_cov() - expected).cwiseAbs().maxCoeff(), 1e-12) << gap << "\n" << r.filter().pose_cov();
    if (gap == 10) {  // more than the chord's one-frame noise, across the path
      const Eigen::Matrix3d chord = F_x * P0 * F_x.transpose() + F_u * odometry_covariance(increment, noise) * F_u.transpose();
      const double position = r.filter().pose_cov().topLeftCorner<2, 2>().trace();
      const double chord_position = chord.topLeftCorner<2, 2>().trace();
      EXPECT_GT(position, 1.2 * chord_position);
    }
  }
}

// robot.ela.lone_needs_check. A robot drives along x with exact odometry and sees
// one landmark alone, which stands for its three confirming sightings and then
// creeps along y at 1 cm per frame (a robot driving by, as in MRCLAM). Without the
// rule it corrects the pose every frame and drags it along; with it the landmark
// corrects only with the sighting that confirms it, having never agreed with
// another landmark. Once it has agreed with another in a frame (checked), it
// corrects alone too.
TEST(RobotLone, ALandmarkOnlyEverSeenAloneDoesNotDragThePose) {
  for (bool rule : {false, true}) {
    SCOPED_TRACE(rule ? "lone_needs_check on" : "lone_needs_check off");
    RobotOptions o = test::robot_options(Mode::kEla);
    o.lone_needs_check = rule;
    o.lone_verdicts = false;
    o.drift_memory = 0.0;  // the creep is for the pose to follow, not for a test to catch
    Robot r(o, 1);
    std::vector<Eigen::Vector2d> lms{{3.0, 0.5}};
    Pose2 truth;
    int corrections = 0;
    for (int f = 0; f < 80; ++f) {
      truth.x = 0.02 * f;
      if (f >= 3) lms[0].y() += 0.01;
      FrameInput in = test::frame_from(f, truth, truth, lms, {0});
      in.noise = {1e-3, 1e-3, 1e-3};
      corrections += r.process(in).num_accepted;
    }
    const double error = std::hypot(r.filter().pose().x - truth.x, r.filter().pose().y - truth.y);
    if (rule) {
      EXPECT_EQ(corrections, 1);  // the sighting that confirms it (Robot::confirm), before it creeps
      EXPECT_LT(error, 1e-9);
      EXPECT_FALSE(r.lmap()[0].checked);
    } else {
      EXPECT_GT(corrections, 70);
      EXPECT_GT(error, 0.1);  // dragged along with the landmark
    }
  }
  // Seen once with a second landmark that agrees, it is checked and corrects alone.
  RobotOptions o = test::robot_options(Mode::kEla);
  o.lone_needs_check = true;
  Robot r(o, 1);
  const std::vector<Eigen::Vector2d> lms{{3.0, 0.5}, {2.0, -1.0}};
  for (int f = 0; f < 3; ++f) r.process(test::frame_from(f, Pose2{}, Pose2{}, lms, {0}));
  ASSERT_EQ(r.lmap()[0].status, LandmarkStatus::kStatic);
  EXPECT_EQ(r.process(test::frame_from(3, Pose2{}, Pose2{}, lms, {0})).num_unchecked, 1);
  for (int f = 4; f < 7; ++f) r.process(test::frame_from(f, Pose2{}, Pose2{}, lms, {0, 1}));  // 1 confirmed
  EXPECT_FALSE(r.lmap()[0].checked);  // 1 was a candidate, not in eq 16's view
  r.process(test::frame_from(7, Pose2{}, Pose2{}, lms, {0, 1}));
  EXPECT_TRUE(r.lmap()[0].checked);
  EXPECT_TRUE(r.lmap()[1].checked);
  const FrameSummary alone = r.process(test::frame_from(8, Pose2{}, Pose2{}, lms, {0}));
  EXPECT_EQ(alone.num_accepted, 1);
  EXPECT_EQ(alone.num_unchecked, 0);
}

}  // namespace
}  // namespace elaslam

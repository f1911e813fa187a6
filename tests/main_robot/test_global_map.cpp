// SPDX-License-Identifier: Apache-2.0
// The global map: fusion, MOVING / RETURN, event ordering, snapshot repair,
// persistence, and message validation.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "../support/messages.hpp"
#include "elaslam/main_robot/main_node.hpp"
#include "global_event.hpp"

namespace elaslam {
namespace {

GlobalMapOptions options(Fusion f = Fusion::kInformation) {
  GlobalMapOptions o;
  o.max_landmark_id = 32;
  o.fusion = f;
  return o;
}

GlobalEvent ev(int robot, std::int64_t seq, int kind, int id, double x = 0, double y = 0, double var = 0.01,
               int frame = 0) {
  return test::global_event(robot, seq, kind, id, {x, y}, Eigen::Matrix2d::Identity() * var, frame);
}

TEST(GlobalMap, InformationFusionMatchesClosedForm) {
  GlobalMap m(options());
  GlobalEvent a = ev(1, 1, landmark_event_t::ADD, 3, 1.0, 2.0);
  a.cov << 0.04, 0.01, 0.01, 0.09;
  GlobalEvent b = ev(2, 1, landmark_event_t::ADD, 3, 1.2, 1.9);
  b.cov << 0.02, -0.005, -0.005, 0.03;
  m.apply(a, nullptr);
  m.apply(b, nullptr);
  const Eigen::Matrix2d I = a.cov.inverse() + b.cov.inverse();
  const Eigen::Matrix2d C = I.inverse();
  const Eigen::Vector2d p = C * (a.cov.inverse() * a.position + b.cov.inverse() * b.position);
  const GlobalEntry& g = m.entry(3);
  EXPECT_EQ(g.status, GlobalStatus::kStatic);
  EXPECT_EQ(g.contributors(), 0b11);
  EXPECT_TRUE(g.fused.isApprox(p, 1e-12));
  EXPECT_TRUE(g.fused_cov.isApprox(C, 1e-12));
}

TEST(GlobalMap, CovarianceIntersectionIsConsistentAndNoTighterThanEither) {
  GlobalMap m(options(Fusion::kCovarianceIntersection));
  m.apply(ev(1, 1, landmark_event_t::ADD, 3, 1.0, 2.0, 0.04), nullptr);
  m.apply(ev(2, 1, landmark_event_t::ADD, 3, 1.2, 2.0, 0.01), nullptr);
  const GlobalEntry& g = m.entry(3);
  // Weights 0.2 / 0.8 by trace: info = 0.2/0.04 + 0.8/0.01 = 85 per axis.
  EXPECT_NEAR(g.fused_cov(0, 0), 1.0 / 85.0, 1e-12);
  EXPECT_NEAR(g.fused.x(), (0.2 / 0.04 * 1.0 + 0.8 / 0.01 * 1.2) / 85.0, 1e-12);
  // CI never claims more information than the sum of the two.
  EXPECT_GT(g.fused_cov(0, 0), 1.0 / (1.0 / 0.04 + 1.0 / 0.01));
}

TEST(GlobalMap, MovingRemovesNotifiesOnceAndReturnLetsBack) {
  GlobalMap m(options());
  std::vector<Notice> notices;
  m.apply(ev(1, 1, landmark_event_t::ADD, 5, 1, 1), &notices);
  m.apply(ev(2, 1, landmark_event_t::ADD, 5, 1.1, 1), &notices);
  const auto v0 = m.version();
  m.apply(ev(2, 2, landmark_event_t::MOVING, 5, 0, 0, 0, 7), &notices);
  ASSERT_EQ(notices.size(), 1u);
  EXPECT_EQ(notices[0].landmark_id, 5);
  EXPECT_EQ(notices[0].detected_by, 2);
  EXPECT_EQ(notices[0].frame, 7);
  EXPECT_EQ(m.entry(5).status, GlobalStatus::kMoving);
  EXPECT_EQ(m.entry(5).contributors(), 0);  // deleted from the map
  EXPECT_GT(m.version(), v0);
  // Another robot's MOVING for the same landmark: idempotent, no second notice.
  m.apply(ev(1, 2, landmark_event_t::MOVING, 5), &notices);
  EXPECT_EQ(notices.size(), 1u);
  // A stale UPDATE while MOVING is kept aside but does not bring it back.
  m.apply(ev(3, 1, landmark_event_t::UPDATE, 5, 2, 2), &notices);
  EXPECT_EQ(m.entry(5).status, GlobalStatus::kMoving);
  // RETURN lets it back, with the RETURN's estimate only: the UPDATE sent while it
  // was MOVING may be of where it was before, so it is not fused.
  m.apply(ev(1, 3, landmark_event_t::RETURN, 5, 3, 3, 0.01, 20), &notices);
  EXPECT_EQ(m.entry(5).status, GlobalStatus::kStatic);
  EXPECT_EQ(m.entry(5).status_frame, 20);
  EXPECT_EQ(m.entry(5).contributors(), 0b001);
  EXPECT_TRUE(m.entry(5).fused.isApprox(Eigen::Vector2d(3, 3), 1e-12)) << m.entry(5).fused.transpose();
  // Robot 3's next estimate, after the RETURN, counts again.
  m.apply(ev(3, 2, landmark_event_t::UPDATE, 5, 3.2, 3, 0.01, 21), &notices);
  EXPECT_EQ(m.entry(5).contributors(), 0b101);
}

TEST(GlobalMap, DuplicatesAndReorderedEventsAreIgnored) {
  GlobalMap m(options());
  EXPECT_EQ(m.apply(ev(1, 1, landmark_event_t::ADD, 2, 1, 1), nullptr), EventResult::kApplied);
  EXPECT_EQ(m.apply(ev(1, 2, landmark_event_t::UPDATE, 2, 2, 2), nullptr), EventResult::kApplied);
  const auto v = m.version();
  EXPECT_EQ(m.apply(ev(1, 2, landmark_event_t::UPDATE, 2, 9, 9), nullptr), EventResult::kDuplicate);
  EXPECT_EQ(m.apply(ev(1, 1, landmark_event_t::ADD, 2, 9, 9), nullptr), EventResult::kStale);
  EXPECT_EQ(m.version(), v);
  EXPECT_DOUBLE_EQ(m.entry(2).fused.x(), 2.0);
  EXPECT_EQ(m.stream(1).duplicates, 2);
}

TEST(GlobalMap, GapIsNotedAndRepairedBySnapshot) {
  GlobalMap m(options());
  std::vector<Notice> notices;
  m.apply(ev(1, 1, landmark_event_t::ADD, 2, 1, 1), &notices);
  m.apply(ev(1, 2, landmark_event_t::ADD, 4, 4, 4), &notices);
  // seq 3 (a MOVING of 4) and 4 (ADD of 6) are lost; seq 5 arrives.
  EXPECT_EQ(m.apply(ev(1, 5, landmark_event_t::UPDATE, 2, 1.5, 1), &notices), EventResult::kAppliedAfterGap);
  EXPECT_TRUE(m.stream(1).gap_pending);
  EXPECT_EQ(m.entry(4).status, GlobalStatus::kStatic);  // not yet known to move
  // The snapshot: robot 1 holds 2 and 6, and 4 as moving.
  std::vector<std::pair<int, RobotEstimate>> lms = {
      {2, RobotEstimate{true, {1.6, 1.0}, Eigen::Matrix2d::Identity() * 0.01, 10}},
      {6, RobotEstimate{true, {6.0, 6.0}, Eigen::Matrix2d::Identity() * 0.01, 10}}};
  m.apply_snapshot(1, 5, 10, lms, {4}, &notices);
  EXPECT_FALSE(m.stream(1).gap_pending);
  EXPECT_EQ(m.entry(4).status, GlobalStatus::kMoving);
  ASSERT_EQ(notices.size(), 1u);
  EXPECT_EQ(notices[0].landmark_id, 4);
  EXPECT_EQ(m.entry(6).status, GlobalStatus::kStatic);
  EXPECT_DOUBLE_EQ(m.entry(2).fused.x(), 1.6);
  // Events covered by the snapshot are stale now.
  EXPECT_EQ(m.apply(ev(1, 4, landmark_event_t::ADD, 6, 9, 9), &notices), EventResult::kStale);
}

RobotEstimate held(double x, double y, int frame) {
  return RobotEstimate{true, {x, y}, Eigen::Matrix2d::Identity() * 0.01, frame};
}

// A gap not yet repaired when main_robot restarts from its state file is repaired
// after it: the snapshot's moving list still stands in for the lost MOVING (the
// pending repair was not saved, and the list was ignored). And an older snapshot
// than the last one applied is still refused after the restart.
TEST(GlobalMap, APendingGapRepairSurvivesARestart) {
  GlobalMap m(options());
  std::vector<Notice> notices;
  m.apply(ev(1, 1, landmark_event_t::ADD, 4, 4, 4), &notices);
  m.apply(ev(2, 1, landmark_event_t::ADD, 4, 4.1, 4), &notices);
  m.apply_snapshot(1, 1, 5, {{4, held(4, 4, 5)}}, {}, &notices);
  // Robot 1's seq 2 (MOVING of 4) is lost; seq 3 arrives: a gap.
  EXPECT_EQ(m.apply(ev(1, 3, landmark_event_t::ADD, 6, 6, 6), &notices), EventResult::kAppliedAfterGap);
  ASSERT_TRUE(m.stream(1).gap_pending);
  GlobalMap restarted(options());
  std::string why;
  ASSERT_TRUE(restarted.from_json(m.to_json(), &why)) << why;
  EXPECT_TRUE(restarted.stream(1).gap_pending);
  EXPECT_EQ(restarted.to_json(), m.to_json());
  const int n = options().max_landmark_id;
  EXPECT_FALSE(restarted.apply_snapshot(1, 1, 4, 0, n, {{4, held(4, 4, 4)}}, {}, {}, &notices));  // older: refused
  notices.clear();
  EXPECT_TRUE(restarted.apply_snapshot(1, 3, 12, 0, n, {{6, held(6, 6, 12)}}, {4}, {9}, &notices));
  EXPECT_EQ(restarted.entry(4).status, GlobalStatus::kMoving);
  ASSERT_EQ(notices.size(), 1u);
  EXPECT_EQ(notices[0].landmark_id, 4);
  EXPECT_FALSE(restarted.stream(1).gap_pending);
}

// A restarted main_robot (empty, no state file) rebuilds from the robots' first
// snapshots: a moving id that no robot holds here is an opinion of unknown age,
// set moving without a notice, and any robot's static holding takes it back.
TEST(GlobalMap, RestartWithoutStateTakesSnapshotMovingListsAsUnconfirmed) {
  GlobalMap m(options());
  std::vector<Notice> notices;
  // Robot 1's first snapshot (seq 40: ahead of anything seen) lists 5 as moving.
  m.apply_snapshot(1, 40, 60, {{2, held(1, 1, 60)}}, {5}, &notices);
  EXPECT_EQ(m.entry(5).status, GlobalStatus::kMoving);
  EXPECT_TRUE(m.entry(5).moving_unconfirmed);
  EXPECT_TRUE(notices.empty());  // no notice for an opinion of unknown age
  EXPECT_EQ(m.entry(2).status, GlobalStatus::kStatic);
  // Robot 2 holds 5 static in its snapshot of a later frame: it is static again.
  m.apply_snapshot(2, 30, 61, {{5, held(5, 5, 61)}}, {}, &notices);
  EXPECT_EQ(m.entry(5).status, GlobalStatus::kStatic);
  EXPECT_FALSE(m.entry(5).moving_unconfirmed);
  EXPECT_TRUE(notices.empty());
}

// A robot's MOVING event for a landmark that only a snapshot's opinion of unknown age
// had as moving confirms it: the other robots are told now (no notice went out for
// the opinion), with this finding's frame and finder.
TEST(GlobalMap, AMovingEventConfirmsAnUnconfirmedEntryAndTellsTheRobots) {
  GlobalMap m(options());
  std::vector<Notice> notices;
  m.apply_snapshot(1, 40, 60, {{2, held(1, 1, 60)}}, {5}, &notices);
  ASSERT_TRUE(m.entry(5).moving_unconfirmed);
  ASSERT_TRUE(notices.empty());
  const std::int64_t version = m.version();
  m.apply(ev(2, 1, landmark_event_t::MOVING, 5, 0, 0, 0, 70), &notices);
  EXPECT_FALSE(m.entry(5).moving_unconfirmed);
  EXPECT_EQ(m.entry(5).moving_by, 2);
  EXPECT_EQ(m.entry(5).status_frame, 70);
  ASSERT_EQ(notices.size(), 1u);
  EXPECT_EQ(notices[0].landmark_id, 5);
  EXPECT_EQ(notices[0].detected_by, 2);
  EXPECT_EQ(notices[0].frame, 70);
  EXPECT_GT(m.version(), version);
  // Once confirmed, a further finding is idempotent again.
  m.apply(ev(3, 1, landmark_event_t::MOVING, 5, 0, 0, 0, 71), &notices);
  EXPECT_EQ(notices.size(), 1u);
  EXPECT_EQ(m.entry(5).moving_by, 2);
}

// After a gap: robot r's MOVING was lost when r held the landmark here, or when the
// landmark never moved as far as this map knows (notice either way); r's listing is
// left alone when the landmark moved before and another robot holds it static
// again (r lists it as moving until it sees it again: possibly stale); and a
// landmark moving here that r holds static was taken back by r (RETURN lost).
TEST(GlobalMap, FirstSnapshotAfterAGapRecoversLostMovingAndReturn) {
  GlobalMap m(options());
  std::vector<Notice> notices;
  m.apply(ev(1, 1, landmark_event_t::ADD, 3, 3, 3, 0.01, 1), &notices);
  m.apply(ev(2, 1, landmark_event_t::ADD, 4, 4, 4, 0.01, 1), &notices);
  m.apply(ev(1, 2, landmark_event_t::ADD, 6, 6, 6, 0.01, 1), &notices);
  m.apply(ev(2, 2, landmark_event_t::ADD, 7, 7, 7, 0.01, 1), &notices);
  m.apply(ev(2, 3, landmark_event_t::MOVING, 4, 0, 0, 0, 3), &notices);     // 4 moved ...
  m.apply(ev(2, 4, landmark_event_t::RETURN, 4, 4, 5, 0.01, 8), &notices);  // ... and came back
  m.apply(ev(2, 5, landmark_event_t::MOVING, 6, 0, 0, 0, 5), &notices);     // 6 moving since frame 5
  ASSERT_EQ(notices.size(), 2u);
  notices.clear();
  // Robot 1's events 3..9 are lost (main_robot down); its snapshot of frame 20
  // lists 3 (it held it), 4 (moved before, robot 2 holds it again) and 7 (never
  // moved, robot 2 holds it) as moving, and holds 6.
  m.apply_snapshot(1, 9, 20, {{6, held(6.1, 6, 20)}}, {3, 4, 7}, &notices);
  EXPECT_EQ(m.entry(3).status, GlobalStatus::kMoving);
  EXPECT_EQ(m.entry(7).status, GlobalStatus::kMoving);
  ASSERT_EQ(notices.size(), 2u);
  EXPECT_EQ(notices[0].detected_by, 1);
  EXPECT_EQ(m.entry(4).status, GlobalStatus::kStatic);  // possibly stale listing: left alone
  EXPECT_EQ(m.entry(6).status, GlobalStatus::kStatic);  // robot 1 took it back: RETURN was lost
  EXPECT_EQ(m.entry(6).status_frame, 20);
  // Without a gap a snapshot's moving list changes nothing.
  notices.clear();
  m.apply(ev(1, 10, landmark_event_t::UPDATE, 6, 6.1, 6, 0.01, 21), &notices);
  m.apply_snapshot(1, 10, 21, {{6, held(6.1, 6, 21)}}, {4}, &notices);
  EXPECT_EQ(m.entry(4).status, GlobalStatus::kStatic);
  EXPECT_TRUE(notices.empty());
}

TEST(GlobalMap, SnapshotReplacesThatRobotsContributionWholesale) {
  GlobalMap m(options());
  m.apply(ev(1, 1, landmark_event_t::ADD, 2, 1, 1), nullptr);
  m.apply(ev(2, 1, landmark_event_t::ADD, 2, 3, 1), nullptr);
  m.apply(ev(1, 2, landmark_event_t::ADD, 7, 7, 7), nullptr);
  m.apply_snapshot(1, 2, 10, {{2, RobotEstimate{true, {1.0, 1.0}, Eigen::Matrix2d::Identity() * 0.01, 10}}}, {},
                   nullptr);
  EXPECT_EQ(m.entry(2).contributors(), 0b11);
  EXPECT_EQ(m.entry(7).contributors(), 0);  // robot 1 no longer holds 7
  EXPECT_EQ(m.entry(2).by_robot[1].position.x(), 3.0);  // robot 2 untouched
}

TEST(GlobalMap, PersistenceRoundTripAndRestart) {
  GlobalMap m(options());
  std::vector<Notice> n;
  m.apply(ev(1, 1, landmark_event_t::ADD, 2, 1, 1), &n);
  m.apply(ev(2, 1, landmark_event_t::ADD, 2, 1.2, 1.1), &n);
  m.apply(ev(2, 2, landmark_event_t::ADD, 9, -3, 4), &n);
  m.apply(ev(1, 2, landmark_event_t::MOVING, 9, 0, 0, 0, 12), &n);
  const std::string text = m.to_json();
  GlobalMap restarted(options());
  std::string why;
  ASSERT_TRUE(restarted.from_json(text, &why)) << why;
  EXPECT_EQ(restarted.version(), m.version());
  EXPECT_EQ(restarted.to_json(), text);
  EXPECT_TRUE(restarted.entry(2).fused.isApprox(m.entry(2).fused, 1e-12));
  EXPECT_EQ(restarted.entry(9).status, GlobalStatus::kMoving);
  // The restarted map continues the robots' streams: old events are stale.
  EXPECT_EQ(restarted.apply(ev(1, 2, landmark_event_t::UPDATE, 2, 5, 5), nullptr), EventResult::kDuplicate);
  EXPECT_EQ(restarted.apply(ev(1, 3, landmark_event_t::UPDATE, 2, 5, 5), nullptr), EventResult::kApplied);
}

// What a restart must not lose: a static landmark no robot holds any more keeps its
// fused estimate (it came back at (0, 0) with a zero covariance, which every map
// chunk then failed the message checks with), and a moving entry that is only an
// opinion of unknown age stays one (it came back as a confirmed finding, which the
// robots apply as a notice, and which a robot holding it static could no longer
// override). A file of before, without the fused estimate, drops such a landmark.
TEST(GlobalMap, PersistenceKeepsALandmarkNoRobotHoldsAndAnUnconfirmedMovingEntry) {
  GlobalMap m(options());
  std::vector<Notice> n;
  m.apply(ev(2, 1, landmark_event_t::ADD, 7, 7, 7), &n);
  m.apply_snapshot(2, 1, 10, {}, {}, &n);  // robot 2 restarted fresh: it no longer holds 7
  ASSERT_EQ(m.entry(7).status, GlobalStatus::kStatic);
  ASSERT_EQ(m.entry(7).contributors(), 0);
  m.apply_snapshot(1, 40, 60, {{2, held(1, 1, 60)}}, {5}, &n);  // 5: unconfirmed moving
  ASSERT_TRUE(m.entry(5).moving_unconfirmed);
  ASSERT_TRUE(m.entry(2).history_unknown);
  const std::string text = m.to_json();
  GlobalMap restarted(options());
  std::string why;
  ASSERT_TRUE(restarted.from_json(text, &why)) << why;
  EXPECT_EQ(restarted.to_json(), text);
  EXPECT_EQ(restarted.entry(7).status, GlobalStatus::kStatic);
  EXPECT_TRUE(restarted.entry(7).fused.isApprox(m.entry(7).fused, 1e-12));
  EXPECT_TRUE(restarted.entry(7).fused_cov.isApprox(m.entry(7).fused_cov, 1e-12));
  EXPECT_GT(restarted.entry(7).fused_cov.determinant(), 0.0);
  EXPECT_TRUE(restarted.entry(5).moving_unconfirmed);
  EXPECT_TRUE(restarted.entry(2).history_unknown);
  // Still an opinion: robot 2 holding 5 static in a later snapshot takes it back.
  restarted.apply_snapshot(2, 30, 61, {{5, held(5, 5, 61)}}, {}, &n);
  EXPECT_EQ(restarted.entry(5).status, GlobalStatus::kStatic);
  // A file of before (no fused estimate, no flags): landmark 7 is left out.
  nlohmann::json j = nlohmann::json::parse(text);
  for (auto& l : j["landmarks"]) {
    l.erase("fused");
    l.erase("moving_unconfirmed");
    l.erase("history_unknown");
  }
  GlobalMap old(options());
  ASSERT_TRUE(old.from_json(j.dump(), &why)) << why;
  EXPECT_EQ(old.entry(7).status, GlobalStatus::kAbsent);
  EXPECT_EQ(old.entry(2).status, GlobalStatus::kStatic);
  // A saved fused estimate is checked like an estimate.
  for (auto& l : j["landmarks"])
    if (l["id"] == 7) l["fused"] = {{"x", 7.0}, {"y", 7.0}, {"cov", {0.0, 0.0, 0.0, 0.0}}};
  EXPECT_FALSE(old.from_json(j.dump(), &why));
  EXPECT_NE(why.find("fused cov"), std::string::npos) << why;
}

// A state file of an older build with 8 robot ids loads: its robots'
// streams continue, the others start fresh.
TEST(GlobalMap, StateOfEightRobotIdsLoads) {
  GlobalMap m(options());
  m.apply(ev(2, 1, landmark_event_t::ADD, 2, 1, 1), nullptr);
  nlohmann::json j = nlohmann::json::parse(m.to_json());
  ASSERT_EQ(j["robots"].size(), static_cast<std::size_t>(kMaxTeamRobots));
  j["robots"].erase(j["robots"].begin() + 8, j["robots"].end());
  GlobalMap old(options());
  std::string why;
  ASSERT_TRUE(old.from_json(j.dump(), &why)) << why;
  EXPECT_EQ(old.apply(ev(2, 1, landmark_event_t::UPDATE, 2, 5, 5), nullptr), EventResult::kDuplicate);
  EXPECT_EQ(old.apply(ev(16, 1, landmark_event_t::ADD, 2, 5, 5), nullptr), EventResult::kApplied);
  j["robots"] = nlohmann::json::array();
  EXPECT_FALSE(old.from_json(j.dump(), &why));
  EXPECT_NE(why.find("robots"), std::string::npos) << why;
}

TEST(GlobalMap, MalformedStateIsRefusedAndMapUnchanged) {
  GlobalMap m(options());
  m.apply(ev(1, 1, landmark_event_t::ADD, 2, 1, 1), nullptr);
  const std::string before = m.to_json();
  std::string why;
  EXPECT_FALSE(m.from_json("{not json", &why));
  EXPECT_FALSE(why.empty());
  std::string bad = before;
  bad.replace(bad.find("\"id\": 2"), 7, "\"id\": 99");
  EXPECT_FALSE(m.from_json(bad, &why));
  EXPECT_NE(why.find("99"), std::string::npos) << why;
  EXPECT_EQ(m.to_json(), before);
}

landmark_event_t msg_event(int robot, std::int64_t seq, int kind, int id) { return test::event_msg(robot, seq, kind, id); }

TEST(MainNode, BadMessagesAreCountedAndDropped) {
  MainNode node(options());
  std::string why;
  EXPECT_TRUE(node.on_event(msg_event(1, 1, landmark_event_t::ADD, 3), &why)) << why;
  const std::string state = node.map().to_json();
  auto bad = msg_event(1, 2, landmark_event_t::ADD, 3);
  bad.x = std::nan("");
  EXPECT_FALSE(node.on_event(bad, &why));
  EXPECT_NE(why.find("finite"), std::string::npos);
  bad = msg_event(17, 2, landmark_event_t::ADD, 3);
  EXPECT_FALSE(node.on_event(bad, &why));
  EXPECT_NE(why.find("robot_id"), std::string::npos);
  bad = msg_event(1, 2, landmark_event_t::ADD, 32);
  EXPECT_FALSE(node.on_event(bad, &why));
  EXPECT_NE(why.find("landmark_id"), std::string::npos);
  bad = msg_event(1, 2, 7, 3);
  EXPECT_FALSE(node.on_event(bad, &why));
  bad = msg_event(1, 2, landmark_event_t::ADD, 3);
  bad.cov[0][0] = -1.0;
  EXPECT_FALSE(node.on_event(bad, &why));
  lmap_snapshot_t snap{};
  snap.robot_id = 1;
  snap.num_chunks = 1;
  snap.id_end = 32;
  snap.num_landmarks = 300;  // the array holds none
  EXPECT_FALSE(node.on_snapshot(snap, &why));
  EXPECT_NE(why.find("num_landmarks"), std::string::npos);
  EXPECT_EQ(node.counters().rejected_inputs, 6);
  EXPECT_EQ(node.map().to_json(), state);
}

// main.body_radius_m: a static landmark cannot be where a robot's body is. One the map
// holds closer to a robot's reported position than the body radius, both estimates
// sharp enough to tell, is taken as moving (found by that robot); nothing else is.
TEST(GlobalMap, AStaticLandmarkWhereARobotIsIsTakenAsMoving) {
  GlobalMapOptions o = options();
  o.body_radius_m = 0.17;
  GlobalMap m(o);
  m.apply(ev(1, 1, landmark_event_t::ADD, 3, 1.0, 2.0, 0.0025), nullptr);   // sigma 5 cm
  m.apply(ev(1, 2, landmark_event_t::ADD, 4, 3.0, 2.0, 0.0025), nullptr);
  m.apply(ev(1, 3, landmark_event_t::ADD, 5, 5.0, 2.0, 0.04), nullptr);     // sigma 20 cm: seen from afar
  m.apply(ev(1, 4, landmark_event_t::ADD, 6, 7.0, 2.0, 0.0025), nullptr);
  const Eigen::Matrix2d sharp = Eigen::Matrix2d::Identity() * 1e-4;
  std::vector<Notice> notices;
  // Robot 2 at 0.18 m from landmark 3: outside its body, nothing taken.
  EXPECT_EQ(m.occupy(2, 10, {1.18, 2.0}, sharp, &notices), 0);
  // ... at 0.16 m from landmark 4 (inside its body): moving, found by robot 2.
  EXPECT_EQ(m.occupy(2, 11, {3.0, 2.16}, sharp, &notices), 1);
  EXPECT_EQ(m.entry(4).status, GlobalStatus::kMoving);
  EXPECT_EQ(m.entry(4).moving_by, 2);
  EXPECT_EQ(m.entry(4).status_frame, 11);
  EXPECT_EQ(m.entry(4).contributors(), 0);  // deleted from the map
  ASSERT_EQ(notices.size(), 1u);
  EXPECT_EQ(notices[0].landmark_id, 4);
  EXPECT_EQ(notices[0].detected_by, 2);
  EXPECT_EQ(notices[0].frame, 11);
  // Already moving: not again, no second notice.
  EXPECT_EQ(m.occupy(2, 12, {3.0, 2.0}, sharp, &notices), 0);
  // Landmark 5 is too uncertain to tell (sqrt(trace / 2) = 0.2 m > 0.17 m): kept.
  EXPECT_EQ(m.occupy(3, 12, {5.0, 2.0}, sharp, &notices), 0);
  EXPECT_EQ(m.entry(5).status, GlobalStatus::kStatic);
  // So is a robot whose own position is that uncertain (sigma 0.2 m), on landmark 6.
  EXPECT_EQ(m.occupy(3, 12, {7.0, 2.0}, Eigen::Matrix2d::Identity() * 0.04, &notices), 0);
  EXPECT_EQ(m.entry(6).status, GlobalStatus::kStatic);
  EXPECT_EQ(notices.size(), 1u);
  // Off (0, the default): nothing, even right on a landmark.
  GlobalMap off(options());
  off.apply(ev(1, 1, landmark_event_t::ADD, 3, 1.0, 2.0, 0.0025), nullptr);
  EXPECT_EQ(off.occupy(2, 10, {1.0, 2.0}, sharp, &notices), 0);
  EXPECT_EQ(off.entry(3).status, GlobalStatus::kStatic);
}

// The rule runs on every accepted POSE of a new frame, and its finding goes out as a
// DYNAMIC_NOTICE; a POSE that is refused or stale finds nothing.
TEST(MainNode, APoseOnAStaticLandmarkSendsANotice) {
  GlobalMapOptions o = options();
  o.body_radius_m = 0.17;
  o.limits.team_mask = 0b11;  // robots 1 and 2
  MainNode node(o);
  node.on_event(msg_event(1, 1, landmark_event_t::ADD, 3));  // at (1, 2), var 0.01
  ASSERT_EQ(node.map().entry(3).status, GlobalStatus::kStatic);
  pose_estimate_t p = test::pose_msg(2, 5);
  p.x = 1.0;
  p.y = 2.0;
  pose_estimate_t outside = p;
  outside.robot_id = 3;  // not in the team: refused
  EXPECT_EQ(node.on_pose(outside), -1);
  EXPECT_EQ(node.counters().occupied, 0);
  node.on_pose(p);
  EXPECT_EQ(node.counters().occupied, 1);
  EXPECT_EQ(node.map().entry(3).status, GlobalStatus::kMoving);
  const auto& n = node.take_notices(100);
  ASSERT_EQ(n.size(), 1u);
  EXPECT_EQ(n[0].landmark_id, 3);
  EXPECT_EQ(n[0].detected_by, 2);
  EXPECT_EQ(n[0].frame, 5);
  // RETURNed by robot 1, then the same POSE again (a late duplicate): ignored.
  node.on_event(test::event_msg(1, 2, landmark_event_t::RETURN, 3, 6));
  ASSERT_EQ(node.map().entry(3).status, GlobalStatus::kStatic);
  node.on_pose(p);
  EXPECT_EQ(node.counters().stale_poses, 1);
  EXPECT_EQ(node.counters().occupied, 1);
  // Robot 2's next frame, still there: moving again.
  p.frame = 7;
  node.on_pose(p);
  EXPECT_EQ(node.counters().occupied, 2);
}

// main.team_map_check_probability: before a round of team maps each robot's map is
// checked against the fusion of the others'. A robot whose estimates disagree on more
// than half of the (at least 3) landmarks it shares is left out of every team map of
// that round; one that agrees is not blamed for the one that does not.
TEST(GlobalMap, ARobotWhoseMapTheOthersRefuseIsLeftOutOfTheirTeamMaps) {
  GlobalMapOptions o = options();
  o.team_map_check_probability = 0.9999;  // chi-square (2 dof) 18.42
  GlobalMap m(o);
  // Robots 1, 2 and 4 map landmarks 3-7 where they are (sigma 5 cm); robot 3 0.5 m off.
  std::int64_t seq[5] = {};
  auto add = [&](int robot, int id, double dx) {
    m.apply(ev(robot, ++seq[robot], landmark_event_t::ADD, id, id + dx, 0.0, 0.0025), nullptr);
  };
  for (int id = 3; id <= 7; ++id)
    for (int r : {1, 2, 3, 4}) add(r, id, r == 3 ? 0.5 : 0.0);
  Eigen::Vector2d p;
  Eigen::Matrix2d C;
  // Before any check, robot 1's team map holds robot 3's estimate: (0 + 0.5 + 0) / 3.
  ASSERT_TRUE(m.fused_without(5, 1, &p, &C));
  EXPECT_NEAR(p.x(), 5.0 + 0.5 / 3.0, 1e-12);
  // Robot 3 against robots 1, 2, 4: d2 = 0.25 / (0.0025 + 0.0025 / 3) = 75. Robot 1
  // against 2, 3, 4 (pulled 0.5 / 3 by robot 3): d2 = 8.3, agrees.
  EXPECT_EQ(m.check_team(), 0b0100u);
  EXPECT_EQ(m.left_out(), 0b0100u);
  EXPECT_EQ(m.team_check(3).shared, 5);
  EXPECT_EQ(m.team_check(3).disagree, 5);
  EXPECT_TRUE(m.is_left_out(3));
  EXPECT_EQ(m.team_check(3).rounds_left_out, 1);
  for (int r : {1, 2, 4}) {
    EXPECT_EQ(m.team_check(r).shared, 5) << r;
    EXPECT_EQ(m.team_check(r).disagree, 0) << r;
    EXPECT_FALSE(m.is_left_out(r)) << r;
  }
  // Robot 1's team map: robots 2 and 4 only.
  ASSERT_TRUE(m.fused_without(5, 1, &p, &C));
  EXPECT_NEAR(p.x(), 5.0, 1e-12);
  EXPECT_NEAR(C(0, 0), 0.0025 / 2.0, 1e-15);
  // Robot 3's own team map: the other three, as always.
  ASSERT_TRUE(m.fused_without(5, 3, &p, &C));
  EXPECT_NEAR(p.x(), 5.0, 1e-12);
  EXPECT_NEAR(C(0, 0), 0.0025 / 3.0, 1e-15);
  // The global map is not touched: robot 3 is in it.
  EXPECT_NEAR(m.entry(5).fused.x(), 5.0 + 0.5 / 4.0, 1e-12);
  // Robot 3 corrects two of its five: 3 of 5 still disagree, still out.
  m.apply(ev(3, ++seq[3], landmark_event_t::UPDATE, 3, 3.0, 0.0, 0.0025), nullptr);
  m.apply(ev(3, ++seq[3], landmark_event_t::UPDATE, 4, 4.0, 0.0, 0.0025), nullptr);
  EXPECT_EQ(m.check_team(), 0b0100u);
  EXPECT_EQ(m.team_check(3).disagree, 3);
  EXPECT_EQ(m.team_check(3).rounds_left_out, 2);
  // A fourth landmark only robots 1 and 3 hold, where they agree: 3 of 6 is not more
  // than half. Back in.
  add(1, 8, 0.0);
  add(3, 8, 0.0);
  EXPECT_EQ(m.check_team(), 0u);
  EXPECT_EQ(m.team_check(3).shared, 6);
  EXPECT_EQ(m.team_check(3).disagree, 3);
  EXPECT_FALSE(m.is_left_out(3));
  EXPECT_EQ(m.team_check(3).rounds_left_out, 2);  // since start
  ASSERT_TRUE(m.fused_without(5, 1, &p, &C));
  EXPECT_NEAR(p.x(), 5.0 + 0.5 / 3.0, 1e-12);
}

// Fewer than kTeamCheckMinShared shared landmarks judge nobody; a landmark only one
// robot holds is not shared; MOVING landmarks are not compared; 0 turns it off.
TEST(GlobalMap, TheTeamCheckNeedsThreeSharedLandmarksAndCanBeOff) {
  GlobalMapOptions o = options();
  o.team_map_check_probability = 0.9999;
  GlobalMap m(o);
  for (int id = 3; id <= 4; ++id) {
    m.apply(ev(1, id, landmark_event_t::ADD, id, id, 0.0, 0.0025), nullptr);
    m.apply(ev(2, id, landmark_event_t::ADD, id, id + 1.0, 0.0, 0.0025), nullptr);  // 1 m apart
  }
  m.apply(ev(2, 5, landmark_event_t::ADD, 9, 9.0, 0.0, 0.0025), nullptr);  // robot 2's alone
  EXPECT_EQ(m.check_team(), 0u);
  EXPECT_EQ(m.team_check(1).shared, 2);
  EXPECT_EQ(m.team_check(2).shared, 2);
  EXPECT_EQ(m.team_check(2).disagree, 2);
  // A third shared landmark, apart too: both out (two robots cannot tell who is wrong,
  // and neither takes the other's map).
  m.apply(ev(1, 5, landmark_event_t::ADD, 5, 5.0, 0.0, 0.0025), nullptr);
  m.apply(ev(2, 6, landmark_event_t::ADD, 5, 6.0, 0.0, 0.0025), nullptr);
  EXPECT_EQ(m.check_team(), 0b11u);
  Eigen::Vector2d p;
  Eigen::Matrix2d C;
  EXPECT_FALSE(m.fused_without(5, 1, &p, &C));
  // Robot 2 finds landmark 5 moving: deleted, no longer compared; 2 shared, both back.
  m.apply(ev(2, 7, landmark_event_t::MOVING, 5), nullptr);
  EXPECT_EQ(m.check_team(), 0u);
  EXPECT_EQ(m.team_check(1).shared, 2);
  // Off: nobody is judged.
  GlobalMap off(options());
  for (int id = 3; id <= 6; ++id) {
    off.apply(ev(1, id, landmark_event_t::ADD, id, id, 0.0, 0.0025), nullptr);
    off.apply(ev(2, id, landmark_event_t::ADD, id, id + 1.0, 0.0, 0.0025), nullptr);
  }
  EXPECT_EQ(off.check_team(), 0u);
  EXPECT_EQ(off.team_check(1).shared, 0);
  ASSERT_TRUE(off.fused_without(5, 1, &p, &C));
  EXPECT_NEAR(p.x(), 6.0, 1e-12);
}

// The node: the check runs when a round of team maps is due; the robot left out is
// named in an alert line and STATUS_MAIN carries FAULT_INCONSISTENT while it is out;
// the others' team maps neither hold its estimates nor list it as a contributor.
TEST(MainNode, ARobotLeftOutOfTheTeamMapsIsSaid) {
  GlobalMapOptions o = options();
  o.team_map_check_probability = 0.9999;
  o.team_map_period_frames = 10;
  MainNode node(o);
  std::int64_t seq[5] = {};
  auto send = [&](int robot, int kind, int id, double x) {
    std::string why;
    ASSERT_TRUE(node.on_event(test::event_msg(robot, ++seq[robot], kind, id, 0, x, 0.0, 0.0025), &why)) << why;
  };
  for (int id = 3; id <= 5; ++id)
    for (int r : {1, 2, 3}) send(r, landmark_event_t::ADD, id, r == 3 ? id + 0.5 : id);
  EXPECT_EQ(node.status_msg(0).fault_flags & node_status_t::FAULT_INCONSISTENT, 0);
  ASSERT_TRUE(node.team_map_due(10));
  EXPECT_EQ(node.map().left_out(), 0b100u);
  EXPECT_EQ(node.map().rounds_left_out(), 1);
  EXPECT_NE(node.status_msg(0).fault_flags & node_status_t::FAULT_INCONSISTENT, 0);
  EXPECT_EQ(node.take_alert(),
            "robot 3's map disagrees with the other robots' on 3 of 3 shared landmarks: left out of their team maps");
  ASSERT_EQ(node.make_team_map(1, 10, 10), 1);
  const global_map_t& c = node.map_chunk(0);
  ASSERT_EQ(c.num_landmarks, 3);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(c.landmarks[i].x, c.landmarks[i].id, 1e-12);  // robot 2's alone
    EXPECT_EQ(c.landmarks[i].contributors, 0b010);
  }
  // Robot 3 maps where the others do: back in at the next round, said once.
  for (int id = 3; id <= 5; ++id) send(3, landmark_event_t::UPDATE, id, id);
  EXPECT_FALSE(node.team_map_due(15));  // same period
  ASSERT_TRUE(node.team_map_due(20));
  EXPECT_EQ(node.map().left_out(), 0u);
  EXPECT_EQ(node.map().rounds_left_out(), 1);
  EXPECT_EQ(node.status_msg(0).fault_flags & node_status_t::FAULT_INCONSISTENT, 0);
  EXPECT_EQ(node.take_alert(),
            "robot 3's map agrees with the other robots' again (0 of 3 shared landmarks disagree): back in their "
            "team maps");
  ASSERT_TRUE(node.team_map_due(30));
  EXPECT_EQ(node.take_alert(), "");
  // Out again; then two of the three landmarks are found moving: too few left to
  // judge robot 3 by, and it is said so.
  for (int id = 3; id <= 5; ++id) send(3, landmark_event_t::UPDATE, id, id + 0.5);
  ASSERT_TRUE(node.team_map_due(40));
  EXPECT_EQ(node.map().left_out(), 0b100u);
  node.take_alert();
  send(1, landmark_event_t::MOVING, 3, 3.0);
  send(1, landmark_event_t::MOVING, 4, 4.0);
  ASSERT_TRUE(node.team_map_due(50));
  EXPECT_EQ(node.map().left_out(), 0u);
  EXPECT_EQ(node.take_alert(),
            "robot 3's map shares too few landmarks with the other robots' to be judged (1, fewer than 3): back in "
            "their team maps");
}

TEST(MainNode, NoticesGetSequenceNumbersAndMapMessageListsMoving) {
  MainNode node(options());
  node.on_event(msg_event(1, 1, landmark_event_t::ADD, 3));
  node.on_event(msg_event(1, 2, landmark_event_t::ADD, 4));
  node.on_event(msg_event(2, 1, landmark_event_t::MOVING, 3));
  const auto& n = node.take_notices(100);
  ASSERT_EQ(n.size(), 1u);
  EXPECT_EQ(n[0].seq, 1);
  EXPECT_EQ(n[0].landmark_id, 3);
  EXPECT_EQ(n[0].detected_by, 2);
  EXPECT_TRUE(node.take_notices(101).empty());
  ASSERT_EQ(node.make_global_map(200), 1);
  const global_map_t& g = node.map_chunk(0);
  ASSERT_EQ(g.num_landmarks, 1);
  EXPECT_EQ(g.landmarks[0].id, 4);
  ASSERT_EQ(g.num_moving, 1);
  EXPECT_EQ(g.moving_ids[0], 3);
  EXPECT_EQ(g.moving_by[0], 2);
  EXPECT_EQ(g.id_begin, 0);
  EXPECT_EQ(g.id_end, 32);
}

}  // namespace
}  // namespace elaslam

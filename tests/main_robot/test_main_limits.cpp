// SPDX-License-Identifier: Apache-2.0
// Messages and state files that decode and look valid but are absurd:
// main_robot refuses them, counts each per reason, and keeps the map as it was.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <limits>

#include "../support/messages.hpp"
#include "elaslam/main_robot/main_node.hpp"

namespace elaslam {
namespace {

GlobalMapOptions options(const std::string& team = "1,2,3,4,5,6,7,8") {
  GlobalMapOptions o;
  o.max_landmark_id = 32;
  std::string why;
  EXPECT_TRUE(parse_team(team, &o.limits.team_mask, &why)) << why;
  return o;
}

landmark_event_t add(int robot, std::int64_t seq, int id, double var = 0.01, int frame = 0) {
  return test::event_msg(robot, seq, landmark_event_t::ADD, id, frame, 1.0, 2.0, var);
}

lmap_snapshot_t snapshot(int robot, std::int64_t seq, int frame, std::vector<int> ids, std::vector<int> moving = {}) {
  lmap_snapshot_t s{};
  s.robot_id = static_cast<int16_t>(robot);
  s.seq = seq;
  s.frame = frame;
  s.num_chunks = 1;
  s.id_end = 32;
  s.num_landmarks = static_cast<int16_t>(ids.size());
  for (int id : ids) {
    landmark_estimate_t l{};
    l.id = id;
    l.x = 0.1 * id + 0.01 * frame;  // the estimate moves with the frame: a rollback shows
    l.y = 1.0;
    l.cov[0][0] = l.cov[1][1] = 0.01;
    s.landmarks.push_back(l);
  }
  s.num_moving = static_cast<int16_t>(moving.size());
  s.moving_ids = moving;
  s.moving_frames.assign(moving.size(), -1);
  return s;
}

pose_estimate_t pose(int robot, int frame) { return test::pose_msg(robot, frame); }

// LMAP_EVENTS: a robot's events of a frame in one message are applied exactly as the
// same events one by one (the map, the counters, the notices); an event that is
// refused inside a valid message is refused alone; a message whose header does not
// speak for its events is refused whole, counted once, and changes nothing.
TEST(MainEventBatches, ABatchIsItsEventsOneByOne) {
  std::vector<landmark_event_t> f0 = {add(1, 1, 3), add(1, 2, 5), add(1, 3, 7)};
  std::vector<landmark_event_t> f1 = {test::event_msg(1, 4, landmark_event_t::UPDATE, 3, 1, 1.1, 2.0, 0.02),
                                      test::event_msg(1, 5, landmark_event_t::MOVING, 5, 1),
                                      add(1, 7, 9, 0.01, 1)};  // seq 6 lost: a gap, repaired by a resync
  for (auto* f : {&f0, &f1})
    for (auto& e : *f) e.incarnation = 42;
  MainNode one(options()), batch(options());
  for (const auto* f : {&f0, &f1})
    for (const auto& e : *f) EXPECT_TRUE(one.on_event(e));
  std::string why;
  EXPECT_TRUE(batch.on_events(test::events_msg(f0), &why)) << why;
  EXPECT_TRUE(batch.on_events(test::events_msg(f1), &why)) << why;
  EXPECT_EQ(batch.counters().events, one.counters().events);
  EXPECT_EQ(batch.counters().events, 6);
  EXPECT_EQ(batch.counters().gaps, 1);
  EXPECT_EQ(batch.take_notices(0).size(), one.take_notices(0).size());
  EXPECT_EQ(batch.take_resyncs(0).size(), 1u);
  for (int id : {3, 5, 7, 9}) {
    EXPECT_EQ(batch.map().entry(id).status, one.map().entry(id).status) << id;
    EXPECT_EQ(batch.map().entry(id).fused, one.map().entry(id).fused) << id;
  }
  EXPECT_EQ(batch.map().entry(5).status, GlobalStatus::kMoving);

  // Inside a valid message, one absurd event is refused alone; the others apply.
  std::vector<landmark_event_t> f2 = {add(1, 8, 11, 1e-320, 2), add(1, 9, 12, 0.01, 2)};
  for (auto& e : f2) e.incarnation = 42;
  EXPECT_FALSE(batch.on_events(test::events_msg(f2), &why));
  EXPECT_NE(why.find("cov_floor_m2"), std::string::npos) << why;
  EXPECT_EQ(batch.counters().refused[Refusal::kImplausible], 1);
  EXPECT_EQ(batch.map().entry(12).status, GlobalStatus::kStatic);

  // Headers that do not speak for their events: refused whole, nothing applied.
  struct Case {
    const char* name;
    void (*spoil)(lmap_events_t&);
    const char* expect;
  };
  const Case cases[] = {
      {"another robot's event", [](lmap_events_t& m) { m.events[1].robot_id = 2; }, "robot_id differs"},
      {"another incarnation", [](lmap_events_t& m) { m.events[0].incarnation = 7; }, "incarnation differs"},
      {"another frame", [](lmap_events_t& m) { m.events[1].frame = 2; }, "frame differs"},
      {"seqs not ascending", [](lmap_events_t& m) { m.events[1].seq = m.events[0].seq; }, "not ascending"},
      {"empty", [](lmap_events_t& m) { m.num_events = 0, m.events.clear(); }, "num_events"},
      {"count beyond the batch size", [](lmap_events_t& m) { m.num_events = contract::kMaxBatchEvents + 1; }, "num_events"},
      {"count beyond the array", [](lmap_events_t& m) { m.num_events = 3; }, "does not match"},
      {"header from outside the team", [](lmap_events_t& m) { m.robot_id = 12; for (auto& e : m.events) e.robot_id = 12; }, "limits.team"},
  };
  for (const Case& c : cases) {
    std::vector<landmark_event_t> f3 = {add(1, 10, 20, 0.01, 3), add(1, 11, 21, 0.01, 3)};
    for (auto& e : f3) e.incarnation = 42;
    lmap_events_t m = test::events_msg(f3);
    c.spoil(m);
    const auto refused = batch.counters().refused.total();
    const auto applied = batch.counters().events;
    EXPECT_FALSE(batch.on_events(m, &why)) << c.name;
    EXPECT_NE(why.find(c.expect), std::string::npos) << c.name << ": " << why;
    EXPECT_EQ(batch.counters().refused.total(), refused + 1) << c.name;
    EXPECT_EQ(batch.counters().events, applied) << c.name;
    EXPECT_NE(batch.map().entry(20).status, GlobalStatus::kStatic) << c.name;
  }
}

// main.moving_repeat_s: the moving set goes out when its lists change (ids, frames,
// finders), else only once the last one sent is moving_repeat_s old; 0: always.
TEST(MainMovingSet, ChangesGoOutAtOnceRepeatsOncePerPeriod) {
  GlobalMapOptions o = options();
  o.moving_repeat_s = 1.0;
  MainNode node(o);
  constexpr std::int64_t t0 = 1'000'000'000, ms = 1000;
  auto due = [&](std::int64_t t) { return node.moving_set_due(node.make_moving_set(t), t); };
  EXPECT_TRUE(due(t0)) << "the first one";
  EXPECT_FALSE(due(t0 + 100 * ms)) << "nothing changed";
  ASSERT_TRUE(node.on_event(add(1, 1, 4)));
  EXPECT_FALSE(due(t0 + 200 * ms)) << "a static landmark is not in the moving lists";
  ASSERT_TRUE(node.on_event(test::event_msg(1, 2, landmark_event_t::MOVING, 4, 1)));
  EXPECT_TRUE(due(t0 + 300 * ms)) << "4 moving";
  EXPECT_FALSE(due(t0 + 1299 * ms));
  EXPECT_TRUE(due(t0 + 1300 * ms)) << "a repeat, a second after the last";
  EXPECT_FALSE(due(t0 + 1400 * ms));
  ASSERT_TRUE(node.on_event(test::event_msg(1, 3, landmark_event_t::RETURN, 4, 2)));
  EXPECT_TRUE(due(t0 + 1500 * ms)) << "4 back: the lists are empty again";
  EXPECT_TRUE(due(t0)) << "a clock stepped back: sent";
  EXPECT_EQ(node.counters().moving_sets, 5);
  o.moving_repeat_s = 0.0;
  MainNode every(o);
  for (int k = 0; k < 3; ++k) EXPECT_TRUE(every.moving_set_due(every.make_moving_set(t0), t0));
}

// GIVEN an ADD whose covariance is denormal (1e-320: inverts to infinity, a NaN
// landmark) or zero (pins the landmark)  THEN it is refused as implausible, naming
// the floor, and the map stays empty.
TEST(MainLimits, DenormalOrZeroCovarianceIsRefused) {
  MainNode node(options());
  std::string why;
  EXPECT_FALSE(node.on_event(add(1, 1, 3, 1e-320), &why));
  EXPECT_NE(why.find("cov_floor_m2"), std::string::npos) << why;
  EXPECT_FALSE(node.on_event(add(1, 1, 3, 0.0), &why));
  auto neg = add(1, 1, 3);
  neg.cov[0][1] = neg.cov[1][0] = 0.02;  // not positive definite
  EXPECT_FALSE(node.on_event(neg, &why));
  EXPECT_FALSE(node.on_event(add(1, 1, 3, 1e9), &why));  // above the ceiling
  EXPECT_NE(why.find("cov_ceiling_m2"), std::string::npos) << why;
  EXPECT_EQ(node.map().count(GlobalStatus::kStatic), 0);
  EXPECT_EQ(node.counters().refused[Refusal::kImplausible], 4);
  EXPECT_TRUE(node.on_event(add(1, 1, 3), &why)) << why;
  EXPECT_TRUE(node.map().entry(3).fused.allFinite());
}

// A POSE's frame NIS must be a finite non-negative number with an even number of
// degrees of freedom within the contract's bound; anything else is refused as
// malformed, names the field and leaves the robot's frame where it was.
TEST(MainLimits, APoseWithAnImpossibleNisIsRefused) {
  MainNode node(options());
  std::string why;
  pose_estimate_t p = pose(1, 0);
  p.nis = 12.5;
  p.nis_dof = 8;
  EXPECT_EQ(node.on_pose(p, &why), 0) << why;
  for (double bad : {-1.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    pose_estimate_t q = pose(1, 1);
    q.nis = bad;
    EXPECT_EQ(node.on_pose(q, &why), -1);
    EXPECT_NE(why.find("nis is negative or not finite"), std::string::npos) << why;
  }
  for (int bad : {-2, 3, 2 * contract::kMaxObsPerFrameLimit + 2}) {
    pose_estimate_t q = pose(1, 1);
    q.nis_dof = static_cast<std::int16_t>(bad);
    EXPECT_EQ(node.on_pose(q, &why), -1);
    EXPECT_NE(why.find("nis_dof"), std::string::npos) << why;
  }
  EXPECT_EQ(node.counters().refused[Refusal::kMalformed], 6);
  EXPECT_EQ(node.on_pose(pose(1, 1), &why), 1) << why;
}

// Snapshots had no position bound (1e300 m accepted; events refused over 1e6 m).
TEST(MainLimits, PositionsBeyondTheWorldBoundAreRefusedInEventsAndSnapshots) {
  MainNode node(options());
  std::string why;
  auto far = add(1, 1, 3);
  far.x = 2e4;  // limits.world_bound_m 1e4 by default
  EXPECT_FALSE(node.on_event(far, &why));
  EXPECT_NE(why.find("world_bound_m"), std::string::npos) << why;
  auto s = snapshot(1, 0, 5, {2, 4});
  s.landmarks[1].y = 1e300;
  EXPECT_FALSE(node.on_snapshot(s, &why));
  EXPECT_NE(why.find("landmark 4"), std::string::npos) << why;
  EXPECT_EQ(node.counters().refused[Refusal::kImplausible], 2);
  EXPECT_EQ(node.map().count(GlobalStatus::kStatic), 0);
}

// One event with seq INT64_MAX made main drop every later event of that robot.
TEST(MainLimits, AFarFutureSeqNeverBlocksTheRealStream) {
  MainNode node(options());
  std::string why;
  ASSERT_TRUE(node.on_event(add(1, 1, 3), &why)) << why;
  EXPECT_FALSE(node.on_event(add(1, std::numeric_limits<std::int64_t>::max(), 4), &why));
  EXPECT_NE(why.find("seq"), std::string::npos) << why;
  EXPECT_FALSE(node.on_event(add(1, 5000000, 4), &why));  // beyond max_seq_jump: held
  EXPECT_NE(why.find("max_seq_jump"), std::string::npos) << why;
  EXPECT_EQ(node.counters().refused[Refusal::kSeqWindow], 1);
  // The real stream goes on.
  EXPECT_TRUE(node.on_event(add(1, 2, 5), &why)) << why;
  EXPECT_EQ(node.map().stream(1).last_seq, 2);
  EXPECT_EQ(node.map().entry(5).status, GlobalStatus::kStatic);
  // A real jump (a robot resumed from its state file skips 2^24) is confirmed by
  // its next message.
  EXPECT_FALSE(node.on_event(add(1, 2 + (1 << 24), 6), &why));
  EXPECT_TRUE(node.on_event(add(1, 3 + (1 << 24), 7), &why)) << why;
  EXPECT_EQ(node.map().stream(1).last_seq, 3 + (1 << 24));
}

TEST(MainLimits, AnOlderSnapshotNeverRollsTheMapBack) {
  MainNode node(options());
  std::string why;
  ASSERT_TRUE(node.on_snapshot(snapshot(1, 4, 10, {2}), &why)) << why;
  ASSERT_TRUE(node.on_snapshot(snapshot(1, 4, 20, {2}), &why)) << why;
  const double x = node.map().entry(2).fused.x();
  // The snapshot of frame 10 again (no events between: the same seq).
  EXPECT_FALSE(node.on_snapshot(snapshot(1, 4, 10, {2}), &why));
  EXPECT_NE(why.find("roll the map back"), std::string::npos) << why;
  EXPECT_FALSE(node.on_snapshot(snapshot(1, 3, 30, {2}), &why));  // a lower seq
  EXPECT_DOUBLE_EQ(node.map().entry(2).fused.x(), x);
  EXPECT_EQ(node.counters().refused[Refusal::kStale], 2);
}

// A snapshot chunk delayed past the robot's next events: it holds the map as of
// its seq, and applying it undid those events (an UPDATE moved back, a newly
// added landmark lost its only estimate).
TEST(MainLimits, ASnapshotOlderThanTheEventsAppliedNeverRollsThemBack) {
  MainNode node(options());
  std::string why;
  ASSERT_TRUE(node.on_event(add(1, 1, 2), &why)) << why;  // frame 10's ADD, seq 1
  landmark_event_t u = add(1, 2, 2);                      // frame 11: UPDATE, seq 2
  u.kind = landmark_event_t::UPDATE;
  u.x = 3.0;
  ASSERT_TRUE(node.on_event(u, &why)) << why;
  ASSERT_TRUE(node.on_event(add(1, 3, 7), &why)) << why;  // and ADD 7, seq 3
  ASSERT_DOUBLE_EQ(node.map().entry(2).by_robot[0].position.x(), 3.0);
  // Frame 10's snapshot (seq 1) arrives last.
  EXPECT_FALSE(node.on_snapshot(snapshot(1, 1, 10, {2}), &why));
  EXPECT_NE(why.find("events applied (seq 3)"), std::string::npos) << why;
  EXPECT_DOUBLE_EQ(node.map().entry(2).by_robot[0].position.x(), 3.0);
  EXPECT_EQ(node.map().entry(7).contributors(), 1);
  EXPECT_EQ(node.counters().refused[Refusal::kStale], 1);
  // One as of the newest event is applied.
  EXPECT_TRUE(node.on_snapshot(snapshot(1, 3, 11, {2, 7}), &why)) << why;
}

TEST(MainLimits, DuplicateIdsInOneSnapshotAreRefused) {
  MainNode node(options());
  std::string why;
  EXPECT_FALSE(node.on_snapshot(snapshot(1, 0, 5, {2, 2}), &why));
  EXPECT_NE(why.find("twice"), std::string::npos) << why;
  EXPECT_FALSE(node.on_snapshot(snapshot(1, 0, 5, {2}, {4, 4}), &why));
  EXPECT_FALSE(node.on_snapshot(snapshot(1, 0, 5, {2, 4}, {4}), &why));
  EXPECT_NE(why.find("static and as moving"), std::string::npos) << why;
  EXPECT_EQ(node.counters().refused[Refusal::kDuplicateId], 3);
  EXPECT_EQ(node.map().count(GlobalStatus::kStatic), 0);
}

// A POSE from a robot outside the team stalled the per-frame GLOBAL_MAP (main
// waited for it to finish every later frame).
TEST(MainLimits, APoseFromOutsideTheTeamNeverStallsTheMap) {
  MainNode node(options("1,2"));
  std::string why;
  EXPECT_EQ(node.on_pose(pose(1, 0)), 0);
  EXPECT_EQ(node.on_pose(pose(5, 0), &why), -1);
  EXPECT_NE(why.find("limits.team"), std::string::npos) << why;
  EXPECT_EQ(node.on_pose(pose(2, 0)), -1);
  for (int f = 1; f < 4; ++f) {
    EXPECT_EQ(node.on_pose(pose(1, f)), -1);
    EXPECT_EQ(node.on_pose(pose(2, f)), f);  // robot 5 stopped at frame 0 would hold this at -1
  }
  EXPECT_FALSE(node.on_event(add(5, 1, 3), &why));
  EXPECT_EQ(node.counters().refused[Refusal::kOutsideTeam], 2);
}

// Robot ids go up to 16 (config/large.yaml); limits.team names any of them, and an
// absent team accepts all 16.
TEST(MainLimits, TeamsOfUpToSixteenRobots) {
  int mask = 0;
  std::string why;
  EXPECT_TRUE(parse_team("1, 9,16", &mask, &why)) << why;
  EXPECT_EQ(mask, (1 << 0) | (1 << 8) | (1 << 15));
  EXPECT_EQ(team_text(mask), "1,9,16");
  for (const char* bad : {"17", "0", "1,1", "01", "1,x", "100", ""}) {
    EXPECT_FALSE(parse_team(bad, &mask, &why)) << bad;
    EXPECT_FALSE(why.empty());
  }
  EXPECT_TRUE(MessageLimits{}.in_team(16));
  EXPECT_FALSE(MessageLimits{}.in_team(17));
  MainNode node(options("1,16"));
  EXPECT_TRUE(node.on_event(add(16, 1, 3), &why)) << why;
  EXPECT_FALSE(node.on_event(add(9, 1, 4), &why));
  EXPECT_NE(why.find("limits.team"), std::string::npos) << why;
  EXPECT_EQ(node.on_pose(pose(1, 0)), 0);
  EXPECT_EQ(node.on_pose(pose(16, 0)), -1);
  EXPECT_EQ(node.on_pose(pose(1, 1)), -1);  // robot 16 is a member: its frame 1 is awaited
  EXPECT_EQ(node.on_pose(pose(16, 1)), 1);
}

// A frame of INT32_MAX pinned GLOBAL_MAP.frame there.
TEST(MainLimits, AFarFutureFrameNeverPinsTheMapFrame) {
  MainNode node(options("1"));
  for (int f = 0; f < 5; ++f) EXPECT_EQ(node.on_pose(pose(1, f)), f);
  std::string why;
  EXPECT_EQ(node.on_pose(pose(1, std::numeric_limits<int>::max()), &why), -1);
  EXPECT_NE(why.find("max_frame_gap"), std::string::npos) << why;
  // (A second message at the same frame would confirm the jump: another forged value.)
  EXPECT_FALSE(node.on_event(add(1, 1, 3, 0.01, std::numeric_limits<int>::max() - 1000), &why));
  EXPECT_EQ(node.on_pose(pose(1, 5)), 5);
  node.make_global_map(0);
  EXPECT_EQ(node.map_chunk(0).frame, 5);
  EXPECT_EQ(node.map().newest_frame(), -1);  // no event got in
  EXPECT_EQ(node.counters().refused[Refusal::kFrameWindow], 2);
  // A real jump (main saw nothing of robot 1 for a while) is confirmed by the next.
  EXPECT_EQ(node.on_pose(pose(1, 500)), -1);
  EXPECT_EQ(node.on_pose(pose(1, 501)), 501);
}

// A late or repeated POSE (a reordered or duplicated datagram) took the place of the
// POSE main held for its events: the held frame was then finished one POSE late (or
// an old frame held again). Now a POSE of a frame already held or finished is
// counted (stale_poses) and changes nothing.
TEST(MainLimits, ALateOrRepeatedPoseNeverLetsTheHeldOneGo) {
  MainNode node(options("1"));
  EXPECT_EQ(node.on_pose(pose(1, 0)), 0);
  pose_estimate_t p1 = pose(1, 1), p2 = pose(1, 2);
  p1.event_seq = 1;  // one event follows each
  p2.event_seq = 2;
  EXPECT_EQ(node.on_pose(p1), -1);
  EXPECT_TRUE(node.on_event(add(1, 1, 3, 0.01, 1)));
  EXPECT_EQ(node.take_finished(), 1);
  EXPECT_EQ(node.on_pose(p2), -1);  // held: its event is not in
  EXPECT_EQ(node.on_pose(p1), -1);  // frame 1 again, late
  EXPECT_EQ(node.on_pose(pose(1, 0)), -1);
  EXPECT_EQ(node.take_finished(), -1);
  EXPECT_TRUE(node.on_event(add(1, 2, 5, 0.01, 2)));
  EXPECT_EQ(node.take_finished(), 2) << "frame 2 finished by its event, as if the late POSEs never came";
  EXPECT_EQ(node.on_pose(p2), -1);  // repeated after it finished
  EXPECT_EQ(node.take_finished(), -1);
  EXPECT_EQ(node.counters().stale_poses, 3);
  EXPECT_EQ(node.counters().rejected_inputs, 0);
  EXPECT_EQ(node.on_pose(pose(1, 3)), 3);
}

// A robot's last events before a quiet spell were lost: main held their POSE, let it
// go at the next POSE, and noticed nothing (a gap shows only at the robot's next
// event, which may never come; a lost MOVING then stayed out of the map). The POSE
// says which events precede it: those still missing at the next POSE are a gap now,
// repaired by a snapshot; one that was only late still applies.
TEST(MainLimits, EventsAPoseAnnouncedAndNoneFollowedAreAGapAtTheNextPose) {
  MainNode node(options("1"));
  EXPECT_EQ(node.on_pose(pose(1, 0)), 0);
  EXPECT_TRUE(node.on_event(add(1, 1, 3, 0.01, 0)));
  pose_estimate_t p1 = pose(1, 1), p2 = pose(1, 2), p3 = pose(1, 3);
  p1.event_seq = 3;  // seqs 2 and 3 follow it: lost
  p2.event_seq = 3;  // nothing new
  p3.event_seq = 3;
  EXPECT_EQ(node.on_pose(p1), -1);
  EXPECT_TRUE(node.take_resyncs(0).empty());
  EXPECT_EQ(node.on_pose(p2), 1);  // frame 1 let go: its events are lost or late
  const auto& asked = node.take_resyncs(0);
  ASSERT_EQ(asked.size(), 1u);
  EXPECT_EQ(asked[0].robot_id, 1);
  EXPECT_EQ(asked[0].reason, resync_request_t::GAP);
  EXPECT_EQ(node.counters().gaps, 1);
  EXPECT_TRUE(node.map().stream(1).gap_pending);
  EXPECT_EQ(node.map().stream(1).last_seq, 1);  // a late event still applies
  EXPECT_NE(node.status_msg(0).fault_flags & node_status_t::FAULT_UNREPAIRED_GAP, 0);
  // Seq 2 was late, not lost: applied as usual.
  EXPECT_TRUE(node.on_event(test::event_msg(1, 2, landmark_event_t::MOVING, 3, 1)));
  EXPECT_EQ(node.map().entry(3).status, GlobalStatus::kMoving);
  EXPECT_EQ(node.counters().duplicates, 0);
  // Seq 3 is lost: the snapshot the robot sends on the request repairs it.
  std::string why;
  EXPECT_TRUE(node.on_snapshot(snapshot(1, 3, 2, {5}, {3}), &why)) << why;
  EXPECT_FALSE(node.map().stream(1).gap_pending);
  EXPECT_EQ(node.map().entry(5).status, GlobalStatus::kStatic);
  EXPECT_EQ(node.on_pose(p3), 3);
  EXPECT_EQ(node.counters().gaps, 1);
  EXPECT_TRUE(node.take_resyncs(0).empty());
}

// main_robot running on into a new run (the simulator or the log started over, the
// robots starting fresh with new incarnations at frame 0) kept the old run's
// finished frame: no map went out until the new run passed it. A robot that comes
// back far behind the team's frame is a new run: the team's frame starts over. A
// robot restarted within a run (at the team's frame) changes nothing.
TEST(MainLimits, ANewRunStartsTheTeamsFrameOver) {
  GlobalMapOptions o = options("1,2");
  o.max_frame_gap = 100;
  o.team_map_period_frames = 10;
  MainNode node(o);
  const auto send = [&node](int robot, int frame, std::int64_t incarnation) {  // the team's finished frame, or -1
    pose_estimate_t p = pose(robot, frame);
    p.incarnation = incarnation;
    return node.on_pose(p);
  };
  int done = -1;
  for (int k = 0; k <= 300; ++k)
    for (int r : {1, 2}) done = std::max(done, send(r, k, 100 * r));
  EXPECT_EQ(done, 300);
  EXPECT_TRUE(node.team_map_due(300));
  // Robot 2 restarted without its state within the run: at the team's frame.
  EXPECT_EQ(send(2, 301, 250), -1);
  EXPECT_EQ(send(1, 301, 100), 301);
  EXPECT_EQ(node.counters().runs_started, 0);
  // A new run: both robots start over at frame 0 with new incarnations.
  // (Robot 2, still in the old run, counts with its old frame, past this one.)
  EXPECT_EQ(send(1, 0, 1000), 0);
  EXPECT_EQ(node.counters().runs_started, 1);
  EXPECT_NE(node.take_alert().find("a new run"), std::string::npos);
  EXPECT_EQ(send(2, 0, 2000), -1);
  EXPECT_EQ(send(1, 1, 1000), -1);
  EXPECT_EQ(send(2, 1, 2000), 1);
  EXPECT_TRUE(node.team_map_due(1));
  node.make_global_map(0);
  EXPECT_EQ(node.map_chunk(0).frame, 1);
  EXPECT_EQ(node.counters().runs_started, 1);
}

// Found by fuzz_main_robot: an event, snapshot or POSE with a negative incarnation
// (a start time, microseconds since the epoch: never negative) was followed, and the
// state main saved then did not load back ("robots[1].incarnation not in [0, ...]").
// Refused as malformed now; the saved state of what was accepted loads back.
TEST(MainLimits, ANegativeIncarnationIsRefusedAndTheStateStillLoadsBack) {
  MainNode node(options("1"));
  std::string why;
  landmark_event_t e = add(1, 1, 3);
  e.incarnation = -1413842209176143135;
  EXPECT_FALSE(node.on_event(e, &why));
  EXPECT_NE(why.find("incarnation is negative"), std::string::npos) << why;
  lmap_snapshot_t s = snapshot(1, 0, 5, {2});
  s.incarnation = -1;
  EXPECT_FALSE(node.on_snapshot(s, &why));
  EXPECT_NE(why.find("incarnation is negative"), std::string::npos) << why;
  pose_estimate_t p = pose(1, 0);
  p.incarnation = -7;
  EXPECT_EQ(node.on_pose(p, &why), -1);
  EXPECT_NE(why.find("incarnation is negative"), std::string::npos) << why;
  EXPECT_EQ(node.counters().refused[Refusal::kMalformed], 3);
  e.incarnation = 1000;
  EXPECT_TRUE(node.on_event(e, &why)) << why;
  GlobalMap loaded(options("1"));
  EXPECT_TRUE(loaded.from_json(node.map().to_json(), &why)) << why;
  EXPECT_EQ(loaded.stream(1).incarnation, 1000);
}

TEST(MainLimits, StatusCountsEveryRefusalPerReason) {
  MainNode node(options("1"));
  node.on_event(add(1, 1, 3, 0.0));
  node.on_event(add(2, 1, 3));
  node.on_snapshot(snapshot(1, 0, 5, {2, 2}));
  const node_status_t s = node.status_msg(0);
  EXPECT_EQ(s.refused[node_status_t::REFUSED_IMPLAUSIBLE], 1);
  EXPECT_EQ(s.refused[node_status_t::REFUSED_OUTSIDE_TEAM], 1);
  EXPECT_EQ(s.refused[node_status_t::REFUSED_DUPLICATE_ID], 1);
  EXPECT_EQ(s.rejected_inputs, 3);
  EXPECT_EQ(s.fault_flags & node_status_t::FAULT_CAPACITY, 0);
}

// The state file is checked like a message: denormal or negative covariances,
// seq beyond 2^62, positions beyond the world bound, robots outside the team.
TEST(MainLimits, AbsurdStateFilesAreRefusedAndTheMapKept) {
  GlobalMap m(options("1,2"));
  GlobalEvent e;
  e.robot_id = 1;
  e.seq = 1;
  e.kind = landmark_event_t::ADD;
  e.landmark_id = 2;
  e.position = {1.0, 1.0};
  e.cov = Eigen::Matrix2d::Identity() * 0.01;
  m.apply(e, nullptr);
  const std::string good = m.to_json();
  const auto spoiled = [&](const std::string& from, const std::string& to) {
    std::string t = good;
    const auto at = t.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return t.replace(at, from.size(), to);
  };
  struct Case {
    std::string from, to, expect;
  };
  const std::vector<Case> cases = {
      {"0.01,", "1e-320,", "cov_floor_m2"},
      {"0.01,", "-0.01,", "cov_floor_m2"},
      {"\"last_seq\": 1", "\"last_seq\": 9223372036854775807", "last_seq"},
      {"\"last_seq\": 1", "\"last_seq\": 1.5", "last_seq"},
      {"\"x\": 1.0", "\"x\": 1e300", "world_bound_m"},
      {"\"robot\": 1", "\"robot\": 3", "limits.team"},
  };
  for (const Case& c : cases) {
    std::string why;
    EXPECT_FALSE(m.from_json(spoiled(c.from, c.to), &why)) << c.to;
    EXPECT_NE(why.find(c.expect), std::string::npos) << c.to << ": " << why;
  }
  EXPECT_EQ(m.to_json(), good);
}

// main's max_landmark_id smaller than the robots' was not caught at start-up: main
// refused every event about the ids between, at run time.
TEST(MainLimits, ConfigMismatchesBetweenSectionsAreFoundAtStartUp) {
  const std::string path = ::testing::TempDir() + "/main_limits_config.yaml";
  const auto write = [&](const std::string& text) {
    FILE* f = std::fopen(path.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs(text.c_str(), f);
    std::fclose(f);
  };
  write("robot:\n  filter: {max_landmark_id: 256}\nmain:\n  max_landmark_id: 64\n");
  auto problems = check_shared_config(path);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].find("main.max_landmark_id (64)"), std::string::npos) << problems[0];
  write("robot:\n  filter: {max_landmark_id: 64}\n  limits: {team: \"1,2\"}\nmain:\n  max_landmark_id: 64\n"
        "  limits: {team: \"1,2,3\"}\n");
  problems = check_shared_config(path);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].find("limits.team"), std::string::npos) << problems[0];
  // The robots fuse a team map that main never sends.
  write("robot:\n  team_map: {fuse: true}\nmain:\n  max_landmark_id: 64\n");
  problems = check_shared_config(path);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].find("team_map_period_frames is absent"), std::string::npos) << problems[0];
  write("robot:\n  team_map: {fuse: true}\nmain:\n  team_map_period_frames: 0\n");
  ASSERT_EQ(check_shared_config(path).size(), 1u);
  write("robot:\n  team_map: {fuse: true}\nmain:\n  team_map_period_frames: 10\n");
  EXPECT_TRUE(check_shared_config(path).empty());
  write("robot:\n  filter: {max_landmark_id: 64}\nmain:\n  max_landmark_id: 64\n");
  EXPECT_TRUE(check_shared_config(path).empty());
  std::remove(path.c_str());
}

}  // namespace
}  // namespace elaslam

namespace elaslam {
namespace {

pose_estimate_t pose_of(int robot, int frame, std::int64_t incarnation) {
  pose_estimate_t p = test::pose_msg(robot, frame);
  p.incarnation = incarnation;
  return p;
}

// A robot restarted with a smaller incarnation than the one main followed (its state
// directory lost, another computer, a clock set back): main refused all its events as
// an older incarnation (26 static landmarks instead of 36). Now its messages are
// refused, flagged (FAULT_INCARNATION) and said while the followed one might be alive;
// once the new one's frames run on past the followed one's, which is no longer heard,
// main follows it as a restart. A replay of old frames never gets past it.
TEST(MainIncarnations, ARobotWhoseIncarnationWentBackIsFollowedOnceItsOldOneIsQuiet) {
  MainNode main(options());
  for (int f = 0; f < 20; ++f) ASSERT_GE(main.on_pose(pose_of(2, f, 9000), nullptr), -1);
  // Replays of the old incarnation's frames: never taken.
  for (int f = 5; f < 12; ++f) main.on_pose(pose_of(2, f, 3000), nullptr);
  EXPECT_EQ(main.counters().restarts, 0);
  EXPECT_TRUE(main.status_msg(0).fault_flags & node_status_t::FAULT_INCARNATION);
  EXPECT_NE(main.take_alert().find("incarnation 3000 refused"), std::string::npos);
  // A new process with a smaller incarnation, frames running on past 19 while 9000 is silent.
  std::string why;
  for (int f = 20; f < 23; ++f) EXPECT_LT(main.on_pose(pose_of(2, f, 500), &why), 0) << f;
  EXPECT_EQ(main.counters().restarts, 0);
  main.on_pose(pose_of(2, 23, 500), &why);
  EXPECT_EQ(main.counters().restarts, 1);
  EXPECT_EQ(main.map().stream(2).incarnation, 500);
  EXPECT_NE(main.take_alert().find("older than the one followed"), std::string::npos);
  // The followed incarnation is now 500: its POSEs count.
  EXPECT_EQ(main.counters().stale_incarnation, 7 + 3);
}

TEST(MainIncarnations, AnOlderIncarnationThatKeepsPaceIsASecondSenderNotARestart) {
  MainNode main(options());
  for (int f = 0; f < 30; ++f) {
    main.on_pose(pose_of(3, f, 9000), nullptr);
    if (f >= 10) main.on_pose(pose_of(3, f, 500), nullptr);  // a copy of the robot, both alive
  }
  EXPECT_EQ(main.counters().restarts, 0);
  EXPECT_EQ(main.map().stream(3).incarnation, 9000);
  EXPECT_TRUE(main.status_msg(0).fault_flags & node_status_t::FAULT_DUPLICATE_SENDER);
}

TEST(MainFaults, ARobotHeardAgainAfterAGapAndAFailedSaveAreFlagged) {
  MainNode main(options());
  for (int f = 0; f < 10; ++f) main.on_pose(pose_of(1, f, 7), nullptr);
  EXPECT_FALSE(main.status_msg(0).fault_flags & node_status_t::FAULT_PARTITION_HEALED);
  main.on_pose(pose_of(1, 10 + MainNode::kPartitionFrames + 1, 7), nullptr);  // 11 frames missing
  EXPECT_TRUE(main.status_msg(0).fault_flags & node_status_t::FAULT_PARTITION_HEALED);
  EXPECT_NE(main.take_alert().find("heard again"), std::string::npos);
  main.note_save(false, "global_map.json: No space left on device");
  EXPECT_TRUE(main.status_msg(0).fault_flags & node_status_t::FAULT_SAVE_FAILED);
  EXPECT_NE(main.take_alert().find("No space left"), std::string::npos);
  main.note_save(true, "");
  EXPECT_FALSE(main.status_msg(0).fault_flags & node_status_t::FAULT_SAVE_FAILED);
}

}  // namespace
}  // namespace elaslam

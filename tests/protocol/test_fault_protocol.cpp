// SPDX-License-Identifier: Apache-2.0
// The rules that make the team's messages survive loss, restarts and duplicates:
// chunking, chunk loss and reordering at main_robot, incarnations,
// a second sender with one robot id, resync requests, and notices repaired from
// GLOBAL_MAP. Robot nodes and main_robot are driven directly with messages, in a
// simulated 50 %-dynamism world, so each rule is seen on real maps.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <vector>

#include "elaslam/common/chunks.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/main_robot/main_node.hpp"
#include "elaslam/robot_node/robot_node.hpp"
#include "elaslam/simulator/messages.hpp"
#include "elaslam/simulator/world.hpp"
#include "elaslam/team/team_config.hpp"

namespace elaslam {
namespace {

// ---- the chunk cutter ---------------------------------------------------------------

TEST(Chunks, CoverTheIdSpaceWithoutOverlapAndStayWithinTheBudget) {
  std::mt19937 rng(3);
  const ChunkSizes s{60, 52, 4, 1200};
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<int> a, b;
    for (int id = 0; id < 1000; ++id) {
      const unsigned r = rng() % 10;
      if (r < 3) {
        a.push_back(id);
      } else if (r < 4) {
        b.push_back(id);
      }
    }
    std::vector<ChunkSpan> out;
    cut_chunks(a.data(), static_cast<int>(a.size()), b.data(), static_cast<int>(b.size()), s, 1000, &out);
    ASSERT_FALSE(out.empty());
    EXPECT_LE(static_cast<int>(out.size()), max_chunks(s, static_cast<int>(a.size()), static_cast<int>(b.size())));
    EXPECT_EQ(out.front().id_begin, 0);
    EXPECT_EQ(out.back().id_end, 1000);
    int na = 0, nb = 0;
    for (std::size_t k = 0; k < out.size(); ++k) {
      const ChunkSpan& c = out[k];
      if (k > 0) {
        EXPECT_EQ(c.id_begin, out[k - 1].id_end);
      }
      EXPECT_LT(c.id_begin, c.id_end);
      EXPECT_LE(s.fixed_bytes + c.count_a * s.a_bytes + c.count_b * s.b_bytes, s.budget);
      EXPECT_EQ(c.first_a, na);
      EXPECT_EQ(c.first_b, nb);
      for (int i = 0; i < c.count_a; ++i) {
        const int id = a[static_cast<std::size_t>(na + i)];
        EXPECT_TRUE(id >= c.id_begin && id < c.id_end);
      }
      na += c.count_a;
      nb += c.count_b;
    }
    EXPECT_EQ(na, static_cast<int>(a.size()));
    EXPECT_EQ(nb, static_cast<int>(b.size()));
  }
  std::vector<ChunkSpan> out;
  cut_chunks(nullptr, 0, nullptr, 0, s, 256, &out);  // an empty map: one empty chunk for every id
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].id_end, 256);
}

// ---- a team driven by hand -----------------------------------------------------------

class Team : public ::testing::Test {
 public:  // also driven by hand, two teams side by side (LossyTeam)
  void SetUp() override {
    cfg_ = load_team_config(std::string(ELASLAM_SOURCE_DIR) + "/config/paper.yaml");
    cfg_.scenario.dynamism_percent = 50.0;
    cfg_.scenario.landmark_speed_mps = 0.5;
    cfg_.robot.ekf.max_landmark_id = 1000;  // a sparse id space: several chunks
    cfg_.main.max_landmark_id = 1000;
    world_ = std::make_unique<sim::World>(cfg_.scenario);
    for (int i = 0; i < world_->num_robots(); ++i) {
      robots_.emplace_back(cfg_.robot, cfg_.scenario.robots[static_cast<std::size_t>(i)].id);
      robots_.back().set_incarnation(100 + i);
    }
    main_ = std::make_unique<MainNode>(cfg_.main);
  }

  // The simulator's ids are 0..71: spread them over 0..999 so a map needs chunks.
  static void spread(sensor_frame_t* m) {
    for (int k = 0; k < m->num_obs; ++k) m->obs[static_cast<std::size_t>(k)].landmark_id *= 13;
  }

  /// One frame of every robot; `deliver(robot index, chunk or event)` decides what
  /// reaches main_robot (loss). Notices and the global map reach every robot.
  template <class Lose>
  void frame(Lose lose) {
    if (k_ > 0) world_->step();
    for (std::size_t i = 0; i < robots_.size(); ++i) {
      sensor_frame_t s = sim::to_message(world_->sensor_frame(static_cast<int>(i)), k_);
      spread(&s);
      RobotNode& r = robots_[i];
      if (r.on_sensor(s, k_) != RobotNode::Verdict::kProcessed) continue;
      for (const auto& e : r.event_msgs())
        if (!lose(e.seq)) main_->on_event(e);
      if (r.snapshot_ready())
        for (int c = 0; c < r.num_snapshot_chunks(); ++c)
          if (!lose(-1)) main_->on_snapshot(r.snapshot_chunk(c));
      main_->on_pose(r.pose_msg());
      for (const auto& q : main_->take_resyncs(k_))
        for (auto& rr : robots_)
          if (rr.on_resync(q, k_))
            for (int c = 0; c < rr.num_snapshot_chunks(); ++c) main_->on_snapshot(rr.snapshot_chunk(c));
      for (const auto& n : main_->take_notices(k_))
        for (auto& rr : robots_)
          if (!lose(-2)) rr.on_notice(n);
    }
    const int chunks = main_->make_global_map(k_);
    for (int c = 0; c < chunks; ++c)
      for (auto& r : robots_) r.on_global_map(main_->map_chunk(c));
    ++k_;
  }
  void frames(int n) {
    for (int i = 0; i < n; ++i) frame([](std::int64_t) { return false; });
  }

  std::set<int> static_ids() const {
    std::set<int> ids;
    for (int id = 0; id < main_->map().max_landmark_id(); ++id)
      if (main_->map().entry(id).status == GlobalStatus::kStatic) ids.insert(id);
    return ids;
  }
  std::set<int> moving_ids() const {
    std::set<int> ids;
    for (int id = 0; id < main_->map().max_landmark_id(); ++id)
      if (main_->map().entry(id).status == GlobalStatus::kMoving) ids.insert(id);
    return ids;
  }

  TeamConfig cfg_;
  std::unique_ptr<sim::World> world_;
  std::vector<RobotNode> robots_;
  std::unique_ptr<MainNode> main_;
  int k_ = 0;
};

TEST_F(Team, SnapshotsComeInChunksThatEachFitADatagram) {
  frames(60);
  RobotNode& r = robots_[0];
  ASSERT_GE(r.make_snapshot(0), 1);
  int landmarks = 0;
  for (int c = 0; c < r.num_snapshot_chunks(); ++c) {
    const lmap_snapshot_t& m = r.snapshot_chunk(c);
    EXPECT_LE(m.getEncodedSize(), contract::kMaxChunkBytes);
    EXPECT_EQ(m.chunk, c);
    EXPECT_EQ(m.num_chunks, r.num_snapshot_chunks());
    landmarks += m.num_landmarks;
  }
  EXPECT_GT(landmarks, 10);
  EXPECT_EQ(r.num_snapshot_chunks() > 1, landmarks > 22);  // 22 landmarks of 52 bytes fit 1,200 bytes
  const int n = main_->make_global_map(0);
  ASSERT_GT(n, 1);  // the team's map: more than one datagram
  for (int c = 0; c < n; ++c) EXPECT_LE(main_->map_chunk(c).getEncodedSize(), contract::kMaxChunkBytes);
}

// Chunks applied in any order give the map the whole snapshot gives; a gap stays
// pending until chunks taken after it have covered every id.
TEST(GlobalMapChunks, OrderDoesNotMatterAndAGapNeedsEveryRange) {
  GlobalMapOptions o;
  o.max_landmark_id = 30;
  auto est = [](double x) { return RobotEstimate{true, {x, 1.0}, Eigen::Matrix2d::Identity() * 0.01, 10}; };
  GlobalMap whole(o), chunked(o);
  std::vector<Notice> notices;
  GlobalEvent e;
  e.robot_id = 1, e.kind = landmark_event_t::ADD, e.landmark_id = 4, e.frame = 1, e.cov = Eigen::Matrix2d::Identity();
  for (GlobalMap* m : {&whole, &chunked}) {
    e.seq = 1;
    m->apply(e, &notices);
    e.seq = 5;  // 2..4 lost
    e.landmark_id = 12;
    m->apply(e, &notices);
    e.landmark_id = 4;
  }
  ASSERT_TRUE(chunked.stream(1).gap_pending);
  whole.apply_snapshot(1, 5, 10, {{3, est(3)}, {12, est(12)}, {25, est(25)}}, {}, &notices);
  EXPECT_FALSE(whole.stream(1).gap_pending);
  chunked.apply_snapshot(1, 5, 10, 20, 30, {{25, est(25)}}, {}, {}, &notices);  // the last range first
  chunked.apply_snapshot(1, 5, 10, 0, 10, {{3, est(3)}}, {}, {}, &notices);
  EXPECT_TRUE(chunked.stream(1).gap_pending);  // ids 10..19 not covered yet
  chunked.apply_snapshot(1, 5, 10, 10, 20, {{12, est(12)}}, {}, {}, &notices);
  EXPECT_FALSE(chunked.stream(1).gap_pending);
  for (int id = 0; id < 30; ++id) {
    EXPECT_EQ(whole.entry(id).status, chunked.entry(id).status) << id;
    EXPECT_EQ(whole.entry(id).by_robot[0].valid, chunked.entry(id).by_robot[0].valid) << id;
  }
  EXPECT_FALSE(chunked.entry(4).by_robot[0].valid);  // not in the snapshot: no longer in robot 1's map
  // An older snapshot after a newer one is ignored (it would roll the map back).
  EXPECT_FALSE(chunked.apply_snapshot(1, 4, 9, 0, 10, {}, {}, {}, &notices));
  EXPECT_TRUE(chunked.entry(3).by_robot[0].valid);
}

// A MOVING event lost for a landmark the finder never had static (a candidate found
// moving), while another robot holds it: the finder's snapshot lists it with the frame
// it was found moving. Newer than the map's last status change: the event's stand-in;
// older (the other robot took it back since): a stale listing, kept static.
TEST(GlobalMapChunks, AListedFindingNewerThanTheMapStandsInForALostMovingEvent) {
  GlobalMapOptions o;
  o.max_landmark_id = 30;
  std::vector<Notice> notices;
  for (const int found : {40, 10}) {
    SCOPED_TRACE(found);
    GlobalMap m(o);
    GlobalEvent g;  // 7 moved before: robot 3 found it moving at 15, robot 2 took it back at 20
    g.landmark_id = 7, g.cov = Eigen::Matrix2d::Identity() * 0.01;
    g.robot_id = 2, g.seq = 1, g.kind = landmark_event_t::ADD, g.frame = 5;
    m.apply(g, &notices);
    g.robot_id = 3, g.seq = 1, g.kind = landmark_event_t::MOVING, g.frame = 15;
    m.apply(g, &notices);
    g.robot_id = 2, g.seq = 2, g.kind = landmark_event_t::RETURN, g.frame = 20;
    m.apply(g, &notices);
    ASSERT_EQ(m.entry(7).status, GlobalStatus::kStatic);
    GlobalEvent e;
    e.robot_id = 1, e.seq = 1, e.kind = landmark_event_t::ADD, e.landmark_id = 3, e.frame = 5;
    e.cov = Eigen::Matrix2d::Identity() * 0.01;
    m.apply(e, &notices);
    e.seq = 3, e.landmark_id = 4, e.frame = 41;  // robot 1's seq 2 (MOVING of 7) lost
    m.apply(e, &notices);
    notices.clear();
    m.apply_snapshot(1, 3, 42, 0, 30, {}, {7}, {found}, &notices);
    if (found > 20) {
      EXPECT_EQ(m.entry(7).status, GlobalStatus::kMoving);
      ASSERT_EQ(notices.size(), 1u);  // the other robots are told
      EXPECT_EQ(notices[0].landmark_id, 7);
      // ...of the frame it was found moving, not the snapshot's: a robot that took
      // it back between the two must not drop it (its notice guard compares frames).
      EXPECT_EQ(notices[0].frame, 40);
      EXPECT_EQ(m.entry(7).status_frame, 40);
    } else {
      EXPECT_EQ(m.entry(7).status, GlobalStatus::kStatic);
      EXPECT_TRUE(notices.empty());
    }
  }
}

landmark_event_t event(int robot, std::int64_t incarnation, std::int64_t seq, int id, int frame) {
  landmark_event_t m{};
  m.robot_id = static_cast<std::int16_t>(robot);
  m.incarnation = incarnation;
  m.seq = seq;
  m.frame = frame;
  m.kind = landmark_event_t::ADD;
  m.landmark_id = id;
  m.x = 1.0;
  m.cov[0][0] = m.cov[1][1] = 0.01;
  return m;
}

TEST(Incarnations, ARestartStartsTheStreamOverAndAsksForASnapshot) {
  GlobalMapOptions o;
  o.max_landmark_id = 32;
  MainNode main(o);
  for (int s = 1; s <= 3; ++s) ASSERT_TRUE(main.on_event(event(2, 500, s, s, s)));
  EXPECT_TRUE(main.take_resyncs(0).empty());
  // Restarted without its state: seq 1 again, a newer incarnation. Applied, not a duplicate.
  ASSERT_TRUE(main.on_event(event(2, 900, 1, 7, 20)));
  EXPECT_EQ(main.counters().duplicates, 0);
  EXPECT_EQ(main.counters().restarts, 1);
  EXPECT_TRUE(main.map().entry(7).by_robot[1].valid);
  const auto& q = main.take_resyncs(0);
  ASSERT_EQ(q.size(), 1u);
  EXPECT_EQ(q[0].robot_id, 2);
  EXPECT_EQ(q[0].reason, resync_request_t::NEW_INCARNATION);
  EXPECT_NE(main.take_alert().find("restarted"), std::string::npos);
  // The old incarnation again: a replay, refused.
  std::string why;
  EXPECT_FALSE(main.on_event(event(2, 500, 4, 9, 21), &why));
  EXPECT_NE(why.find("older incarnation"), std::string::npos);
  EXPECT_FALSE(main.map().entry(9).by_robot[1].valid);
  EXPECT_FALSE(main.status_msg(0).fault_flags & node_status_t::FAULT_DUPLICATE_SENDER);
  // It keeps talking: two live senders with id 2, flagged loudly.
  for (int s = 5; s <= 7; ++s) main.on_event(event(2, 500, s, 9, 20 + s));
  const node_status_t st = main.status_msg(0);
  EXPECT_TRUE(st.fault_flags & node_status_t::FAULT_DUPLICATE_SENDER);
  EXPECT_EQ(st.duplicate_robots, 1 << 1);
  EXPECT_NE(main.take_alert().find("two live senders"), std::string::npos);
}

TEST(Incarnations, ARobotSeesASecondSenderOfItsPose) {
  const TeamConfig cfg = load_team_config(std::string(ELASLAM_SOURCE_DIR) + "/config/paper.yaml");
  RobotNode r(cfg.robot, 2);
  r.set_incarnation(7);
  EXPECT_FALSE(r.on_own_channel(7, 0));  // its own, looped back
  EXPECT_EQ(r.status_msg(0).fault_flags, 0);
  EXPECT_TRUE(r.on_own_channel(8, 0));  // started after this one: at once
  EXPECT_FALSE(r.on_own_channel(8, 1));  // said once, not every frame
  EXPECT_TRUE(r.status_msg(0).fault_flags & node_status_t::FAULT_DUPLICATE_SENDER);
}

// A robot restarted as a new process may still hear its dead predecessor's last
// datagrams (late on a slow link): they were flagged as a second live sender. An
// older incarnation is one only when it goes on to new frames.
TEST(Incarnations, APredecessorsLateDatagramsAreNotASecondSender) {
  const TeamConfig cfg = load_team_config(std::string(ELASLAM_SOURCE_DIR) + "/config/paper.yaml");
  RobotNode r(cfg.robot, 2);
  r.set_incarnation(7);
  for (int f : {40, 41, 41, 40}) EXPECT_FALSE(r.on_own_channel(5, f)) << f;  // the predecessor's last frames
  EXPECT_EQ(r.status_msg(0).fault_flags, 0);
  EXPECT_EQ(r.counters().foreign_poses, 4);
  // A live older process keeps going: its third new frame is a second sender.
  EXPECT_TRUE(r.on_own_channel(5, 42));
  EXPECT_TRUE(r.status_msg(0).fault_flags & node_status_t::FAULT_DUPLICATE_SENDER);
}

// main_robot: the same for a robot that restarted without its state. Its old
// incarnation's datagrams of frames it had reached are late ones; new frames are a
// second sender.
TEST(Incarnations, MainTakesLateDatagramsOfAReplacedIncarnationForLateNotForASecondSender) {
  GlobalMapOptions o;
  o.max_landmark_id = 32;
  MainNode main(o);
  for (int s = 1; s <= 5; ++s) ASSERT_TRUE(main.on_event(event(2, 500, s, s, 10 + s)));  // frames 11-15
  ASSERT_TRUE(main.on_event(event(2, 900, 1, 7, 16)));  // restarted
  for (int f : {13, 14, 15, 15, 12}) EXPECT_FALSE(main.on_event(event(2, 500, 6, 9, f))) << f;
  EXPECT_FALSE(main.status_msg(0).fault_flags & node_status_t::FAULT_DUPLICATE_SENDER);
  EXPECT_EQ(main.counters().stale_incarnation, 5);
  for (int f : {16, 17}) EXPECT_FALSE(main.on_event(event(2, 500, 6, 9, f)));
  EXPECT_FALSE(main.status_msg(0).fault_flags & node_status_t::FAULT_DUPLICATE_SENDER);
  EXPECT_FALSE(main.on_event(event(2, 500, 6, 9, 18)));  // a third new frame: it is alive
  EXPECT_TRUE(main.status_msg(0).fault_flags & node_status_t::FAULT_DUPLICATE_SENDER);
}

TEST(Resync, AGapAsksOnceThenAgainAfterTheInterval) {
  GlobalMapOptions o;
  o.max_landmark_id = 32;
  o.resync_interval_frames = 5;
  MainNode main(o);
  ASSERT_TRUE(main.on_event(event(1, 3, 1, 1, 1)));
  ASSERT_TRUE(main.on_event(event(1, 3, 4, 2, 2)));  // 2, 3 lost
  auto q = main.take_resyncs(0);
  ASSERT_EQ(q.size(), 1u);
  EXPECT_EQ(q[0].reason, resync_request_t::GAP);
  EXPECT_EQ(q[0].after_seq, 4);
  pose_estimate_t p{};
  p.robot_id = 1;
  p.incarnation = 3;
  for (int f = 2; f < 6; ++f) {
    p.frame = f;
    main.on_pose(p);
  }
  EXPECT_TRUE(main.take_resyncs(0).empty());  // within the interval
  p.frame = 7;
  main.on_pose(p);
  EXPECT_EQ(main.take_resyncs(0).size(), 1u);  // still unrepaired: asked again
  EXPECT_TRUE(main.status_msg(0).fault_flags & node_status_t::FAULT_UNREPAIRED_GAP);
}

TEST_F(Team, ARobotAnswersAResyncOncePerFrame) {
  frames(12);
  resync_request_t q{};
  q.robot_id = 2;
  EXPECT_FALSE(robots_[0].on_resync(q, 0));  // not robot 1's
  EXPECT_TRUE(robots_[1].on_resync(q, 0));
  EXPECT_GE(robots_[1].num_snapshot_chunks(), 1);
  EXPECT_FALSE(robots_[1].on_resync(q, 0));  // again in the same frame
  frames(1);
  EXPECT_TRUE(robots_[1].on_resync(q, 0));
}

// A robot that never got a notice learns it from the next GLOBAL_MAP chunk; a
// second map does not apply it twice; a notice older than the robot's own view of
// the landmark is not applied.
TEST_F(Team, ALostNoticeIsRepairedFromTheGlobalMap) {
  frames(30);
  RobotNode& r = robots_[0];
  int held = -1;
  for (int id = 0; id < r.robot().lmap().size() && held < 0; ++id)
    if (r.robot().lmap()[id].status == LandmarkStatus::kStatic && r.robot().filter().has_landmark(id)) held = id;
  ASSERT_GE(held, 0);
  global_map_t g{};
  g.num_chunks = 1;
  g.id_end = 1000;
  contract::set_count(&g.moving_ids, &g.num_moving, 1);
  g.moving_frames.assign(1, r.robot().lmap()[held].status_frame - 1);
  g.moving_by.assign(1, 3);
  g.moving_ids[0] = held;
  ASSERT_TRUE(r.on_global_map(g));
  EXPECT_EQ(r.counters().notices_repaired, 0);  // older than the robot's own view
  g.moving_frames[0] = k_ - 1;
  ASSERT_TRUE(r.on_global_map(g));
  EXPECT_EQ(r.counters().notices_repaired, 1);
  EXPECT_FALSE(r.robot().filter().has_landmark(held));
  ASSERT_TRUE(r.on_global_map(g));
  EXPECT_EQ(r.counters().notices_repaired, 1);
  g.moving_by[0] = 9;
  std::string why;
  EXPECT_FALSE(r.on_global_map(g, &why));
  EXPECT_NE(why.find("moving_by"), std::string::npos);
}

// 30 % of the events, snapshot chunks and notices lost on the way: after the repair
// (resync requests, snapshot chunks, the global map's moving set) main's map is the
// lossless run's within 2 static landmarks, and every landmark the lossless team
// found moving is out of its static set.
TEST(LossyTeam, ThirtyPercentLossIsRepaired) {
  struct Run : Team {
    void TestBody() override {}
  };
  Run lossless, lossy;
  lossless.SetUp();
  lossy.SetUp();
  std::mt19937 rng(11);
  lossless.frames(150);
  for (int f = 0; f < 140; ++f) lossy.frame([&](std::int64_t) { return rng() % 100 < 30; });
  lossy.frames(10);  // the last frames lossless: time for the last repairs
  const std::set<int> a = lossless.static_ids(), b = lossy.static_ids();
  std::vector<int> diff;
  std::set_symmetric_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(diff));
  EXPECT_LE(diff.size(), 2u) << a.size() << " static without loss, " << b.size() << " with";
  for (int id : lossless.moving_ids()) EXPECT_EQ(b.count(id), 0u) << "moving landmark " << id << " left in the map";
  EXPECT_GT(lossy.main_->counters().resyncs_requested, 0);
  EXPECT_GT(lossy.main_->counters().gaps, 0);
  for (int s = 1; s <= 3; ++s) EXPECT_FALSE(lossy.main_->map().stream(s).gap_pending);
}

}  // namespace
}  // namespace elaslam

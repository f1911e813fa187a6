// SPDX-License-Identifier: Apache-2.0
// The robot node's message layer: every bad message is counted and dropped without
// touching the filter; duplicated and reordered frames are refused; gaps are bridged.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <random>

#include <Eigen/Geometry>

#include "elaslam/robot_node/robot_node.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/common/cov.hpp"
#include "scene.hpp"

namespace elaslam {
namespace {

using test::to_msg;

class RobotNodeInput : public ::testing::Test {
 protected:
  RobotNodeInput() : node_(test::robot_options(Mode::kEla), 2), lms_(test::ring(6, 3.0)) {}
  sensor_frame_t frame(int k, double x = 0.0) {
    const Pose2 p{x, 0.0, 0.0};
    return to_msg(test::frame_from(k, p, p, lms_, test::all_ids(6)), 2);
  }
  void run(int from, int to) {
    for (int k = from; k < to; ++k) ASSERT_EQ(node_.on_sensor(frame(k, 0.01 * k), 0), RobotNode::Verdict::kProcessed);
  }
  // The filter's whole state, to check that a refused message changed nothing.
  Eigen::VectorXd state() const {
    const EkfSlam& f = node_.robot().filter();
    Eigen::VectorXd v(f.mean().size() + f.covariance().size());
    v << f.mean(), f.covariance().reshaped();
    return v;
  }
  RobotNode node_;
  std::vector<Eigen::Vector2d> lms_;
};

TEST_F(RobotNodeInput, EveryKindOfBadMessageIsRefusedAndCounted) {
  run(0, 5);
  const Eigen::VectorXd before = state();
  const int lm_before = node_.robot().filter().num_landmarks();
  struct Case {
    const char* name;
    std::function<void(sensor_frame_t&)> spoil;
    const char* expect;
  };
  const std::vector<Case> cases = {
      {"NaN range", [](sensor_frame_t& m) { m.obs[1].range = std::nan(""); }, "range"},
      {"negative range", [](sensor_frame_t& m) { m.obs[0].range = -1.0; }, "range"},
      {"bearing out of range", [](sensor_frame_t& m) { m.obs[2].bearing = 4.0; }, "bearing"},
      {"unknown id", [](sensor_frame_t& m) { m.obs[3].landmark_id = 64; }, "landmark_id"},
      {"negative id", [](sensor_frame_t& m) { m.obs[3].landmark_id = -1; }, "landmark_id"},
      {"too many observations", [](sensor_frame_t& m) { m.num_obs = 65; }, "num_obs"},
      {"negative count", [](sensor_frame_t& m) { m.num_obs = -1; }, "num_obs"},
      {"wrong robot", [](sensor_frame_t& m) { m.robot_id = 3; }, "robot_id"},
      {"NaN odometer", [](sensor_frame_t& m) { m.odom_theta = std::nan(""); }, "odometer"},
      {"infinite odometer", [](sensor_frame_t& m) { m.odom_x = INFINITY; }, "odometer"},
      {"negative odometry noise", [](sensor_frame_t& m) { m.odom_var_rot_per_m = -1e-3; }, "noise"},
      {"same landmark twice", [](sensor_frame_t& m) { m.obs[1].landmark_id = m.obs[0].landmark_id; }, "twice"},
      {"frame far ahead", [](sensor_frame_t& m) { m.frame = 100000; }, "max_frame_gap"},
      {"negative frame", [](sensor_frame_t& m) { m.frame = -3; }, "frame"},
  };
  int refused = 0;
  for (const Case& c : cases) {
    sensor_frame_t m = frame(5);
    c.spoil(m);
    std::string why;
    EXPECT_EQ(node_.on_sensor(m, 0, &why), RobotNode::Verdict::kInvalid) << c.name;
    EXPECT_NE(why.find(c.expect), std::string::npos) << c.name << ": " << why;
    ++refused;
    EXPECT_EQ(state(), before) << c.name;
  }
  EXPECT_EQ(node_.counters().rejected_inputs, refused);
  EXPECT_EQ(node_.robot().filter().num_landmarks(), lm_before);
  // The next good frame goes through as usual.
  EXPECT_EQ(node_.on_sensor(frame(5, 0.05), 0), RobotNode::Verdict::kProcessed);
}

TEST_F(RobotNodeInput, DuplicatedAndReorderedFramesAreDroppedAndCounted) {
  run(0, 6);
  const Eigen::VectorXd before = state();
  EXPECT_EQ(node_.on_sensor(frame(5, 0.05), 0), RobotNode::Verdict::kDuplicate);
  EXPECT_EQ(node_.on_sensor(frame(3, 0.03), 0), RobotNode::Verdict::kOutOfOrder);
  EXPECT_EQ(state(), before);
  EXPECT_EQ(node_.counters().frames_duplicate, 1);
  EXPECT_EQ(node_.counters().frames_out_of_order, 1);
  EXPECT_EQ(node_.status_msg(0).frames_dropped, 2);
}

TEST_F(RobotNodeInput, GapIsBridgedWithTheOdometer) {
  run(0, 6);
  // Frames 6..9 are lost; frame 10 arrives with the odometer 0.10 m along.
  ASSERT_EQ(node_.on_sensor(frame(10, 0.10), 0), RobotNode::Verdict::kProcessed);
  EXPECT_EQ(node_.counters().frames_gap, 4);
  EXPECT_NEAR(node_.pose_msg().x, 0.10, 1e-3);
  EXPECT_EQ(node_.pose_msg().frame, 10);
}

TEST_F(RobotNodeInput, OutputsCarrySeqPoseAndPeriodicSnapshots) {
  run(0, 4);  // landmarks confirmed at frame 2 (ADD x6), then UPDATEs
  const auto& ev = node_.event_msgs();
  ASSERT_EQ(ev.size(), 6u);
  EXPECT_EQ(ev.front().seq, 7);  // seq 1..6 were the ADDs of frame 2
  EXPECT_EQ(ev.front().kind, landmark_event_t::UPDATE);
  EXPECT_EQ(ev.front().robot_id, 2);
  EXPECT_EQ(node_.pose_msg().source_utime, 1003);
  EXPECT_EQ(node_.pose_msg().num_landmarks, 6);
  EXPECT_FALSE(node_.snapshot_ready());
  run(4, 11);  // frame 10: snapshot (period 10)
  ASSERT_TRUE(node_.snapshot_ready());
  ASSERT_EQ(node_.num_snapshot_chunks(), 1);  // 6 landmarks fit one datagram
  EXPECT_EQ(node_.snapshot_chunk(0).num_landmarks, 6);
  EXPECT_EQ(node_.snapshot_chunk(0).seq, node_.event_msgs().back().seq);
  EXPECT_EQ(node_.snapshot_chunk(0).id_begin, 0);
  EXPECT_EQ(node_.snapshot_chunk(0).id_end, node_.robot().lmap().size());  // max_landmark_id
}

// LMAP_EVENTS (robot.node.batch_events): a frame's events, cut into messages of at
// most kMaxBatchEvents, are event_msgs() in order, field for field, under a header
// that matches every event; the stamp reaches all of them. 40 landmarks confirmed in
// one frame: 40 ADDs in three messages (14, 14, 12).
TEST(RobotNodeBatches, AFramesEventsGoInMessagesOfAtMostTheBatchSize) {
  RobotNode node(test::robot_options(Mode::kEla), 2);
  const auto lms = test::ring(40, 3.0);
  const Pose2 p{0.0, 0.0, 0.0};
  for (int k = 0; k < 3; ++k) {
    ASSERT_EQ(node.on_sensor(to_msg(test::frame_from(k, p, p, lms, test::all_ids(40)), 2), 0), RobotNode::Verdict::kProcessed);
    if (k < 2) {
      EXPECT_EQ(node.num_event_batches(), 0) << "no event, no message";
    }
  }
  const auto& ev = node.event_msgs();
  ASSERT_EQ(ev.size(), 40u);
  constexpr int kB = contract::kMaxBatchEvents;
  ASSERT_EQ(kB, 14);
  ASSERT_EQ(node.num_event_batches(), 3);
  node.stamp_events(777);
  std::size_t next = 0;
  for (int b = 0; b < node.num_event_batches(); ++b) {
    const lmap_events_t& m = node.event_batch(b);
    EXPECT_EQ(m.num_events, b < 2 ? kB : 40 - 2 * kB);
    ASSERT_EQ(m.events.size(), static_cast<std::size_t>(m.num_events));
    EXPECT_EQ(m.robot_id, 2);
    EXPECT_EQ(m.frame, 2);
    EXPECT_EQ(m.incarnation, node.incarnation());
    EXPECT_EQ(m.utime, 777);
    for (const landmark_event_t& e : m.events) {
      const landmark_event_t& s = ev[next++];
      EXPECT_EQ(e.seq, s.seq);
      EXPECT_EQ(e.kind, landmark_event_t::ADD);
      EXPECT_EQ(e.landmark_id, s.landmark_id);
      EXPECT_EQ(e.x, s.x);
      EXPECT_EQ(e.y, s.y);
      EXPECT_EQ(e.cov[0][1], s.cov[0][1]);
      EXPECT_EQ(e.cov[1][1], s.cov[1][1]);
      EXPECT_EQ(e.frame, m.frame);
      EXPECT_EQ(e.robot_id, m.robot_id);
      EXPECT_EQ(e.incarnation, m.incarnation);
      EXPECT_EQ(e.utime, 777);
      EXPECT_EQ(s.utime, 777);
    }
    // One datagram each (contract::kMaxChunkBytes), as the snapshot chunks.
    EXPECT_LE(m.getEncodedSize(), contract::kMaxChunkBytes);
  }
  EXPECT_EQ(next, ev.size());
  EXPECT_EQ(ev.back().seq, 40);
  // The next frame's UPDATEs replace them: 40 of them, three messages again.
  ASSERT_EQ(node.on_sensor(to_msg(test::frame_from(3, p, p, lms, test::all_ids(40)), 2), 0), RobotNode::Verdict::kProcessed);
  EXPECT_EQ(node.num_event_batches(), 3);
  EXPECT_EQ(node.event_batch(0).events.front().seq, 41);
  EXPECT_EQ(node.event_batch(0).events.front().kind, landmark_event_t::UPDATE);
}

// CANDIDATES_<r>: the landmarks seen but not trusted yet, while there are some, and
// one empty list when the last one was confirmed.
TEST_F(RobotNodeInput, CandidatesAreSentWhileThereAreSomeThenOnceEmpty) {
  run(0, 1);
  ASSERT_TRUE(node_.candidates_ready());
  const candidate_list_t& c = node_.candidates_msg();
  EXPECT_EQ(c.robot_id, 2);
  EXPECT_EQ(c.frame, 0);
  ASSERT_EQ(c.num_candidates, 6);
  EXPECT_EQ(c.num_omitted, 0);
  for (int k = 0; k < c.num_candidates; ++k) {
    const landmark_estimate_t& l = c.candidates[static_cast<std::size_t>(k)];
    ASSERT_GE(l.id, 0);
    ASSERT_LT(l.id, 6);
    EXPECT_NEAR(l.x, lms_[static_cast<std::size_t>(l.id)].x(), 0.2);
    EXPECT_NEAR(l.y, lms_[static_cast<std::size_t>(l.id)].y(), 0.2);
    EXPECT_GT(l.cov[0][0], 0.0);
  }
  run(1, 2);
  ASSERT_TRUE(node_.candidates_ready());
  EXPECT_EQ(node_.candidates_msg().num_candidates, 6);
  run(2, 3);  // confirmed (ADD x6): the empty list clears a viewer's candidates
  ASSERT_TRUE(node_.candidates_ready());
  EXPECT_EQ(node_.candidates_msg().num_candidates, 0);
  run(3, 4);
  EXPECT_FALSE(node_.candidates_ready());

  RobotOptions off = test::robot_options(Mode::kEla);
  off.candidates_period_frames = 0;
  RobotNode quiet(off, 2);
  ASSERT_EQ(quiet.on_sensor(frame(0), 0), RobotNode::Verdict::kProcessed);
  EXPECT_FALSE(quiet.candidates_ready());
}

// The robot's confirmed tracks (MoverTrack::confirmed), in the pool's order: what
// TRACKS_<r> carries.
std::vector<int> confirmed_ids(const MoverTracks& pool) {
  std::vector<int> ids;
  for (const int id : pool.ids())
    if (pool.track(id).confirmed()) ids.push_back(id);
  return ids;
}

// TRACKS_<r>: a robot among six landmarks, one of which (2) moves at 0.8 m/s from
// frame 20 to 50 and then rests: while the robot tracks it, every frame's TRACKS
// lists exactly Robot::tracks()'s confirmed tracks (id, mean, covariance, model
// probabilities, flags); one empty list follows the track's end, then none.
TEST(RobotNodeTracks, TracksAreSentWhileThereAreSomeThenOnceEmpty) {
  RobotNode node(test::robot_options(Mode::kEla), 2);
  std::vector<Eigen::Vector2d> lms = test::ring(6, 3.0);
  const Eigen::Vector2d start = lms[2];
  std::mt19937_64 rng(7);
  int sent = 0, empty = 0, quiet_after_empty = 0;
  bool was_tracking = false;
  for (int f = 0; f < 120; ++f) {
    lms[2] = start + 0.08 * (std::clamp(f, 20, 50) - 20) * Eigen::Vector2d(0.0, 1.0);
    sensor_frame_t m = to_msg(test::frame_from(f, Pose2{}, Pose2{}, lms, test::all_ids(6), &rng), 2);
    m.utime = 1'700'000'000'000'000 + std::int64_t{100000} * f;
    ASSERT_EQ(node.on_sensor(m, 5000 + f), RobotNode::Verdict::kProcessed) << f;
    const MoverTracks& pool = node.robot().tracks();
    const std::vector<int> ids = confirmed_ids(pool);
    const bool tracking = !ids.empty();
    if (!tracking && !was_tracking) {
      EXPECT_EQ(node.num_track_chunks(), 0) << f;
      if (empty > 0) ++quiet_after_empty;
      continue;
    }
    ASSERT_EQ(node.num_track_chunks(), 1) << f;  // fewer tracks than one chunk holds
    const track_list_t& t = node.track_chunk(0);
    EXPECT_EQ(t.chunk, 0);
    EXPECT_EQ(t.num_chunks, 1);
    EXPECT_EQ(t.robot_id, 2);
    EXPECT_EQ(t.frame, f);
    EXPECT_EQ(t.utime, 5000 + f);
    EXPECT_EQ(t.incarnation, node.incarnation());
    EXPECT_EQ(t.num_omitted, 0);
    ASSERT_EQ(t.num_tracks, static_cast<int>(ids.size())) << f;
    if (t.num_tracks == 0) ++empty;
    for (int k = 0; k < t.num_tracks; ++k) {
      const track_t& m = t.tracks[static_cast<std::size_t>(k)];
      ASSERT_EQ(m.id, ids[static_cast<std::size_t>(k)]);
      const MoverTrack& want = pool.track(m.id);
      EXPECT_EQ(m.x, want.mean()(0));
      EXPECT_EQ(m.y, want.mean()(1));
      EXPECT_EQ(m.vx, want.mean()(2));
      EXPECT_EQ(m.vy, want.mean()(3));
      EXPECT_NEAR((read_cov_upper(m.cov) - want.covariance()).norm(), 0.0, 1e-6 * want.covariance().norm());
      for (std::size_t i = 0; i < 3; ++i) EXPECT_FLOAT_EQ(m.probabilities[i], static_cast<float>(want.probabilities()[i]));
      EXPECT_EQ(m.likeliest, static_cast<int>(want.likeliest()));
      EXPECT_EQ(m.stopped != 0, want.stopped());
      EXPECT_EQ(m.validated != 0, want.validated());
      EXPECT_EQ(m.sightings, want.sightings());
      if (m.id == 2 && f >= 30 && f < 50) {
        EXPECT_LT((Eigen::Vector2d(m.x, m.y) - lms[2]).norm(), 0.2) << f;
      }
    }
    ++sent;
    was_tracking = tracking;
  }
  EXPECT_GT(sent, 20);  // the mover was tracked for seconds
  EXPECT_EQ(empty, 1);  // one empty list when its track ended (RETURN)
  EXPECT_GT(quiet_after_empty, 5);
}

// More tracks than one datagram holds (15 movers): every frame's confirmed tracks all
// go out, in the pool's order, over ceil(n / kMaxTracks) chunks of one publication
// (each chunk's place, the shared frame, stamp and incarnation); none is omitted.
TEST(RobotNodeTracks, TracksBeyondOneChunkGoOutInSeveralNoneOmitted) {
  RobotNode node(test::robot_options(Mode::kEla), 2);
  const int n = 2 * (contract::kMaxTracks + 3);
  std::vector<Eigen::Vector2d> lms = test::ring(n, 3.0);
  const std::vector<Eigen::Vector2d> start = lms;
  std::mt19937_64 rng(3);
  int most = 0, most_chunks = 0;
  for (int f = 0; f < 60; ++f) {
    // Every other landmark (the rest hold the robot's pose) moves outward at 0.8 m/s from frame 20.
    for (int i = 0; i < n; i += 2)
      lms[static_cast<std::size_t>(i)] = start[static_cast<std::size_t>(i)] * (1.0 + 0.08 / 3.0 * (std::max(f, 20) - 20));
    sensor_frame_t m = to_msg(test::frame_from(f, Pose2{}, Pose2{}, lms, test::all_ids(n), &rng), 2);
    m.utime = 1'700'000'000'000'000 + std::int64_t{100000} * f;
    ASSERT_EQ(node.on_sensor(m, 7000 + f), RobotNode::Verdict::kProcessed) << f;
    const int chunks = node.num_track_chunks();
    if (chunks == 0) continue;
    const std::vector<int> want = confirmed_ids(node.robot().tracks());
    const int held = static_cast<int>(want.size());
    ASSERT_EQ(chunks, std::max(1, (held + contract::kMaxTracks - 1) / contract::kMaxTracks)) << f;
    std::vector<int> got;
    for (int c = 0; c < chunks; ++c) {
      const track_list_t& t = node.track_chunk(c);
      EXPECT_EQ(t.chunk, c);
      EXPECT_EQ(t.num_chunks, chunks);
      EXPECT_EQ(t.frame, f);
      EXPECT_EQ(t.utime, 7000 + f);
      EXPECT_EQ(t.robot_id, 2);
      EXPECT_EQ(t.incarnation, node.incarnation());
      EXPECT_EQ(t.num_omitted, 0);
      EXPECT_EQ(t.num_tracks, c + 1 < chunks ? contract::kMaxTracks : held - c * contract::kMaxTracks) << f;
      for (int k = 0; k < t.num_tracks; ++k) got.push_back(t.tracks[static_cast<std::size_t>(k)].id);
    }
    EXPECT_EQ(got, want) << f;
    most = std::max(most, held);
    most_chunks = std::max(most_chunks, chunks);
  }
  ASSERT_GT(most, contract::kMaxTracks) << "the scene must track more movers than one chunk holds";
  EXPECT_EQ(most_chunks, 2);
  EXPECT_EQ(node.counters().tracks_omitted, 0);
}

TEST_F(RobotNodeInput, NoticesAreValidatedAndAppliedToOthersOnly) {
  run(0, 4);
  dynamic_notice_t n{};
  n.seq = 1;
  n.frame = 3;  // found moving in frame 3, after this robot mapped it
  n.landmark_id = 3;
  n.detected_by = 2;  // this robot itself: nothing to do
  EXPECT_TRUE(node_.on_notice(n));
  EXPECT_TRUE(node_.robot().filter().has_landmark(3));
  n.detected_by = 1;
  EXPECT_TRUE(node_.on_notice(n));
  EXPECT_FALSE(node_.robot().filter().has_landmark(3));
  n.landmark_id = 999;
  EXPECT_FALSE(node_.on_notice(n));
  n.landmark_id = 3;
  n.detected_by = 0;
  EXPECT_FALSE(node_.on_notice(n));
  EXPECT_EQ(node_.counters().notices_applied, 1);
  EXPECT_EQ(node_.counters().rejected_inputs, 2);
}

// TEAM_MAP_<r> (robot.team_map): the other robots' estimates go into the aided
// filter only; the own filter (what the robot reports) never changes. A chunk that
// lists this robot as a contributor, an older version and an estimate that
// contradicts the robot's are not fused.
TEST(RobotNodeTeamMap, TeamEstimatesGoIntoTheAidedFilterOnly) {
  RobotOptions o = test::robot_options(Mode::kEla);
  o.team_map_fuse = true;
  RobotNode node(o, 2);
  const std::vector<Eigen::Vector2d> lms = test::ring(6, 3.0);
  for (int k = 0; k < 6; ++k) {
    const Pose2 p{0.01 * k, 0.0, 0.0};
    ASSERT_EQ(node.on_sensor(to_msg(test::frame_from(k, p, p, lms, test::all_ids(6)), 2), 0),
              RobotNode::Verdict::kProcessed);
  }
  const Robot& robot = node.robot();
  ASSERT_TRUE(robot.filter().has_landmark(1));
  const Eigen::VectorXd own_mean = robot.filter().mean();
  // Nothing fused yet: the two filters agree, up to rounding (each applies its
  // pending covariance steps when it is next read, and only the own filter is
  // read between updates, so they group them differently: EkfSlam::update).
  EXPECT_LT((robot.estimate().mean() - own_mean).cwiseAbs().maxCoeff(), 1e-12);
  global_map_t g{};
  g.incarnation = 7;
  g.version = 10;
  g.num_chunks = 1;
  g.id_end = 1000;
  contract::set_count(&g.landmarks, &g.num_landmarks, 2);
  for (int k = 0; k < 2; ++k) {
    global_landmark_t& l = g.landmarks[static_cast<std::size_t>(k)];
    l.id = k + 1;
    l.x = lms[static_cast<std::size_t>(k + 1)].x();
    l.y = lms[static_cast<std::size_t>(k + 1)].y();
    l.cov[0][0] = l.cov[1][1] = 1e-4;
    l.contributors = 0b101;  // robots 1 and 3
    l.status = global_landmark_t::STATIC;
  }
  ASSERT_TRUE(node.on_team_map(g));
  EXPECT_EQ(robot.team_counters().fused, 2);
  EXPECT_EQ(robot.filter().mean(), own_mean);
  EXPECT_LT(robot.estimate().landmark_cov(1).trace(), robot.filter().landmark_cov(1).trace());
  EXPECT_LT(robot.estimate().pose_cov().trace(), robot.filter().pose_cov().trace());
  // The same map again: nothing new.
  ASSERT_TRUE(node.on_team_map(g));
  EXPECT_EQ(robot.team_counters().fused, 2);
  // An older version: ignored.
  g.version = 9;
  g.landmarks[0].cov[0][0] = g.landmarks[0].cov[1][1] = 1e-5;
  ASSERT_TRUE(node.on_team_map(g));
  EXPECT_EQ(node.counters().team_map_stale, 1);
  EXPECT_EQ(robot.team_counters().fused, 2);
  // A chunk of main's previous incarnation (a datagram delayed past main's
  // restart): ignored, whatever its version, and the current incarnation's older
  // versions stay old after it.
  g.incarnation = 6;
  g.version = 50;
  ASSERT_TRUE(node.on_team_map(g));
  g.incarnation = 7;
  g.version = 9;
  ASSERT_TRUE(node.on_team_map(g));
  EXPECT_EQ(node.counters().team_map_stale, 3);
  EXPECT_EQ(robot.team_counters().fused, 2);
  // This robot's own information in it: refused.
  g.version = 11;
  g.landmarks[1].contributors = 0b010;
  std::string why;
  const Eigen::VectorXd aided = robot.estimate().mean();
  EXPECT_FALSE(node.on_team_map(g, &why));
  EXPECT_NE(why.find("contributor"), std::string::npos);
  EXPECT_EQ(robot.estimate().mean(), aided);
  // An estimate 2 m from the robot's, with a 1 cm sigma: contradicts it, not fused.
  g.landmarks[1].contributors = 0b001;
  g.landmarks[0].x += 2.0;
  g.landmarks[1].cov[0][0] = g.landmarks[1].cov[1][1] = 2e-5;
  ASSERT_TRUE(node.on_team_map(g));
  EXPECT_EQ(robot.team_counters().gated, 1);
  EXPECT_EQ(robot.team_counters().fused, 3);
  // Invalid (a NaN covariance): refused by the message checks, counted.
  g.landmarks[0].cov[0][0] = std::nan("");
  const std::int64_t rejected = node.counters().rejected_inputs;
  EXPECT_FALSE(node.on_team_map(g));
  EXPECT_EQ(node.counters().rejected_inputs, rejected + 1);
  g.landmarks[0].cov[0][0] = 1e-4;
  // An id beyond filter.max_landmark_id, a frame far ahead: refused.
  const int id0 = g.landmarks[0].id;
  g.landmarks[1].id = o.ekf.max_landmark_id;
  EXPECT_FALSE(node.on_team_map(g, &why));
  EXPECT_NE(why.find("max_landmark_id"), std::string::npos);
  g.landmarks[1].id = 2;
  g.frame = 5 + o.max_frame_gap + 1;
  EXPECT_FALSE(node.on_team_map(g, &why));
  EXPECT_NE(why.find("max_frame_gap"), std::string::npos);
  EXPECT_EQ(robot.filter().mean(), own_mean);
  // A map of frame 5 (this robot's last) waits for frame 6: in a lockstep team it
  // may arrive before or after SENSOR 6, and takes effect after frame 6 either way.
  g.frame = 5;
  g.version = 12;
  g.landmarks[0].x = lms[static_cast<std::size_t>(id0)].x();
  g.landmarks[0].cov[0][0] = g.landmarks[0].cov[1][1] = 1e-6;
  const std::int64_t fused = robot.team_counters().fused;
  ASSERT_TRUE(node.on_team_map(g));
  EXPECT_EQ(robot.team_counters().fused, fused);
  const Pose2 p6{0.06, 0.0, 0.0};
  ASSERT_EQ(node.on_sensor(to_msg(test::frame_from(6, p6, p6, lms, test::all_ids(6)), 2), 0),
            RobotNode::Verdict::kProcessed);
  EXPECT_GT(robot.team_counters().fused, fused);
}

// The team's map of test::ring(6, 3.0): every landmark rotated by 0.3 rad about the
// origin and its distance from the origin scaled by `scale`, certain (1 cm).
global_map_t turned_team_map(const std::vector<Eigen::Vector2d>& lms, double scale) {
  global_map_t g{};
  g.version = 1;
  g.num_chunks = 1;
  g.id_end = 1000;
  contract::set_count(&g.landmarks, &g.num_landmarks, static_cast<int>(lms.size()));
  const Eigen::Rotation2Dd rot(0.3);
  for (int k = 0; k < static_cast<int>(lms.size()); ++k) {
    global_landmark_t& l = g.landmarks[static_cast<std::size_t>(k)];
    const Eigen::Vector2d p = scale * (rot * lms[static_cast<std::size_t>(k)]);
    l.id = k;
    l.x = p.x();
    l.y = p.y();
    l.cov[0][0] = l.cov[1][1] = 1e-4;
    l.contributors = 0b1;
  }
  return g;
}

// Most of a team map disagrees with the robot, which has just seen every landmark in
// view fail its test (its heading was kicked by 0.3 rad): the robot is the one that
// is wrong. It says so (FAULT_INCONSISTENT) and fuses the map untested. A robot with
// no such trouble of its own refuses the same map; one disagreeing landmark of six
// is refused alone. The map is turned and stretched (x1.15: 0.45 m at 3 m), no
// rigid motion of the robot's: the gauge test (next test) does not fire.
TEST(RobotNodeTeamMap, ARobotInTroubleThatMostOfItsTeamMapDisagreesWithIsLost) {
  RobotOptions o = test::robot_options(Mode::kEla);
  o.team_map_fuse = true;
  const std::vector<Eigen::Vector2d> lms = test::ring(6, 3.0);
  const Pose2 zero{0.0, 0.0, 0.0}, kicked{0.0, 0.0, -0.3};
  const auto make = [&](bool trouble) {
    auto node = std::make_unique<RobotNode>(o, 2);
    for (int k = 0; k < 8; ++k) {
      // The last frame sees the kick (its landmarks fail the ELA, not yet MOVING).
      const Pose2& truth = trouble && k == 7 ? kicked : zero;  // the odometer still says zero
      EXPECT_EQ(node->on_sensor(to_msg(test::frame_from(k, truth, zero, lms, test::all_ids(6)), 2), 0),
                RobotNode::Verdict::kProcessed);
    }
    return node;
  };
  global_map_t g = turned_team_map(lms, 1.15);
  const auto lost = make(true);
  const int held = static_cast<int>(lost->robot().estimate().num_landmarks());
  ASSERT_TRUE(lost->on_team_map(g));
  EXPECT_EQ(lost->robot().team_counters().lost, 1);
  EXPECT_EQ(lost->robot().team_counters().gated, 0);
  EXPECT_GE(lost->robot().team_counters().fused, 3);
  EXPECT_GE(held, 3);
  EXPECT_NE(lost->status_msg(0).fault_flags & node_status_t::FAULT_INCONSISTENT, 0);
  EXPECT_NE(lost->take_alert().find("inconsistent"), std::string::npos);

  const auto fine = make(false);
  ASSERT_TRUE(fine->on_team_map(g));
  EXPECT_EQ(fine->robot().team_counters().lost, 0);
  EXPECT_EQ(fine->robot().team_counters().gated, 6);
  EXPECT_EQ(fine->robot().team_counters().fused, 0);
  EXPECT_EQ(fine->status_msg(0).fault_flags & node_status_t::FAULT_INCONSISTENT, 0);
  EXPECT_NEAR(fine->robot().estimate().pose().theta, fine->robot().filter().pose().theta, 1e-12);

  const auto one_off = make(true);
  for (int k = 1; k < 6; ++k) {
    global_landmark_t& l = g.landmarks[static_cast<std::size_t>(k)];
    l.x = one_off->robot().estimate().landmark(k).x();
    l.y = one_off->robot().estimate().landmark(k).y();
  }
  g.landmarks[0].contributors = 0b1;
  ASSERT_TRUE(one_off->on_team_map(g));
  EXPECT_EQ(one_off->robot().team_counters().lost, 0);
  EXPECT_EQ(one_off->robot().team_counters().gated, 1);
}

// The same team map turned only (a rigid motion of the robot's map): the gauge test
// moves the robot, in trouble or not, onto it. Its STATUS says so (FAULT_RELOCALISED,
// the motion in relocalised_*), its alert line gives the motion, both filters moved,
// the next frame sends a snapshot (main's copy of its map moves too) and every
// landmark of the map is then fused, tested.
TEST(RobotNodeTeamMap, ARobotWhoseWholeMapIsTurnedIsRelocalisedAndSaysSo) {
  RobotOptions o = test::robot_options(Mode::kEla);
  o.team_map_fuse = true;
  o.snapshot_period_frames = 1000;
  const std::vector<Eigen::Vector2d> lms = test::ring(6, 3.0);
  const Pose2 zero{0.0, 0.0, 0.0};
  RobotNode node(o, 2);
  for (int k = 0; k < 8; ++k)
    ASSERT_EQ(node.on_sensor(to_msg(test::frame_from(k, zero, zero, lms, test::all_ids(6)), 2), 0),
              RobotNode::Verdict::kProcessed);
  EXPECT_EQ(node.status_msg(0).relocalisations, 0);
  EXPECT_EQ(node.status_msg(0).fault_flags & node_status_t::FAULT_RELOCALISED, 0);
  node.take_alert();
  ASSERT_TRUE(node.on_team_map(turned_team_map(lms, 1.0)));
  const TeamCounters& t = node.robot().team_counters();
  EXPECT_EQ(t.relocalised, 1);
  EXPECT_EQ(t.lost, 0);
  EXPECT_EQ(t.gated, 0);
  EXPECT_EQ(t.fused, 6);
  for (const EkfSlam* f : {&node.robot().filter(), &node.robot().estimate()}) {
    EXPECT_NEAR(f->pose().theta, 0.3, 1e-6);
    EXPECT_NEAR(f->landmark(2).x(), (Eigen::Rotation2Dd(0.3) * lms[2]).x(), 1e-6);
  }
  const node_status_t st = node.status_msg(0);
  EXPECT_NE(st.fault_flags & node_status_t::FAULT_RELOCALISED, 0);
  EXPECT_EQ(st.relocalisations, 1);
  EXPECT_EQ(st.relocalised_frame, 7);
  EXPECT_NEAR(st.relocalised_rotation, 0.3, 1e-6);
  EXPECT_NEAR(st.relocalised_x, 0.0, 1e-6);
  EXPECT_NEAR(st.relocalised_y, 0.0, 1e-6);
  const std::string alert = node.take_alert();
  EXPECT_NE(alert.find("robot 2 relocalised at frame 7"), std::string::npos) << alert;
  EXPECT_NE(alert.find("rotation 17.19 deg"), std::string::npos) << alert;
  EXPECT_NE(alert.find("6 of 6 landmarks"), std::string::npos) << alert;
  EXPECT_FALSE(node.snapshot_ready());
  // The same sightings as before: a rigid motion of the whole state predicts them all.
  ASSERT_EQ(node.on_sensor(to_msg(test::frame_from(8, zero, zero, lms, test::all_ids(6)), 2), 0),
            RobotNode::Verdict::kProcessed);
  EXPECT_TRUE(node.snapshot_ready());
  EXPECT_GT(node.pose_msg().snapshot_chunks, 0);
  EXPECT_EQ(node.pose_msg().num_accepted, 6);
  EXPECT_EQ(node.pose_msg().num_rejected, 0);
  EXPECT_EQ(node.robot().team_counters().relocalised, 1);
}

TEST(RobotNodeTeamMap, RefusedWhenTheOptionIsOff) {
  RobotNode node(test::robot_options(Mode::kEla), 2);
  global_map_t g{};
  g.num_chunks = 1;
  std::string why;
  EXPECT_FALSE(node.on_team_map(g, &why));
  EXPECT_NE(why.find("team_map.fuse is off"), std::string::npos);
  EXPECT_EQ(node.counters().rejected_inputs, 1);
}

// A notice about frame f that arrives before this robot's own SENSOR frame f (the
// detecting robot and main_robot were faster) takes effect after frame f, exactly
// as in the in-process run: the landmark still corrects frame f here.
TEST_F(RobotNodeInput, ANoticeAheadOfThisRobotsFrameWaitsForIt) {
  run(0, 4);  // frames 0..3 processed: landmark 3 mapped
  dynamic_notice_t n{};
  n.seq = 1;
  n.landmark_id = 3;
  n.detected_by = 1;
  n.frame = 4;  // another robot's detection in frame 4, before our frame 4
  EXPECT_TRUE(node_.on_notice(n));
  EXPECT_EQ(node_.counters().notices_deferred, 1);
  EXPECT_TRUE(node_.robot().filter().has_landmark(3));  // held
  run(4, 5);
  // Frame 4 used landmark 3 (its pose went out with 6 landmarks); then the notice
  // took effect.
  EXPECT_EQ(node_.pose_msg().num_landmarks, 6);
  EXPECT_FALSE(node_.robot().filter().has_landmark(3));
  EXPECT_EQ(node_.counters().notices_applied, 1);
  // A notice for a frame already processed applies at once.
  n.landmark_id = 4;
  n.frame = 2;
  EXPECT_TRUE(node_.on_notice(n));
  EXPECT_FALSE(node_.robot().filter().has_landmark(4));
  EXPECT_EQ(node_.counters().notices_deferred, 1);
  // One further ahead than node.max_frame_gap is not held: applied at once.
  n.landmark_id = 5;
  n.frame = 4 + 1000;
  EXPECT_TRUE(node_.on_notice(n));
  EXPECT_FALSE(node_.robot().filter().has_landmark(5));
}

// A DYNAMIC_NOTICE datagram duplicated or delayed on the link (or replayed by main
// after a restart) must not undo what this robot has learnt since: a landmark it
// took back after the notice stays, and a notice is applied once.
TEST_F(RobotNodeInput, ADuplicatedOrLateNoticeNeverUndoesNewerState) {
  run(0, 4);  // frames 0..3: landmark 3 mapped
  dynamic_notice_t n{};
  n.seq = 1;
  n.landmark_id = 3;
  n.detected_by = 1;
  n.frame = 3;
  EXPECT_TRUE(node_.on_notice(n));
  EXPECT_FALSE(node_.robot().filter().has_landmark(3));
  EXPECT_EQ(node_.counters().notices_applied, 1);
  // The landmark never moved here: this robot sees it again and takes it back.
  int k = 4;
  for (; k < 60 && node_.robot().lmap()[3].status != LandmarkStatus::kStatic; ++k) run(k, k + 1);
  ASSERT_EQ(node_.robot().lmap()[3].status, LandmarkStatus::kStatic);
  ASSERT_TRUE(node_.robot().filter().has_landmark(3));
  // The same notice again (a duplicate), an older one, another robot's of the same
  // frame: none removes it.
  EXPECT_TRUE(node_.on_notice(n));
  n.frame = 2;
  EXPECT_TRUE(node_.on_notice(n));
  n.frame = 3;
  n.detected_by = 3;
  EXPECT_TRUE(node_.on_notice(n));
  EXPECT_TRUE(node_.robot().filter().has_landmark(3));
  EXPECT_EQ(node_.robot().lmap()[3].times_moving, 1);
  EXPECT_EQ(node_.counters().notices_applied, 1);
  EXPECT_EQ(node_.counters().notices_stale, 3);
  // A finding newer than the one had but older than this robot taking it back (a
  // late datagram): this robot's own view is newer.
  const int back = node_.robot().lmap()[3].status_frame;
  ASSERT_GT(back - 1, 3);
  n.frame = back - 1;
  EXPECT_TRUE(node_.on_notice(n));
  EXPECT_TRUE(node_.robot().filter().has_landmark(3));
  EXPECT_EQ(node_.counters().notices_stale, 4);
  // A finding after it is applied.
  n.frame = k - 1;
  EXPECT_TRUE(node_.on_notice(n));
  EXPECT_FALSE(node_.robot().filter().has_landmark(3));
  EXPECT_EQ(node_.counters().notices_applied, 2);
  EXPECT_EQ(node_.counters().notices_stale, 4);
}

// A sensor source that starts over (a new run from frame 0) while the node runs on:
// its frames are refused as old, and counted in a row until a frame is processed
// (the process shell starts fresh after 10); a late datagram between processed
// frames starts no run.
TEST(RobotNodeSource, FramesBehindAreCountedInARowUntilOneIsProcessed) {
  RobotOptions o = test::robot_options(Mode::kEla);
  RobotNode node(o, 2);
  const std::vector<Eigen::Vector2d> lms = test::ring(6, 3.0);
  const auto msg = [&](int k) {
    const Pose2 p{0.01 * k, 0.0, 0.0};
    return to_msg(test::frame_from(k, p, p, lms, test::all_ids(6)), 2);
  };
  for (int k = 0; k < 30; ++k) ASSERT_EQ(node.on_sensor(msg(k), 0), RobotNode::Verdict::kProcessed);
  EXPECT_EQ(node.on_sensor(msg(25), 0), RobotNode::Verdict::kOutOfOrder);  // a late datagram
  EXPECT_EQ(node.frames_behind(), 1);
  EXPECT_EQ(node.on_sensor(msg(30), 0), RobotNode::Verdict::kProcessed);
  EXPECT_EQ(node.frames_behind(), 0);
  EXPECT_EQ(node.on_sensor(msg(30), 0), RobotNode::Verdict::kDuplicate);  // not older: not counted
  EXPECT_EQ(node.frames_behind(), 0);
  for (int k = 0; k < 10; ++k) EXPECT_EQ(node.on_sensor(msg(k), 0), RobotNode::Verdict::kOutOfOrder);
  EXPECT_EQ(node.frames_behind(), 10);
  EXPECT_EQ(node.on_sensor(msg(31), 0), RobotNode::Verdict::kProcessed);
  EXPECT_EQ(node.frames_behind(), 0);
}

}  // namespace
}  // namespace elaslam

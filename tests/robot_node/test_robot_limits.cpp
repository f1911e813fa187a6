// SPDX-License-Identifier: Apache-2.0
// A robot node against messages that decode and look valid but are absurd (issue
// 15): frame numbers near INT32_MAX or forged far ahead, odometer jumps, notices
// and global maps from outside the team or with absurd contents, a full filter.
// Each is refused (counted per reason) or flagged, and never poisons later frames.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include <nlohmann/json.hpp>

#include "elaslam/common/contract.hpp"
#include "elaslam/robot_node/robot_node.hpp"
#include "elaslam/robot_node/robot_state.hpp"
#include "scene.hpp"

namespace elaslam {
namespace {

using test::to_msg;

RobotOptions options(int capacity = 64) {
  RobotOptions o = test::robot_options(Mode::kEla);
  o.ekf.capacity = capacity;
  std::string why;
  EXPECT_TRUE(parse_team("1,2,3", &o.limits.team_mask, &why)) << why;
  return o;
}

class RobotLimits : public ::testing::Test {
 protected:
  explicit RobotLimits(int capacity = 64) : node_(options(capacity), 2), lms_(test::ring(6, 3.0)) {}
  // Frame k: the robot at x = 0.01 k, its odometer reading `offset` further along x.
  sensor_frame_t frame(int k, double offset = 0.0) {
    const Pose2 truth{0.01 * k, 0.0, 0.0}, odo{0.01 * k + offset, 0.0, 0.0};
    return to_msg(test::frame_from(k, truth, odo, lms_, test::all_ids(lms_.size())), 2);
  }
  RobotNode::Verdict send(const sensor_frame_t& m, std::string* why = nullptr) { return node_.on_sensor(m, 0, why); }
  void run(int from, int to, double offset = 0.0) {
    for (int k = from; k < to; ++k) ASSERT_EQ(send(frame(k, offset)), RobotNode::Verdict::kProcessed) << k;
  }
  double error() const { return std::hypot(node_.pose_msg().x - 0.01 * node_.pose_msg().frame, node_.pose_msg().y); }
  RobotNode node_;
  std::vector<Eigen::Vector2d> lms_;
};

// A frame of 2147483642 overflowed last_frame_ + max_frame_gap: the robot never
// processed another frame.
TEST_F(RobotLimits, FramesNearInt32MaxNeverOverflowTheWindow) {
  const int top = std::numeric_limits<int>::max();
  auto m = frame(0);
  m.frame = top - 10;
  ASSERT_EQ(send(m), RobotNode::Verdict::kProcessed);
  for (int f = top - 9; f <= top - 5; ++f) {
    m.frame = f;
    std::string why;
    EXPECT_EQ(send(m, &why), RobotNode::Verdict::kProcessed) << f << ": " << why;
  }
  EXPECT_EQ(node_.robot().last_frame(), top - 5);
}

// A first frame of INT32_MAX - 5 (a forged or stray datagram before the real stream)
// was taken as the reference: the robot then refused real frames 1..10 as old, until
// the process started over. Now the next frame that does not continue a lone first
// frame starts the node over from it: no real frame is lost.
TEST_F(RobotLimits, AFirstFrameFarAheadNeverCostsTheRealFrames) {
  node_.set_incarnation(40);
  auto forged = frame(0);
  forged.frame = std::numeric_limits<int>::max() - 5;
  ASSERT_EQ(send(forged), RobotNode::Verdict::kProcessed);
  run(1, 30);
  EXPECT_EQ(node_.counters().frames, 29);
  EXPECT_EQ(node_.robot().last_frame(), 29);
  EXPECT_EQ(node_.incarnation(), 41);  // its stream starts over at main_robot too
  EXPECT_NE(node_.take_alert().find("started over"), std::string::npos);
  EXPECT_LT(error(), 0.05);
  // Two frames that continue each other are the stream: an older one after them is refused.
  EXPECT_EQ(send(frame(3)), RobotNode::Verdict::kOutOfOrder);
  EXPECT_EQ(node_.counters().frames, 29);
}

TEST_F(RobotLimits, AFirstFrameFarBehindItsSuccessorStartsOverToo) {
  node_.set_incarnation(40);
  ASSERT_EQ(send(frame(0)), RobotNode::Verdict::kProcessed);  // a stray frame 0 of an old run
  run(500, 520);                                               // the real stream, far ahead
  EXPECT_EQ(node_.counters().frames, 20);
  EXPECT_EQ(node_.robot().last_frame(), 519);
}

// Faults an operator must see, in STATUS (node_status_t.fault_flags) and as a line.
TEST_F(RobotLimits, LostFramesASilentMainAndAFailedSaveAreFlagged) {
  const auto flags = [&](std::int64_t now) { return node_.status_msg(now).fault_flags; };
  const std::int64_t s = 1000000;
  ASSERT_EQ(node_.on_sensor(frame(0), 1 * s, nullptr), RobotNode::Verdict::kProcessed);
  node_.main_heard(1 * s);
  EXPECT_EQ(flags(1 * s), 0);
  // Frames 1..3 never came.
  ASSERT_EQ(node_.on_sensor(frame(4), 2 * s, nullptr), RobotNode::Verdict::kProcessed);
  EXPECT_TRUE(flags(2 * s) & node_status_t::FAULT_FRAMES_LOST);
  EXPECT_NE(node_.take_alert().find("never received frames 1..3"), std::string::npos);
  run(5, 5 + RobotNode::kAlertFrames);
  EXPECT_FALSE(flags(2 * s) & node_status_t::FAULT_FRAMES_LOST);  // 100 frames later
  // main_robot not heard for longer than node.main_silent_s (5 s).
  node_.check_main(5 * s);
  EXPECT_FALSE(flags(5 * s) & node_status_t::FAULT_MAIN_SILENT);
  node_.check_main(7 * s);
  EXPECT_TRUE(flags(7 * s) & node_status_t::FAULT_MAIN_SILENT);
  EXPECT_NE(node_.take_alert().find("has not heard main_robot for 6.0 s"), std::string::npos);
  node_.main_heard(9 * s);
  EXPECT_FALSE(flags(9 * s) & node_status_t::FAULT_MAIN_SILENT);
  EXPECT_TRUE(flags(9 * s) & node_status_t::FAULT_PARTITION_HEALED);
  EXPECT_NE(node_.take_alert().find("heard again after 8.0 s"), std::string::npos);
  // A save that fails: flagged until one succeeds.
  node_.note_save(false, "state.json: No space left on device");
  EXPECT_TRUE(flags(9 * s) & node_status_t::FAULT_SAVE_FAILED);
  EXPECT_NE(node_.take_alert().find("No space left"), std::string::npos);
  node_.note_save(false, "state.json: No space left on device");
  EXPECT_EQ(node_.take_alert(), "");  // said once per series
  node_.note_save(true, "");
  EXPECT_FALSE(flags(9 * s) & node_status_t::FAULT_SAVE_FAILED);
}

// One forged frame 99 ahead (inside max_frame_gap) made the robot refuse the 99
// real frames after it (its error rose from 0.19 to 1.09 m in the team run).
TEST_F(RobotLimits, AForgedFrameFarAheadNeverBlocksTheRealFrames) {
  run(0, 10);
  std::string why;
  EXPECT_EQ(send(frame(55), &why), RobotNode::Verdict::kInvalid);  // 46 ahead, inside max_frame_gap 50
  EXPECT_NE(why.find("confirm_jump_frames"), std::string::npos) << why;
  run(10, 30);  // every real frame processed
  EXPECT_EQ(node_.counters().refused[Refusal::kFrameWindow], 1);
  EXPECT_EQ(node_.counters().frames, 30);
  // A real jump (frames lost in a burst) is taken when the next frame confirms it.
  EXPECT_EQ(send(frame(70)), RobotNode::Verdict::kInvalid);
  EXPECT_EQ(send(frame(71)), RobotNode::Verdict::kProcessed);
  EXPECT_LT(error(), 0.05);
}

// One odometry jump of 9e5 m (inside the old 1e6 m bound) ruined the robot for the
// rest of the run. Now beyond limits.world_bound_m; a jump inside it (5 km) is
// beyond what the robot can drive in a frame.
TEST_F(RobotLimits, AnOdometerJumpIsRefusedAndDoesNotPoisonLaterFrames) {
  run(0, 10);
  std::string why;
  EXPECT_EQ(send(frame(10, 9e5), &why), RobotNode::Verdict::kInvalid);
  EXPECT_NE(why.find("world_bound_m"), std::string::npos) << why;
  EXPECT_EQ(send(frame(10, 5e3), &why), RobotNode::Verdict::kInvalid);
  EXPECT_NE(why.find("max_step_m"), std::string::npos) << why;
  EXPECT_EQ(node_.counters().refused[Refusal::kOdometry], 1);
  run(11, 30);
  EXPECT_LT(error(), 0.05);
  EXPECT_EQ(node_.counters().odometry_reanchors, 0);
}

// A jump the following readings continue is a new odometer origin (a reset): after
// odometry_reanchor_frames readings the robot re-anchors on it, the motion between
// unknown within the vehicle's bounds; the landmarks pull it back.
TEST_F(RobotLimits, AnOdometerResetIsReanchoredAfterConsistentReadings) {
  run(0, 10);
  const int n = node_.robot().options().odometry_reanchor_frames;
  for (int k = 10; k < 10 + n - 1; ++k) EXPECT_EQ(send(frame(k, 50.0)), RobotNode::Verdict::kInvalid) << k;
  EXPECT_EQ(send(frame(10 + n - 1, 50.0)), RobotNode::Verdict::kProcessed);
  EXPECT_EQ(node_.counters().odometry_reanchors, 1);
  run(10 + n, 40, 50.0);
  EXPECT_LT(error(), 0.1);
}

TEST_F(RobotLimits, AnOdometerBeyondTheWorldBoundIsRefused) {
  run(0, 3);
  auto m = frame(3);
  m.odom_x = 5e5;  // limits.world_bound_m 1e4 by default
  std::string why;
  EXPECT_EQ(send(m, &why), RobotNode::Verdict::kInvalid);
  EXPECT_NE(why.find("world_bound_m"), std::string::npos) << why;
  EXPECT_EQ(node_.counters().refused[Refusal::kImplausible], 1);
}

TEST_F(RobotLimits, NoticesAndMapsFromOutsideTheTeamAreRefused) {
  run(0, 5);
  dynamic_notice_t n{};
  n.seq = 1;
  n.frame = 4;
  n.landmark_id = 1;
  n.detected_by = 5;  // team 1,2,3
  std::string why;
  EXPECT_FALSE(node_.on_notice(n, &why));
  EXPECT_NE(why.find("limits.team"), std::string::npos) << why;
  n.detected_by = 1;
  n.seq = std::numeric_limits<std::int64_t>::max();
  EXPECT_FALSE(node_.on_notice(n, &why));
  EXPECT_TRUE(node_.robot().filter().has_landmark(1));

  global_map_t g{};
  g.num_moving = 1;
  g.moving_ids = {1};
  g.moving_frames = {4};
  g.moving_by = {6};
  EXPECT_FALSE(node_.on_global_map(g, &why));
  EXPECT_EQ(node_.counters().refused[Refusal::kOutsideTeam], 2);
  g.num_moving = 2;
  g.moving_ids = {1, 1};
  g.moving_frames = {4, 4};
  g.moving_by = {1, 1};
  EXPECT_FALSE(node_.on_global_map(g, &why));
  EXPECT_EQ(node_.counters().refused[Refusal::kDuplicateId], 1);
  global_map_t far{};
  far.num_landmarks = 1;
  far.landmarks.resize(1);
  far.landmarks[0].id = 2;
  far.landmarks[0].x = 1e300;
  far.landmarks[0].cov[0][0] = far.landmarks[0].cov[1][1] = 0.01;
  EXPECT_FALSE(node_.on_global_map(far, &why));
  EXPECT_NE(why.find("world_bound_m"), std::string::npos) << why;
  EXPECT_TRUE(node_.robot().filter().has_landmark(1));
  const node_status_t s = node_.status_msg(0);
  EXPECT_EQ(s.refused[node_status_t::REFUSED_OUTSIDE_TEAM], 2);
  EXPECT_EQ(s.refused[node_status_t::REFUSED_MALFORMED], 1);
  EXPECT_EQ(s.refused[node_status_t::REFUSED_IMPLAUSIBLE], 1);
}

// A full filter showed only as a filter_faults counter.
class SmallFilter : public RobotLimits {
 protected:
  SmallFilter() : RobotLimits(3) {}
};

TEST_F(SmallFilter, AFullFilterRaisesTheCapacityFaultAndOneAlert) {
  run(0, 1);
  EXPECT_FALSE(node_.take_alert().empty());
  EXPECT_GT(node_.counters().filter_full, 0);
  EXPECT_NE(node_.status_msg(0).fault_flags & node_status_t::FAULT_CAPACITY, 0);
  run(1, 5);
  EXPECT_TRUE(node_.take_alert().empty());  // rate-limited: once per kAlertFrames frames
}

// A loaded state is checked like a message: a denormal covariance or a position
// beyond the world bound is refused with the field named, never loaded.
// A frame carries at most robot.filter.max_observations (4 here): one with more is
// refused naming the key, counted, and the next frame is processed.
TEST(RobotObservationCap, AFrameWithMoreObservationsThanConfiguredIsRefused) {
  RobotOptions o = options();
  o.max_observations = 4;
  RobotNode node(o, 2);
  const std::vector<Eigen::Vector2d> lms = test::ring(6, 3.0);
  const Pose2 at{0.0, 0.0, 0.0};
  std::string why;
  EXPECT_EQ(node.on_sensor(to_msg(test::frame_from(0, at, at, lms, {0, 1, 2, 3, 4, 5}), 2), 0, &why),
            RobotNode::Verdict::kInvalid);
  EXPECT_NE(why.find("robot.filter.max_observations"), std::string::npos) << why;
  EXPECT_EQ(node.counters().rejected_inputs, 1);
  EXPECT_EQ(node.on_sensor(to_msg(test::frame_from(0, at, at, lms, {0, 1, 2, 3}), 2), 0, &why),
            RobotNode::Verdict::kProcessed)
      << why;
  EXPECT_EQ(node.robot().filter().num_landmarks(), 4);
}

TEST_F(RobotLimits, AbsurdStateFilesAreRefused) {
  run(0, 6);
  const nlohmann::json good = nlohmann::json::parse(save_robot_state(node_));
  const auto sealed = [](nlohmann::json doc) {
    doc["fnv1a64"] = robot_state_checksum(doc["state"].dump());
    return doc.dump();
  };
  RobotNode fresh(options(), 2);
  std::string why;
  ASSERT_TRUE(load_robot_state(sealed(good), &fresh, &why)) << why;
  nlohmann::json t = good;
  t["state"]["robot"]["last_odometer"][0] = 1e300;
  EXPECT_FALSE(load_robot_state(sealed(t), &fresh, &why));
  EXPECT_NE(why.find("last_odometer"), std::string::npos) << why;
  t = good;
  t["state"]["lmap"][0]["cov"] = {1e-320, 0.0, 0.0, 1e-320};
  EXPECT_FALSE(load_robot_state(sealed(t), &fresh, &why));
  EXPECT_NE(why.find("cov_floor_m2"), std::string::npos) << why;
  t = good;
  t["state"]["lmap"][0]["position"][1] = 1e300;
  EXPECT_FALSE(load_robot_state(sealed(t), &fresh, &why));
  EXPECT_NE(why.find("position"), std::string::npos) << why;
  t = good;
  t["state"]["node"]["seq"] = std::numeric_limits<std::int64_t>::max();
  EXPECT_FALSE(load_robot_state(sealed(t), &fresh, &why));
  EXPECT_NE(why.find("node.seq"), std::string::npos) << why;
  // A landmark's own block of P at 1e-320 (its snapshot would carry it).
  t = good;
  auto& lower = t["state"]["filter"]["cov_lower"];
  const int slot_offset = StateLayout::landmark_offset(0);
  const auto diag = [](int i) { return static_cast<std::size_t>(i * (i + 1) / 2 + i); };
  for (int i = slot_offset; i < slot_offset + 2; ++i) lower[diag(i)] = 1e-320;
  lower[diag(slot_offset + 1) - 1] = 0.0;
  EXPECT_FALSE(load_robot_state(sealed(t), &fresh, &why));
  EXPECT_NE(why.find("filter.cov_lower"), std::string::npos) << why;
}

}  // namespace
}  // namespace elaslam

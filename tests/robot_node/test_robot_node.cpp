// The robot node's message layer: every bad message is counted and dropped without
// touching the filter; duplicated and reordered frames are refused; gaps are bridged.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "elaslam/robot_node/robot_node.hpp"
#include "elaslam/common/contract.hpp"
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

TEST_F(RobotNodeInput, NoticesAreValidatedAndAppliedToOthersOnly) {
  run(0, 4);
  dynamic_notice_t n{};
  n.seq = 1;
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

}  // namespace
}  // namespace elaslam

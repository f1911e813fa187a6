// SPDX-License-Identifier: Apache-2.0
// FrameAdmission: a frame's order against the last processed one (a duplicate, an
// older frame counted as behind until one is processed), a break from a lone first
// frame, duplicate sightings refused with the marks cleared for the next frame, and
// the frame window.
#include "elaslam/robot_node/frame_admission.hpp"

#include <gtest/gtest.h>

#include "scene.hpp"

namespace elaslam {
namespace {

class FrameAdmissionTest : public ::testing::Test {
 protected:
  FrameAdmissionTest() : options_(options()), admission_(options_, 2), robot_(options_, 2), lms_(test::ring(4, 3.0)) {}
  static RobotOptions options() {
    RobotOptions o = test::robot_options(Mode::kEla);
    o.max_frame_gap = 20;
    o.confirm_jump_frames = 5;
    return o;
  }
  sensor_frame_t frame(int k) {
    const Pose2 p{0.01 * k, 0.0, 0.0};
    return test::to_msg(test::frame_from(k, p, p, lms_, test::all_ids(4)), 2);
  }
  // Admitted and run through the Robot, as RobotNode does.
  void process(int k) {
    const sensor_frame_t m = frame(k);
    ASSERT_EQ(admission_.validate(m), "");
    ASSERT_EQ(admission_.order(m), FrameAdmission::Order::kNewer);
    bool reanchor = false;
    Refusal reason{};
    ASSERT_EQ(admission_.check_progress(m, robot_, &reanchor, &reason), "");
    robot_.process(test::frame_from(k, {0.01 * k, 0.0, 0.0}, {0.01 * k, 0.0, 0.0}, lms_, test::all_ids(4)));
    admission_.processed(k);
  }
  RobotOptions options_;
  FrameAdmission admission_;
  Robot robot_;
  std::vector<Eigen::Vector2d> lms_;
};

TEST_F(FrameAdmissionTest, DuplicatesAndOlderFramesAreTold) {
  process(0);
  process(1);
  EXPECT_EQ(admission_.order(frame(1)), FrameAdmission::Order::kDuplicate);
  EXPECT_EQ(admission_.order(frame(0)), FrameAdmission::Order::kOlder);
  EXPECT_EQ(admission_.order(frame(0)), FrameAdmission::Order::kOlder);
  EXPECT_EQ(admission_.frames_behind(), 2);
  process(2);
  EXPECT_EQ(admission_.frames_behind(), 0);
  EXPECT_EQ(admission_.last_frame(), 2);
}

TEST_F(FrameAdmissionTest, AFrameThatDoesNotContinueTheLastBreaksFromIt) {
  process(0);
  EXPECT_FALSE(admission_.breaks_from_last(frame(1)));
  EXPECT_FALSE(admission_.breaks_from_last(frame(5)));  // confirm_jump_frames ahead
  EXPECT_TRUE(admission_.breaks_from_last(frame(6)));
}

TEST_F(FrameAdmissionTest, ADuplicateSightingIsRefusedAndTheNextFrameIsNotAffected) {
  sensor_frame_t m = frame(0);
  m.obs[2].landmark_id = m.obs[1].landmark_id;
  Refusal reason{};
  EXPECT_NE(admission_.check_duplicate_ids(m, &reason).find("twice"), std::string::npos);
  EXPECT_EQ(reason, Refusal::kDuplicateId);
  EXPECT_EQ(admission_.check_duplicate_ids(frame(0), &reason), "");  // the marks were cleared
}

TEST_F(FrameAdmissionTest, FramesBeyondTheWindowAreRefused) {
  process(0);
  process(1);
  bool reanchor = false;
  Refusal reason{};
  EXPECT_NE(admission_.check_progress(frame(30), robot_, &reanchor, &reason).find("max_frame_gap"), std::string::npos);
  EXPECT_EQ(reason, Refusal::kFrameWindow);
  // Within the window but beyond confirm_jump_frames: held until the next frame confirms it.
  EXPECT_NE(admission_.check_progress(frame(10), robot_, &reanchor, &reason).find("held"), std::string::npos);
  EXPECT_EQ(admission_.check_progress(frame(11), robot_, &reanchor, &reason), "");
  EXPECT_FALSE(reanchor);
}

}  // namespace
}  // namespace elaslam

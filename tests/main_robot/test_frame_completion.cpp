// SPDX-License-Identifier: Apache-2.0
// FrameCompletion: a robot's frame is finished when the events and snapshot its POSE
// announced are in (or at its next POSE, when they are lost); the team has finished
// the oldest frame of the robots seen; late POSEs change nothing; a restart forgets
// what the robot announced.
#include "elaslam/main_robot/frame_completion.hpp"

#include <gtest/gtest.h>

namespace elaslam {
namespace {

TEST(FrameCompletion, AFrameIsFinishedWhenWhatItsPoseAnnouncedIsIn) {
  FrameCompletion c;
  // Robot 1's POSE of frame 0 with its events up to seq 3 already applied: finished.
  EXPECT_EQ(c.take_pose(1, 0, 3, 0, 3).finished, 0);
  // Frame 1 announces seq 5, two not in yet: held.
  EXPECT_EQ(c.take_pose(1, 1, 5, 0, 3).finished, -1);
  c.events_applied(1, 4);
  EXPECT_EQ(c.take_finished(), -1);
  c.events_applied(1, 5);
  EXPECT_EQ(c.take_finished(), 1);
  EXPECT_EQ(c.take_finished(), -1);  // taken once
  EXPECT_EQ(c.completed(), 1);
}

TEST(FrameCompletion, TheTeamHasFinishedTheOldestFrameOfItsRobots) {
  FrameCompletion c;
  EXPECT_EQ(c.take_pose(1, 0, 0, 0, 0).finished, 0);
  EXPECT_EQ(c.take_pose(1, 1, 0, 0, 0).finished, 1);
  // Robot 2 joins at frame 0: the team's finished frame does not go back.
  EXPECT_EQ(c.take_pose(2, 0, 0, 0, 0).finished, -1);
  EXPECT_EQ(c.completed(), 1);
  EXPECT_EQ(c.take_pose(1, 2, 0, 0, 0).finished, -1);  // robot 2 holds the team at 0
  EXPECT_EQ(c.take_pose(2, 2, 0, 0, 0).finished, 2);
  EXPECT_EQ(c.robot_frame(2), 2);
  EXPECT_EQ(c.robot_frame(3), -1);  // never heard from
}

TEST(FrameCompletion, ASnapshotAnnouncedIsWaitedForAndMayComeFirst) {
  FrameCompletion c;
  EXPECT_EQ(c.take_pose(1, 4, 2, 3, 2).finished, -1);  // 3 snapshot chunks announced
  c.events_applied(1, 2);
  EXPECT_EQ(c.take_finished(), -1);
  c.snapshot_applied(1, 4, 2);
  EXPECT_EQ(c.take_finished(), 4);
  // The snapshot of frame 5 in before its POSE: the POSE finds it.
  c.snapshot_applied(1, 5, 2);
  EXPECT_EQ(c.take_pose(1, 5, 2, 3, 2).finished, 5);
}

TEST(FrameCompletion, LostEventsAreLetGoAtTheNextPoseAndLatePosesChangeNothing) {
  FrameCompletion c;
  EXPECT_EQ(c.take_pose(1, 0, 4, 0, 1).finished, -1);
  const FrameCompletion::PoseOutcome out = c.take_pose(1, 1, 6, 0, 1);
  EXPECT_EQ(out.finished, 0);  // frame 0 let go: its events (seq 2..4) lost or late
  EXPECT_EQ(out.let_go_frame, 0);
  EXPECT_EQ(out.let_go_event_seq, 4);
  EXPECT_TRUE(c.stale(1, 1));
  EXPECT_TRUE(c.stale(1, 0));
  EXPECT_FALSE(c.stale(1, 2));
  c.restart(1);  // what it announced no longer comes
  EXPECT_FALSE(c.stale(1, 1));
  EXPECT_EQ(c.robot_frame(1), -1);
}

}  // namespace
}  // namespace elaslam

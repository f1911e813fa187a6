// SPDX-License-Identifier: Apache-2.0
// DeferredInputs: a moving report is news once, held while ahead of the robot's
// frames and released at its frame in arrival order; one older than the robot's own
// view of the landmark is stale; a team map's estimates fall due after the robot's
// frame that follows the map's, and an older map version is ignored.
#include "elaslam/robot_node/deferred_inputs.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "scene.hpp"

namespace elaslam {
namespace {

RobotOptions options(bool team_map) {
  RobotOptions o = test::robot_options(Mode::kEla);
  o.max_frame_gap = 10;
  o.team_map_fuse = team_map;
  return o;
}

std::vector<int> released(DeferredInputs* d, int last_frame) {
  std::vector<int> ids;
  d->release_moving(last_frame, [&ids](const MovingReport& m) { ids.push_back(m.landmark_id); });
  return ids;
}

TEST(DeferredInputs, AMovingReportIsHeldUntilItsFrameAndIsNewsOnce) {
  const RobotOptions o = options(false);
  DeferredInputs d(o);
  const LMap lmap(o.ekf.max_landmark_id);
  // A fresh node (no frame yet) takes a report at once.
  EXPECT_EQ(d.take_moving({1, 0, 3}, lmap, -1), DeferredInputs::Take::kNow);
  EXPECT_EQ(d.take_moving({1, 0, 3}, lmap, -1), DeferredInputs::Take::kStale);  // a duplicated datagram
  // Ahead of frame 5: held; within max_frame_gap only.
  EXPECT_EQ(d.take_moving({7, 8, 3}, lmap, 5), DeferredInputs::Take::kHeld);
  EXPECT_EQ(d.take_moving({4, 6, 2}, lmap, 5), DeferredInputs::Take::kHeld);
  EXPECT_EQ(d.take_moving({9, 40, 2}, lmap, 5), DeferredInputs::Take::kNow);  // too far ahead: not held
  EXPECT_EQ(d.take_moving({7, 7, 3}, lmap, 5), DeferredInputs::Take::kStale);  // older than the one had
  EXPECT_TRUE(released(&d, 5).empty());
  EXPECT_EQ(released(&d, 6), std::vector<int>({4}));
  EXPECT_EQ(released(&d, 9), std::vector<int>({7}));
  EXPECT_TRUE(released(&d, 20).empty());
  // A newer report of a landmark is news again.
  EXPECT_EQ(d.take_moving({7, 12, 3}, lmap, 20), DeferredInputs::Take::kNow);
}

TEST(DeferredInputs, HeldReportsLeaveInArrivalOrder) {
  const RobotOptions o = options(false);
  DeferredInputs d(o);
  const LMap lmap(o.ekf.max_landmark_id);
  for (int id : {5, 2, 9}) ASSERT_EQ(d.take_moving({id, 3, 1}, lmap, 1), DeferredInputs::Take::kHeld);
  EXPECT_EQ(released(&d, 3), std::vector<int>({5, 2, 9}));
}

TEST(DeferredInputs, AReportOlderThanTheRobotsOwnViewIsStale) {
  const RobotOptions o = options(false);
  DeferredInputs d(o);
  LMap lmap(o.ekf.max_landmark_id);
  lmap.map_at_once(3, 10);  // this robot saw it again at frame 10: its view changed then
  EXPECT_FALSE(d.is_news({3, 8, 2}, lmap));
  EXPECT_EQ(d.take_moving({3, 8, 2}, lmap, 12), DeferredInputs::Take::kStale);
  EXPECT_TRUE(d.is_news({3, 11, 2}, lmap));
}

global_map_t team_map(std::int64_t incarnation, std::int64_t version, int frame, int id, double x) {
  global_map_t m{};
  m.incarnation = incarnation;
  m.version = version;
  m.frame = frame;
  m.num_landmarks = 1;
  m.landmarks.resize(1);
  m.landmarks[0].id = id;
  m.landmarks[0].x = x;
  m.landmarks[0].cov[0][0] = m.landmarks[0].cov[1][1] = 0.01;
  return m;
}

TEST(DeferredInputs, TeamEstimatesFallDueAfterTheFrameThatFollowsTheMaps) {
  DeferredInputs d(options(true));
  ASSERT_TRUE(d.take_team_map(team_map(1, 5, 10, 4, 1.0)));
  EXPECT_TRUE(d.due_team_estimates(10).empty());
  ASSERT_TRUE(d.take_team_map(team_map(1, 6, 10, 4, 2.0)));  // newer: replaces the held estimate
  EXPECT_FALSE(d.take_team_map(team_map(1, 4, 10, 4, 9.0)));  // an older version: ignored
  EXPECT_FALSE(d.take_team_map(team_map(0, 9, 10, 4, 9.0)));  // an earlier incarnation: ignored
  const std::vector<TeamEstimate>& due = d.due_team_estimates(11);
  ASSERT_EQ(due.size(), 1u);
  EXPECT_EQ(due[0].landmark_id, 4);
  EXPECT_EQ(due[0].position.x(), 2.0);
  EXPECT_DOUBLE_EQ(due[0].cov(1, 1), 0.01);
  EXPECT_TRUE(d.due_team_estimates(12).empty());  // taken once
  EXPECT_TRUE(d.take_team_map(team_map(2, 0, 11, 4, 3.0)));  // main restarted: a new incarnation counts
}

}  // namespace
}  // namespace elaslam

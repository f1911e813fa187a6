// SPDX-License-Identifier: Apache-2.0
// The adapter from recorded messages to the metrics (eval/frame_data.hpp) refuses
// what a node would refuse: POSEs with a forged source_utime would otherwise give a
// latency p50 of -4.7 s.
#include <gtest/gtest.h>

#include <cmath>

#include "elaslam/eval/frame_data.hpp"

namespace elaslam {
namespace {

pose_estimate_t pose() {
  pose_estimate_t p{};
  p.robot_id = 1;
  p.frame = 3;
  p.utime = 2'000'000;
  p.source_utime = 1'990'000;
  p.cov[0][0] = p.cov[1][1] = p.cov[2][2] = 1e-4;
  return p;
}

TEST(FrameData, APoseStampedAfterItsReceiptIsNotEvaluated) {
  MessageLimits l;
  Refusal why = Refusal::kMalformed;
  EXPECT_EQ(check_logged(pose(), 2'001'000, l, &why), "");
  pose_estimate_t p = pose();
  p.source_utime = 2'001'000 + 4'700'000;  // a latency of -4.7 s
  EXPECT_NE(check_logged(p, 2'001'000, l, &why).find("source_utime"), std::string::npos);
  p = pose();
  p.x = 1e300;
  EXPECT_NE(check_logged(p, 2'001'000, l, &why).find("world_bound_m"), std::string::npos);
  EXPECT_EQ(why, Refusal::kImplausible);
  p = pose();
  p.cov[2][2] = NAN;
  EXPECT_NE(check_logged(p, 2'001'000, l, &why), "");
}

TEST(FrameData, AGlobalMapChunkWithRepeatsOrAbsurdEntriesIsNotEvaluated) {
  MessageLimits l;
  Refusal why = Refusal::kMalformed;
  global_map_t g{};
  g.num_landmarks = 2;
  g.landmarks.resize(2);
  for (int i = 0; i < 2; ++i) {
    g.landmarks[static_cast<std::size_t>(i)].id = 4 + i;
    g.landmarks[static_cast<std::size_t>(i)].cov[0][0] = g.landmarks[static_cast<std::size_t>(i)].cov[1][1] = 0.01;
  }
  EXPECT_EQ(check_logged(g, l, &why), "");
  // main_robot's map before any robot has finished a frame is stamped -1: valid (a
  // default live run has about 12 of them; evaluate called them malformed).
  g.frame = -1;
  EXPECT_EQ(check_logged(g, l, &why), "");
  g.frame = -2;
  EXPECT_NE(check_logged(g, l, &why), "");
  g.frame = 0;
  g.landmarks[1].id = 4;
  EXPECT_NE(check_logged(g, l, &why), "");
  EXPECT_EQ(why, Refusal::kDuplicateId);
  g.landmarks[1].id = 5;
  g.landmarks[1].cov[0][0] = g.landmarks[1].cov[1][1] = 1e-320;
  EXPECT_NE(check_logged(g, l, &why).find("cov_floor_m2"), std::string::npos);
}

}  // namespace
}  // namespace elaslam

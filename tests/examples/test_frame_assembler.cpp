// SPDX-License-Identifier: Apache-2.0
// The example driver's frames (examples/sensor_driver/frame_assembler.hpp) against
// the SENSOR contract robot_node checks: consecutive frame indices from 0, every
// frame emitted (empty ones too), the odometer reading at the frame's end, one
// sighting per landmark, bearings in [-pi, pi), at most max_observations, and
// what it drops counted by reason.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "frame_assembler.hpp"

namespace elaslam::examples {
namespace {

struct Collected {
  std::vector<sensor_frame_t> frames;
  FrameAssembler make(AssemblerOptions o = {}) {
    return FrameAssembler(o, [this](const sensor_frame_t& m) { frames.push_back(m); });
  }
};

TEST(FrameAssembler, FramesAreConsecutiveAndCoverTheirPeriod) {
  Collected c;
  FrameAssembler a = c.make();
  a.line("odom 100.00 0 0 0");
  a.line("det 100.02 7 2.0 0.1");
  a.line("odom 100.05 0.05 0 0.01");
  a.line("det 100.12 8 3.0 -0.2");   // frame 1
  a.line("odom 100.35 0.3 0 0.02");  // frames 1 and 2 end: 2 is empty
  a.flush();
  ASSERT_EQ(c.frames.size(), 4u);
  for (std::size_t k = 0; k < c.frames.size(); ++k) {
    EXPECT_EQ(c.frames[k].frame, static_cast<int>(k));
    EXPECT_EQ(c.frames[k].robot_id, 1);
    EXPECT_EQ(c.frames[k].utime, std::llround((100.0 + 0.1 * static_cast<double>(k + 1)) * 1e6));
  }
  ASSERT_EQ(c.frames[0].num_obs, 1);
  EXPECT_EQ(c.frames[0].obs[0].landmark_id, 7);
  EXPECT_DOUBLE_EQ(c.frames[0].odom_x, 0.05);  // the latest reading at the frame's end
  ASSERT_EQ(c.frames[1].num_obs, 1);
  EXPECT_EQ(c.frames[1].obs[0].landmark_id, 8);
  EXPECT_EQ(c.frames[2].num_obs, 0);
  EXPECT_DOUBLE_EQ(c.frames[2].odom_x, 0.05);  // no new reading: zero increment
  EXPECT_DOUBLE_EQ(c.frames[3].odom_x, 0.3);
  EXPECT_EQ(a.counters().frames, 4);
  EXPECT_EQ(a.counters().empty_frames, 2);
  EXPECT_EQ(a.counters().detections, 2);
}

TEST(FrameAssembler, OneSightingPerLandmarkAndBearingsWrapped) {
  Collected c;
  FrameAssembler a = c.make();
  a.odometry(0.0, 0, 0, 7.0);                 // heading wrapped too
  a.detection(0.01, 3, 1.0, 0.2);
  a.detection(0.02, 3, 1.1, 3.5);             // the later one kept, bearing wrapped
  a.flush();
  ASSERT_EQ(c.frames.size(), 1u);
  ASSERT_EQ(c.frames[0].num_obs, 1);
  EXPECT_DOUBLE_EQ(c.frames[0].obs[0].range, 1.1);
  EXPECT_NEAR(c.frames[0].obs[0].bearing, 3.5 - 2.0 * M_PI, 1e-12);
  EXPECT_NEAR(c.frames[0].odom_theta, 7.0 - 2.0 * M_PI, 1e-12);
  EXPECT_EQ(a.counters().repeated_in_frame, 1);
}

TEST(FrameAssembler, BadReadingsAreCountedAndLeaveTheFramesAlone) {
  Collected c;
  AssemblerOptions o;
  o.max_landmark_id = 100;
  FrameAssembler a = c.make(o);
  a.line("odom 1.0 0 0 0");
  EXPECT_FALSE(a.line("odom 1.0 0 0"));        // a field short
  EXPECT_FALSE(a.line("det 1.0 5 1.0 0.0 9"));  // a field too many
  EXPECT_FALSE(a.line("tag 1.0 5 1.0 0.0"));   // unknown kind
  EXPECT_TRUE(a.line("# a comment"));
  EXPECT_TRUE(a.line(""));
  a.line("det 1.01 100 1.0 0.0");              // id outside [0, 100)
  a.line("det 1.01 5 -1.0 0.0");               // range not positive
  a.detection(1.01, 5, std::nan(""), 0.0);
  a.line("odom 1.25 0.2 0 0");                 // frames 0 and 1 done
  a.line("det 1.15 6 1.0 0.0");                // older than the frame being filled (2)
  a.flush();
  ASSERT_EQ(c.frames.size(), 3u);
  for (const auto& f : c.frames) EXPECT_EQ(f.num_obs, 0);
  EXPECT_EQ(a.counters().bad_lines, 3);
  EXPECT_EQ(a.counters().bad_detections, 3);
  EXPECT_EQ(a.counters().out_of_order, 1);
}

TEST(FrameAssembler, TooManySightingsKeepTheNearest) {
  Collected c;
  AssemblerOptions o;
  o.max_observations = 3;
  FrameAssembler a = c.make(o);
  a.odometry(0.0, 0, 0, 0);
  for (int id = 0; id < 5; ++id) a.detection(0.01, id, 5.0 - id, 0.0);  // ranges 5, 4, 3, 2, 1
  a.flush();
  ASSERT_EQ(c.frames[0].num_obs, 3);
  for (int k = 0; k < 3; ++k) EXPECT_LE(c.frames[0].obs[static_cast<std::size_t>(k)].range, 3.0);
  EXPECT_EQ(a.counters().over_capacity, 2);
}

TEST(FrameAssembler, FramesBeforeAnyOdometryAreCounted) {
  Collected c;
  FrameAssembler a = c.make();
  a.detection(0.0, 1, 1.0, 0.0);
  a.odometry(0.15, 1.0, 2.0, 0.0);
  a.flush();
  ASSERT_EQ(c.frames.size(), 2u);
  EXPECT_DOUBLE_EQ(c.frames[0].odom_x, 0.0);
  EXPECT_EQ(a.counters().frames_without_odometry, 1);
  EXPECT_DOUBLE_EQ(c.frames[1].odom_y, 2.0);
}

}  // namespace
}  // namespace elaslam::examples

// SPDX-License-Identifier: Apache-2.0
// A steady flow through the node shell and the in-process transport allocates
// nothing: messages are decoded into the input's one message, encoded into the
// shell's one buffer, queued in reused slots.
#include <gtest/gtest.h>

#include "../support/no_alloc.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/sensor_frame_t.hpp"
#include "elaslam/transport/inprocess_transport.hpp"
#include "elaslam/transport/node_shell.hpp"

namespace elaslam::transport {
namespace {

TEST(ShellNoAlloc, ASensorToPoseRoundTripAllocatesNothingOnceWarm) {
  InProcessTransport bus;
  NodeShell robot(bus, ShellOptions("robot", "", nullptr));
  NodeShell sim(bus, ShellOptions("sim", "", nullptr));
  const std::string sensor_ch = "SENSOR_1", pose_ch = "POSE_1";
  long poses = 0;
  robot.subscribe<sensor_frame_t>(sensor_ch, [&](const sensor_frame_t& s, const std::string&) {
    pose_estimate_t p{};
    p.frame = s.frame;
    p.robot_id = s.robot_id;
    robot.publish(pose_ch, p);
  }, kUnboundedQueue);
  sim.subscribe<pose_estimate_t>("POSE_[0-9]+", [&](const pose_estimate_t&, const std::string&) { ++poses; },
                                 kUnboundedQueue);
  sensor_frame_t s{};
  s.robot_id = 1;
  s.obs.resize(10);
  s.num_obs = 10;
  auto frame = [&](int k) {
    s.frame = k;
    sim.publish(sensor_ch, s);
    bus.dispatch_all();
  };
  for (int k = 0; k < 100; ++k) frame(k);  // warm: every queue slot has carried its message once
  {
    test::NoAllocRegion region;
    for (int k = 100; k < 2000; ++k) frame(k);
  }
  EXPECT_EQ(test::allocations_in_region(), 0);
  EXPECT_EQ(poses, 2000);
}

}  // namespace
}  // namespace elaslam::transport

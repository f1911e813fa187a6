// SPDX-License-Identifier: Apache-2.0
// The steady flow the no-allocation tests measure: a simulator's shell publishes
// SENSOR_1 frames, a robot's shell answers each with POSE_1, every message delivered
// by the in-process bus under both transports.
#pragma once

#include <string>

#include "../support/no_alloc.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/sensor_frame_t.hpp"
#include "elaslam/transport/inprocess_transport.hpp"
#include "elaslam/transport/node_shell.hpp"

namespace elaslam::test {

// Frames 0..1999 through shells on robot_side and sim_side (transports on `bus`): the
// first 100 warm them (every queue slot has carried its message once), the other
// 1900 run inside a NoAllocRegion (test::allocations_in_region() after). Returns the
// POSEs the simulator's shell received.
inline long sensor_pose_round_trip(transport::InProcessTransport& bus, transport::Transport& robot_side,
                                   transport::Transport& sim_side) {
  using transport::kUnboundedQueue;
  transport::NodeShell robot(robot_side, transport::ShellOptions("robot", "", nullptr));
  transport::NodeShell sim(sim_side, transport::ShellOptions("sim", "", nullptr));
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
  for (int k = 0; k < 100; ++k) frame(k);
  {
    NoAllocRegion region;
    for (int k = 100; k < 2000; ++k) frame(k);
  }
  return poses;
}

}  // namespace elaslam::test

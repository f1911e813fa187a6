// SPDX-License-Identifier: Apache-2.0
// The monitor's progress line (transport/team_progress.hpp): what each message adds
// to it, the exact text, and its handlers on a node shell over the in-process
// transport (a notice handled, garbage counted as undecodable).
#include <gtest/gtest.h>

#include <cstdint>
#include <string>

#include "elaslam/common/channels.hpp"
#include "elaslam/transport/inprocess_transport.hpp"
#include "elaslam/transport/node_shell.hpp"
#include "elaslam/transport/team_progress.hpp"

namespace elaslam::transport {
namespace {

node_status_t status(int node, std::int64_t dropped = 0) {
  node_status_t s{};
  s.node_id = node;
  s.frames_dropped = dropped;
  return s;
}

// A Msg of zeros but for `field`, set to `value`.
template <typename Msg, typename Field>
Msg message_with(Field Msg::*field, Field value) {
  Msg m{};
  m.*field = value;
  return m;
}

run_info_t run_info_msg(std::int32_t frames) { return message_with(&run_info_t::frames, frames); }
sensor_frame_t sensor_msg(std::int32_t frame) { return message_with(&sensor_frame_t::frame, frame); }
pose_estimate_t pose_msg(std::int16_t robot) { return message_with(&pose_estimate_t::robot_id, robot); }

TEST(TeamProgress, WaitingUntilTheFirstFrame) {
  TeamProgress p;
  EXPECT_EQ(p.line(0, 0), "waiting for the first frame");
  p.on_run_info(run_info_msg(150));
  EXPECT_EQ(p.line(3, 1), "waiting for the first frame of 150");
}

TEST(TeamProgress, FramesPosesMovingAndNotices) {
  TeamProgress p;
  p.on_run_info(run_info_msg(150));
  p.on_run_info(run_info_msg(0));  // no count: the last one stays
  p.on_sensor(sensor_msg(149));
  p.on_sensor(sensor_msg(10));  // late: the frame never goes back
  p.on_pose(pose_msg(1));
  EXPECT_EQ(p.line(0, 0), "frame 150/150 | poses 1 from 1 robot | moving landmarks found 0 | notices 0");
  p.on_pose(pose_msg(2));
  p.on_pose(pose_msg(2));
  dynamic_notice_t n{};
  n.landmark_id = 7;
  p.on_notice(n);
  global_map_t map{};
  map.num_moving = 2;
  map.moving_ids = {7, 9};
  p.on_global_map(map);
  EXPECT_EQ(p.line(0, 0), "frame 150/150 | poses 3 from 2 robots | moving landmarks found 2 | notices 1");
}

TEST(TeamProgress, HealthDropsRefusalsCalibrationAndFaults) {
  TeamProgress p;
  p.on_sensor(sensor_msg(4));
  p.on_robot_status(status(1, 2));
  node_status_t r2 = status(2, 3);
  r2.refused[0] = 4;
  r2.refused[3] = 1;
  r2.fault_flags = node_status_t::FAULT_FRAMES_LOST | node_status_t::FAULT_MAIN_SILENT;
  r2.odom_turn_scale = 1.02f;
  r2.odom_speed_scale = 0.98f;
  r2.odom_turn_scale_sigma = 0.01f;
  p.on_robot_status(r2);
  p.on_robot_status(status(1, 1));  // robot 1's latest count replaces its earlier one
  node_status_t m = status(0);
  m.refused[1] = 2;
  p.on_main_status(m);
  EXPECT_EQ(p.line(5, 6),
            "frame 5 | poses 0 from 0 robots | moving landmarks found 0 | notices 0 | robots report 4 dropped frames"
            " | undecodable 5 | refused (authentication) 6 | messages refused 7"
            " | odometer turn/speed scale: robot 2 1.020/0.980 | FAULT robot 2: frames lost, main silent");
}

TEST(TeamProgress, HandlersOnAShell) {
  InProcessTransport bus;
  NodeShell shell(bus, ShellOptions("monitor", "_T", nullptr));
  TeamProgress p;
  p.subscribe(shell);
  dynamic_notice_t n{};
  n.seq = 1;
  n.frame = 3;
  n.landmark_id = 7;
  n.detected_by = 1;
  EXPECT_TRUE(shell.publish(channels::dynamic_notice("_T"), n));
  const std::uint8_t garbage[5] = {1, 2, 3, 4, 5};
  bus.publish(channels::run_info("_T"), garbage, sizeof garbage);
  while (bus.handle_timeout(0) > 0) {
  }
  p.on_sensor(sensor_msg(0));
  EXPECT_EQ(p.line(shell),
            "frame 1 | poses 0 from 0 robots | moving landmarks found 1 | notices 1 | undecodable 1");
}

}  // namespace
}  // namespace elaslam::transport

// SPDX-License-Identifier: Apache-2.0
// System tests of the robot_node and main_robot processes over LCM (label `system`).
// Run inside tools/netns_run.sh: a private network namespace, LCM_DEFAULT_URL set.
// Waits are bounded loops on handleTimeout; readiness is seen on the nodes' STATUS
// messages, never assumed after a sleep.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <list>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "../support/child_process.hpp"
#include "elaslam/common/channels.hpp"
#include "elaslam/global_map_t.hpp"
#include "elaslam/landmark_event_t.hpp"
#include "elaslam/lmap_snapshot_t.hpp"
#include "elaslam/node_status_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/sensor_frame_t.hpp"

namespace elaslam {
namespace {

const std::string kBin = std::string(ELASLAM_BINARY_DIR) + "/bin/";
const std::string kConfig = std::string(ELASLAM_SOURCE_DIR) + "/config/paper.yaml";
using Clock = std::chrono::steady_clock;

class Bus {
 public:
  Bus() {
    EXPECT_TRUE(lc_.good()) << "LCM not available: run under tools/netns_run.sh";
    sub<pose_estimate_t>(channels::pose(1), [this](const pose_estimate_t& m) { pose_frames.push_back(m.frame); });
    sub<node_status_t>("STATUS_.*", [this](const node_status_t& m) { ++statuses[m.node_kind * 100 + m.node_id]; });
    sub<global_map_t>(channels::global_map(), [this](const global_map_t& m) { last_map = m, ++maps; });
  }
  template <typename Msg>
  void sub(const std::string& channel, std::function<void(const Msg&)> fn) {
    handlers_.push_back([fn](const lcm::ReceiveBuffer* rb) {
      Msg m;
      if (m.decode(rb->data, 0, static_cast<int>(rb->data_size)) >= 0) fn(m);
    });
    auto* s = lc_.subscribeFunction(
        channel, +[](const lcm::ReceiveBuffer* rb, const std::string&, std::function<void(const lcm::ReceiveBuffer*)>* h) { (*h)(rb); },
        &handlers_.back());
    s->setQueueCapacity(10000);
  }
  /// Handle messages until done() or the timeout; true when done() held.
  bool until(const std::function<bool()>& done, int timeout_ms) {
    const auto end = Clock::now() + std::chrono::milliseconds(timeout_ms);
    while (!done()) {
      if (Clock::now() > end) return false;
      lc_.handleTimeout(20);
    }
    return true;
  }
  template <typename Msg>
  void publish(const std::string& channel, const Msg& m) {
    lc_.publish(channel, &m);
  }
  void publish_raw(const std::string& channel, const std::vector<std::uint8_t>& bytes) {
    lc_.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
  }

  std::vector<int> pose_frames;
  std::map<int, int> statuses;  // node_kind * 100 + node_id -> count
  global_map_t last_map{};
  int maps = 0;

 private:
  lcm::LCM lc_;
  std::list<std::function<void(const lcm::ReceiveBuffer*)>> handlers_;
};

int status_key(int kind, int id) { return kind * 100 + id; }

TEST(SystemRobotNode, PosesCoverEveryFrameOfTheSimulator) {
  Bus bus;
  test::Child robot(kBin + "robot_node", {"--config", kConfig, "--robot", "1", "--mode", "ela", "--status-period", "0.1"});
  ASSERT_TRUE(bus.until([&] { return bus.statuses[status_key(node_status_t::ROBOT, 1)] > 0; }, 10000))
      << robot.stderr_text();
  test::Child sim(kBin + "simulator", {"--config", kConfig, "--frames", "60", "--rate", "50", "--dynamism", "50"});
  EXPECT_TRUE(bus.until([&] { return bus.pose_frames.size() >= 60; }, 30000));
  EXPECT_EQ(sim.wait(), 0) << sim.stderr_text();
  std::vector<int> expected;
  for (int k = 0; k < 60; ++k) expected.push_back(k);
  EXPECT_EQ(bus.pose_frames, expected);
  EXPECT_EQ(robot.stop(), 0);
  EXPECT_NE(robot.stderr_text().find("robot_node 1: frames=60 gaps=0"), std::string::npos) << robot.stderr_text();
}

sensor_frame_t frame(int k, int robot = 1) {
  sensor_frame_t m{};
  m.frame = k;
  m.robot_id = static_cast<int16_t>(robot);
  m.obs.resize(2);
  m.num_obs = 2;
  m.obs[0] = {3, 2.0, 0.5};
  m.obs[1] = {4, 3.0, -0.5};
  return m;
}

TEST(SystemRobotNode, BadMessagesAreCountedAndTheNodeCarriesOn) {
  Bus bus;
  test::Child robot(kBin + "robot_node", {"--config", kConfig, "--robot", "1", "--status-period", "0.1"});
  ASSERT_TRUE(bus.until([&] { return bus.statuses[status_key(node_status_t::ROBOT, 1)] > 0; }, 10000));
  bus.publish(channels::sensor(1), frame(0));
  bus.publish_raw(channels::sensor(1), {1, 2, 3, 4, 5});  // not a sensor_frame_t
  sensor_frame_t bad = frame(1);
  bad.obs[1].range = std::nan("");
  bus.publish(channels::sensor(1), bad);
  bus.publish(channels::sensor(1), frame(1, 2));  // another robot's frame on our channel
  bus.publish(channels::sensor(1), frame(0));     // duplicate
  bus.publish(channels::sensor(1), frame(1));
  EXPECT_TRUE(bus.until([&] { return bus.pose_frames.size() >= 2; }, 10000));
  EXPECT_EQ(bus.pose_frames, (std::vector<int>{0, 1}));
  EXPECT_EQ(robot.stop(), 0);
  const std::string err = robot.stderr_text();
  EXPECT_NE(err.find("frames=2 gaps=0 duplicates=1 out_of_order=0 rejected=2 decode_errors=1"), std::string::npos)
      << err;
}

landmark_event_t add(int robot, std::int64_t seq, int id, double x) {
  landmark_event_t e{};
  e.robot_id = static_cast<int16_t>(robot);
  e.seq = seq;
  e.kind = landmark_event_t::ADD;
  e.landmark_id = id;
  e.x = x;
  e.y = 1.0;
  e.cov[0][0] = e.cov[1][1] = 0.01;
  return e;
}

TEST(SystemMainRobot, RestartedMainRobotContinuesWithTheSameMap) {
  const std::string state = ::testing::TempDir() + "/elaslam_main_state_" + std::to_string(getpid()) + ".json";
  std::remove(state.c_str());
  Bus bus;
  std::int64_t version = 0;
  {
    test::Child main(kBin + "main_robot", {"--config", kConfig, "--state", state});
    ASSERT_TRUE(bus.until([&] { return bus.maps > 0; }, 10000)) << main.stderr_text();
    for (int i = 0; i < 3; ++i) bus.publish(channels::lmap_event(), add(1, i + 1, 10 + i, i));
    ASSERT_TRUE(bus.until([&] { return bus.last_map.num_landmarks == 3; }, 10000));
    version = bus.last_map.version;
    EXPECT_EQ(main.stop(), 0) << main.stderr_text();
  }
  bus.until([] { return false; }, 300);  // drain the first process's last messages
  bus.maps = 0;
  bus.last_map = global_map_t{};
  test::Child main(kBin + "main_robot", {"--config", kConfig, "--state", state});
  ASSERT_TRUE(bus.until([&] { return bus.maps > 0; }, 10000)) << main.stderr_text();
  EXPECT_EQ(bus.last_map.num_landmarks, 3);
  EXPECT_EQ(bus.last_map.version, version);
  EXPECT_NE(main.stderr_text().find("resumed from"), std::string::npos);
  // The robot's snapshot brings it up to date: it now holds 4 landmarks.
  lmap_snapshot_t snap{};
  snap.robot_id = 1;
  snap.seq = 3;
  snap.frame = 10;
  snap.num_chunks = 1;
  snap.id_end = 256;  // the whole id space of config/paper.yaml in one chunk
  snap.landmarks.resize(4);
  snap.num_landmarks = 4;
  for (int i = 0; i < 4; ++i) snap.landmarks[static_cast<std::size_t>(i)] = {10 + i, double(i), 2.0, {{0.01, 0.0}, {0.0, 0.01}}};
  bus.publish(channels::lmap_snapshot(), snap);
  EXPECT_TRUE(bus.until([&] { return bus.last_map.num_landmarks == 4; }, 10000));
  EXPECT_EQ(main.stop(), 0);
  std::remove(state.c_str());
}

}  // namespace
}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// System test of the simulator process over LCM (label `system`). Runs inside
// tools/netns_run.sh, which provides a private network namespace and
// LCM_DEFAULT_URL. Starts build/bin/simulator as a child process and listens.
// All waits are bounded; nothing sleeps for synchronisation: the subscriptions
// exist before the child starts, and loops run handleTimeout until a deadline.
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "../support/child_process.hpp"
#include "../support/test_keys.hpp"
#include "elaslam/common/channels.hpp"
#include "elaslam/ground_truth_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/sensor_frame_t.hpp"

namespace {

const std::string kSimulator = std::string(ELASLAM_BINARY_DIR) + "/bin/simulator";
const std::string kConfig = std::string(ELASLAM_SOURCE_DIR) + "/config/paper.yaml";
// Per-channel queue: larger than any run here, so the test can never drop a frame
// even if this thread is descheduled for a while.
constexpr int kQueueCapacity = 1024;

using elaslam::test::Child;

/// Records what arrives on SENSOR_1..3 and GROUND_TRUTH; optionally answers each
/// sensor frame with a POSE_<r> (a stand-in robot for --lockstep).
class Listener {
 public:
  explicit Listener(bool answer_poses) : answer_(answer_poses) {
    EXPECT_TRUE(lc_.good()) << "LCM not available: run under tools/netns_run.sh";
    // subscribeFunction: LCM's member-function subscriptions crash under GCC 12 UBSan (vptr).
    for (int r = 1; r <= 3; ++r)
      lc_.subscribeFunction(elaslam::channels::sensor(r), &Listener::on_sensor, this)
          ->setQueueCapacity(kQueueCapacity);
    lc_.subscribeFunction(elaslam::channels::ground_truth(), &Listener::on_truth, this)
        ->setQueueCapacity(kQueueCapacity);
  }

  /// Handle messages until `done()` holds and the child has exited, or the deadline.
  template <typename Done>
  void run(Child* child, Done done, int timeout_ms) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    while (std::chrono::steady_clock::now() < end) {
      lc_.handleTimeout(50);
      const bool exited = child->poll();
      if (exited && done()) break;
      if (exited) {  // drain what is still queued, then stop: no more will come
        while (lc_.handleTimeout(200) > 0) {
        }
        break;
      }
    }
  }

  std::vector<std::vector<int>> sensor_frames = std::vector<std::vector<int>>(4);  // [robot id] -> frames
  std::vector<int> truth_frames;
  std::vector<std::int64_t> sensor1_utime, truth_utime;
  int bad_messages = 0;

 private:
  static void on_sensor(const lcm::ReceiveBuffer*, const std::string& channel, const elaslam::sensor_frame_t* m,
                        Listener* self) {
    self->sensor(channel, m);
  }
  static void on_truth(const lcm::ReceiveBuffer*, const std::string&, const elaslam::ground_truth_t* m,
                       Listener* self) {
    self->truth(m);
  }
  void sensor(const std::string& channel, const elaslam::sensor_frame_t* m) {
    const int r = m->robot_id;
    if (r < 1 || r > 3 || channel != elaslam::channels::sensor(r) || m->num_obs < 0 || m->num_obs > 64) {
      ++bad_messages;
      return;
    }
    sensor_frames[static_cast<std::size_t>(r)].push_back(m->frame);
    if (r == 1) sensor1_utime.push_back(m->utime);
    if (answer_) {
      elaslam::pose_estimate_t p{};
      p.frame = m->frame;
      p.robot_id = m->robot_id;
      p.source_utime = m->utime;
      lc_.publish(elaslam::channels::pose(r), &p);
    }
  }
  void truth(const elaslam::ground_truth_t* m) {
    if (m->num_robots != 3 || m->num_landmarks != 72) ++bad_messages;
    truth_frames.push_back(m->frame);
    truth_utime.push_back(m->utime);
  }

  lcm::LCM lc_;
  bool answer_;
};

std::vector<int> iota_frames(int n) {
  std::vector<int> v;
  for (int i = 0; i < n; ++i) v.push_back(i);
  return v;
}

void expect_all_frames(const Listener& l, int n) {
  for (int r = 1; r <= 3; ++r)
    EXPECT_EQ(l.sensor_frames[static_cast<std::size_t>(r)], iota_frames(n)) << "SENSOR_" << r;
  EXPECT_EQ(l.truth_frames, iota_frames(n)) << "GROUND_TRUTH";
  EXPECT_EQ(l.sensor1_utime, l.truth_utime) << "one utime stamp per frame";
  EXPECT_EQ(l.bad_messages, 0);
}

TEST(SystemSimulator, PublishesEveryFrameOnEveryChannel) {
  Listener l(false);
  Child sim(kSimulator, {"--config", kConfig, "--frames", "20", "--rate", "50", "--start-delay-ms", "200", "--dynamism", "50"});
  l.run(&sim, [&] { return l.truth_frames.size() == 20; }, 30000);
  ASSERT_TRUE(sim.poll()) << "simulator still running after 30 s";
  EXPECT_EQ(sim.exit_code(), 0) << sim.stderr_text();
  expect_all_frames(l, 20);
  EXPECT_NE(sim.stderr_text().find("20 frames published"), std::string::npos) << sim.stderr_text();
}

TEST(SystemSimulator, LockstepWaitsForEveryRobotsPose) {
  Listener l(true);  // answers every SENSOR_<r> with POSE_<r>
  Child sim(kSimulator, {"--config", kConfig, "--frames", "30", "--rate", "1000", "--lockstep", "--lockstep-timeout-ms", "5000",
             "--start-delay-ms", "200"});
  l.run(&sim, [&] { return l.truth_frames.size() == 30; }, 40000);
  ASSERT_TRUE(sim.poll());
  EXPECT_EQ(sim.exit_code(), 0) << sim.stderr_text();
  expect_all_frames(l, 30);
  EXPECT_NE(sim.stderr_text().find("lockstep timeouts 0,"), std::string::npos) << sim.stderr_text();
}

TEST(SystemSimulator, LockstepTimeoutIsCountedAndTheRunGoesOn) {
  Listener l(false);  // nobody answers
  Child sim(kSimulator, {"--config", kConfig, "--frames", "3", "--rate", "100", "--lockstep", "--lockstep-timeout-ms", "100"});
  l.run(&sim, [&] { return l.truth_frames.size() == 3; }, 30000);
  ASSERT_TRUE(sim.poll());
  EXPECT_EQ(sim.exit_code(), 0) << sim.stderr_text();
  EXPECT_NE(sim.stderr_text().find("lockstep timeouts 3,"), std::string::npos) << sim.stderr_text();
}

TEST(SystemSimulator, StopsCleanlyOnSigterm) {
  Listener l(false);
  Child sim(kSimulator, {"--config", kConfig, "--frames", "1000000", "--rate", "100"});
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  bool signalled = false;
  while (!sim.poll() && std::chrono::steady_clock::now() < end) {
    l.run(&sim, [] { return true; }, 50);
    if (!signalled && l.truth_frames.size() >= 5) {
      sim.signal(SIGTERM);
      signalled = true;
    }
  }
  ASSERT_TRUE(sim.poll()) << "no exit within 20 s";
  EXPECT_TRUE(signalled);
  EXPECT_EQ(sim.exit_code(), 0) << sim.stderr_text();
  EXPECT_NE(sim.stderr_text().find("stopped by signal"), std::string::npos) << sim.stderr_text();
}

TEST(SystemSimulator, BadCommandLineOrConfigExitsWith2) {
  // The config lookup: a variable that names no file is an error, never a fall-through.
  Child bad_env(kSimulator, {"--frames", "20"}, {"ELASLAM_CONFIG=/nonexistent/elaslam.yaml"});
  EXPECT_EQ(bad_env.wait(), 2);
  EXPECT_NE(bad_env.stderr_text().find("$ELASLAM_CONFIG=/nonexistent/elaslam.yaml: no such file"), std::string::npos)
      << bad_env.stderr_text();
  Child bad_range(kSimulator, {"--config", kConfig, "--frames", "0"});
  EXPECT_EQ(bad_range.wait(), 2);
  Child missing(kSimulator, {"--config", "/nonexistent.yaml"});
  EXPECT_EQ(missing.wait(), 2);
  EXPECT_NE(missing.stderr_text().find("--config /nonexistent.yaml: no such file"), std::string::npos)
      << missing.stderr_text();
  // An override that breaks a cross-field check: robot 1 would move 12.7 m per frame > D = 8 m.
  Child too_fast(kSimulator, {"--config", kConfig, "--rate", "0.1"});
  EXPECT_EQ(too_fast.wait(), 2);
  EXPECT_NE(too_fast.stderr_text().find("scenario.robots[0].speed_mps"), std::string::npos)
      << too_fast.stderr_text();
}

// Without --config or $ELASLAM_CONFIG, a program of the build tree finds the default
// where an installed one would: <prefix>/share/elaslam/config/paper.yaml, the build
// tree mirroring the installed layout (build/share/elaslam/config -> config/).
TEST(SystemSimulator, FindsTheInstalledDefaultConfig) {
  if (access("/etc/elaslam/elaslam.yaml", F_OK) == 0) GTEST_SKIP() << "this host has /etc/elaslam/elaslam.yaml";
  Child sim(kSimulator, {"--check"}, {"ELASLAM_CONFIG"});
  EXPECT_EQ(sim.wait(), 0) << sim.stderr_text();
  Child robot(std::string(ELASLAM_BINARY_DIR) + "/bin/robot_node", {"--robot", "1", "--lcm-url", "memq://"},
              {"ELASLAM_CONFIG"});
  // The node starts (memq://) and says which config it read; stop it.
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (robot.stderr_text().find("config") == std::string::npos && std::chrono::steady_clock::now() < end && !robot.poll())
    std::this_thread::sleep_for(std::chrono::milliseconds(10));  // polling a child's output, bounded
  EXPECT_EQ(robot.stop(), 0) << robot.stderr_text();
  EXPECT_NE(robot.stderr_text().find("share/elaslam/config/paper.yaml (installed default)"), std::string::npos)
      << robot.stderr_text();
}

// --check validates a node's configuration without starting it (after an edit of
// /etc/elaslam/elaslam.yaml on a robot, before restarting its service).
TEST(SystemSimulator, NodesCheckTheirConfigWithoutStarting) {
  const std::string bin = std::string(ELASLAM_BINARY_DIR) + "/bin/";
  Child robot_ok(bin + "robot_node", {"--robot", "2", "--config", kConfig, "--check"});
  EXPECT_EQ(robot_ok.wait(), 0) << robot_ok.stderr_text();
  Child main_ok(bin + "main_robot", {"--config", kConfig, "--check"});
  EXPECT_EQ(main_ok.wait(), 0) << main_ok.stderr_text();
  const std::string bad = testing::TempDir() + "/bad_robot.yaml";
  std::ofstream(bad) << "robot:\n  mode: fast\n";
  Child robot_bad(bin + "robot_node", {"--robot", "2", "--config", bad, "--check"});
  EXPECT_EQ(robot_bad.wait(), 2);
  EXPECT_NE(robot_bad.stderr_text().find("robot.mode: invalid value 'fast'"), std::string::npos) << robot_bad.stderr_text();
  Child main_bad(bin + "main_robot", {"--config", bad, "--check"});
  EXPECT_EQ(main_bad.wait(), 2);
  EXPECT_NE(main_bad.stderr_text().find("main: missing"), std::string::npos) << main_bad.stderr_text();
}

// --check also loads the team key as the process would at start: a key file that
// others may read stops the check (exit 2, naming the file and its mode), not the
// service's first start; a good one passes.
// --check loads the team's roster and the node's own key as the start would: a key
// file others can read, or a key that is not the node's in the roster, fails the
// check (exit 2, the reason named), not the service's first start.
TEST(SystemSimulator, CheckLoadsTheKeysAsTheStartWould) {
  const std::string bin = std::string(ELASLAM_BINARY_DIR) + "/bin/";
  const std::string dir = testing::TempDir();
  const std::string roster = dir + "/check_roster.yaml";
  std::ofstream(roster) << elaslam::test::team_yaml({2, elaslam::transport::kSenderMain, elaslam::transport::kSenderSimulator});
  struct Program {
    std::string path;
    std::vector<std::string> extra;
    std::int16_t sender;
  };
  const std::vector<Program> programs = {{bin + "robot_node", {"--robot", "2"}, 2},
                                         {bin + "main_robot", {}, elaslam::transport::kSenderMain},
                                         {kSimulator, {}, elaslam::transport::kSenderSimulator}};
  for (const mode_t mode : {0644, 0600}) {
    for (const auto& p : programs) {
      const std::string key = dir + "/check_" + elaslam::transport::sender_name(p.sender) + ".key";
      std::ofstream(key) << elaslam::test::team_key_text(p.sender);
      ASSERT_EQ(chmod(key.c_str(), mode), 0);
      std::vector<std::string> args = p.extra;
      for (const char* a : {"--config", kConfig.c_str(), "--roster", roster.c_str(), "--key-file", key.c_str(), "--check"})
        args.emplace_back(a);
      Child c(p.path, args);
      if (mode == 0600) {
        EXPECT_EQ(c.wait(), 0) << p.path << ": " << c.stderr_text();
      } else {
        EXPECT_EQ(c.wait(), 2) << p.path;
        EXPECT_NE(c.stderr_text().find(key + ": has mode 0644"), std::string::npos) << p.path << ": " << c.stderr_text();
      }
    }
  }
  // robot_node 2 with main's key: not robot_2's in the roster.
  Child wrong(bin + "robot_node", {"--robot", "2", "--config", kConfig, "--roster", roster, "--key-file",
                                   dir + "/check_main.key", "--check"});
  EXPECT_EQ(wrong.wait(), 2);
  EXPECT_NE(wrong.stderr_text().find("is not robot_2's"), std::string::npos) << wrong.stderr_text();
}

}  // namespace

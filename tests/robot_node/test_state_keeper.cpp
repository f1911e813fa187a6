// SPDX-License-Identifier: Apache-2.0
// The restart policy (StateKeeper, resume_state, save_state): saved after processed
// frames and resumed at the frame saved; a resumed state the arriving frames do not
// continue is dropped after kMisfitFrames refusals, and so is the map of a sensor
// source that starts over, each with a larger incarnation; a corrupt file is moved
// aside and the node starts fresh.
#include "elaslam/robot_node/state_keeper.hpp"

#include <filesystem>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "elaslam/common/atomic_file.hpp"
#include "scene.hpp"

namespace elaslam {
namespace {

constexpr int kId = 1;

struct Scratch {
  Scratch() {
    char tmpl[] = "/tmp/elaslam_keeper_test.XXXXXX";
    dir = ::mkdtemp(tmpl);
    path = dir + "/robot1.state";
  }
  ~Scratch() { std::filesystem::remove_all(dir); }
  std::string dir, path;
};

RobotOptions options() {
  RobotOptions o = test::robot_options(Mode::kEla);
  o.state_save_interval_s = 0.0;  // after every processed frame
  return o;
}

// Frames first..last of a robot standing still among eight landmarks, each followed by
// a turn of the keeper.
void feed(RobotNode* node, StateKeeper* keeper, int first, int last) {
  static const auto lms = test::ring(8, 4.0);
  std::mt19937_64 rng(static_cast<std::uint64_t>(first) + 17);
  for (int f = first; f <= last; ++f) {
    node->on_sensor(test::to_msg(test::frame_from(f, Pose2{}, Pose2{}, lms, test::all_ids(8), &rng), kId), 0);
    keeper->turn();
  }
}

TEST(StateKeeper, SavesProcessedFramesAndAResumeContinuesThere) {
  Scratch s;
  RobotNode node(options(), kId);
  EXPECT_FALSE(resume_state(s.path, 5, 0, &node));  // no file yet: fresh, this start's incarnation
  EXPECT_EQ(node.incarnation(), 5);
  StateKeeper keeper(s.path, options(), &node, false, 5, 0);
  feed(&node, &keeper, 0, 20);
  ASSERT_TRUE(std::filesystem::exists(s.path));
  RobotNode again(options(), kId);
  ASSERT_TRUE(resume_state(s.path, 9, 0, &again));
  EXPECT_EQ(again.robot().last_frame(), 20);
  EXPECT_EQ(again.incarnation(), 5);  // a resumed node keeps its own
  EXPECT_EQ(again.robot().filter().num_landmarks(), node.robot().filter().num_landmarks());
  EXPECT_GT(again.event_seq(), node.event_seq());  // numbered on past anything sent after the save
}

TEST(StateKeeper, AResumedStateTheFramesDoNotContinueIsDropped) {
  Scratch s;
  {
    RobotNode node(options(), kId);
    StateKeeper keeper(s.path, options(), &node, false, 1, 0);
    feed(&node, &keeper, 0, 60);
  }
  RobotNode node(options(), kId);
  ASSERT_TRUE(resume_state(s.path, 7, 0, &node));
  StateKeeper keeper(s.path, options(), &node, true, 7, 0);
  // A new run from frame 0: every frame older than the state's 60, refused.
  feed(&node, &keeper, 0, static_cast<int>(StateKeeper::kMisfitFrames) - 2);
  EXPECT_EQ(node.robot().last_frame(), 60);  // not yet: fewer refusals than kMisfitFrames
  feed(&node, &keeper, static_cast<int>(StateKeeper::kMisfitFrames) - 1, static_cast<int>(StateKeeper::kMisfitFrames) - 1);
  EXPECT_EQ(node.robot().last_frame(), -1);  // started fresh
  EXPECT_EQ(node.incarnation(), 8);          // above this start's
  feed(&node, &keeper, static_cast<int>(StateKeeper::kMisfitFrames), 30);
  EXPECT_EQ(node.robot().last_frame(), 30);  // and the new run goes on
}

TEST(StateKeeper, ASensorSourceThatStartsOverRestartsTheRobotWithoutAFile) {
  RobotNode node(options(), kId);
  node.set_incarnation(3);
  StateKeeper keeper("", options(), &node, false, 3, 0);
  feed(&node, &keeper, 0, 40);
  ASSERT_GT(node.robot().filter().num_landmarks(), 0);
  feed(&node, &keeper, 0, static_cast<int>(StateKeeper::kMisfitFrames) - 1);
  EXPECT_EQ(node.robot().last_frame(), -1);
  EXPECT_EQ(node.robot().filter().num_landmarks(), 0);
  EXPECT_EQ(node.incarnation(), 4);
}

TEST(StateKeeper, ACorruptFileIsMovedAsideAndTheNodeStartsFresh) {
  Scratch s;
  std::string why;
  ASSERT_TRUE(files::write_atomic(s.path, "{\"format\": \"not a state\"}", &why)) << why;
  RobotNode node(options(), kId);
  EXPECT_FALSE(resume_state(s.path, 2, 0, &node));
  EXPECT_FALSE(std::filesystem::exists(s.path));
  EXPECT_TRUE(std::filesystem::exists(s.path + ".corrupt"));
  EXPECT_EQ(node.robot().last_frame(), -1);
  EXPECT_EQ(node.incarnation(), 2);
}

}  // namespace
}  // namespace elaslam

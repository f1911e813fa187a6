// SPDX-License-Identifier: Apache-2.0
// The nodes on the message layer, over the in-process transport: RobotPorts and
// MainPorts (what robot_node, main_robot and the in-process team run all run), the
// channel suffix, and the simulator's lockstep waits.
#include <gtest/gtest.h>

#include <algorithm>

#include <atomic>
#include <cstdio>
#include <string>
#include <vector>

#include "../support/messages.hpp"
#include "elaslam/common/channels.hpp"
#include "elaslam/global_map_t.hpp"
#include "elaslam/main_robot/main_ports.hpp"
#include "elaslam/robot_node/robot_ports.hpp"
#include "elaslam/simulator/lockstep.hpp"
#include "elaslam/simulator/messages.hpp"
#include "elaslam/simulator/scenario.hpp"
#include "elaslam/simulator/world.hpp"
#include "elaslam/transport/inprocess_transport.hpp"
#include "elaslam/transport/node_shell.hpp"

namespace elaslam {
namespace {

using transport::InProcessTransport;
using transport::NodeShell;
using transport::ShellOptions;

const std::string kConfig = std::string(ELASLAM_SOURCE_DIR) + "/config/paper.yaml";

/// Everything published on a team's channels, in dispatch order: "<channel> <frame>".
class Observer {
 public:
  Observer(InProcessTransport& bus, const std::string& suffix) : shell_(bus, ShellOptions("observer", suffix, nullptr)) {
    watch<pose_estimate_t>("POSE_[0-9]+" + suffix);
    watch<landmark_event_t>(channels::lmap_event(suffix));
    watch<lmap_events_t>(channels::lmap_events(suffix));
    watch<lmap_snapshot_t>(channels::lmap_snapshot(suffix));
    watch<global_map_t>(channels::global_map(suffix));
    watch<dynamic_notice_t>(channels::dynamic_notice(suffix));
  }
  NodeShell& shell() { return shell_; }
  std::vector<std::string> seen;
  int batched_events = 0;  // events carried by the LMAP_EVENTS seen

 private:
  template <class Msg>
  void watch(const std::string& pattern) {
    shell_.subscribe<Msg>(pattern, [this](const Msg& m, const std::string& ch) {
      seen.push_back(ch + " " + std::to_string(m.frame));
      if constexpr (std::is_same_v<Msg, lmap_events_t>) batched_events += m.num_events;
    }, transport::kUnboundedQueue);
  }
  NodeShell shell_;
};

/// Robot 1's sensor frames of the paper's scenario at 50 % dynamism.
std::vector<sensor_frame_t> robot1_frames(int n) {
  sim::ScenarioOptions o = sim::load_scenario(kConfig);
  o.dynamism_percent = 50.0;
  sim::World world(o);
  std::vector<sensor_frame_t> out;
  for (int k = 0; k < n; ++k) {
    if (k > 0) world.step();
    out.push_back(sim::to_message(world.sensor_frame(0), 1000 + k));
  }
  return out;
}

/// Robot 1's node on its ports over an in-process bus, and an observer of the team's
/// channels that also publishes the SENSOR frames.
class RobotOnBus : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_TRUE(ports.open()); }
  void send(const sensor_frame_t& f) {
    obs.shell().publish(channels::sensor(1), f);
    bus.dispatch_all();
  }
  InProcessTransport bus;
  NodeShell shell{bus, ShellOptions("robot_node 1", "", nullptr)};
  RobotNode node{load_robot_options(kConfig), 1};
  RobotPorts<NodeShell> ports{shell, node};
  Observer obs{bus, ""};
};

TEST_F(RobotOnBus, EachFrameGoesOutAsItsPoseThenItsEventsAndSnapshot) {
  int after_frame = 0;
  ports.after_frame([&](const RobotNode& n) {
    EXPECT_EQ(&n, &node);
    ++after_frame;
  });
  std::vector<pose_estimate_t> poses;
  obs.shell().subscribe<pose_estimate_t>(
      channels::pose(1), [&](const pose_estimate_t& m, const std::string&) { poses.push_back(m); },
      transport::kUnboundedQueue);
  for (const auto& f : robot1_frames(12)) send(f);
  EXPECT_EQ(after_frame, 12);
  // Per frame: the POSE first (the frame's end for a lockstep simulator), then its
  // events (LMAP_EVENTS, robot.node.batch_events) and a snapshot every 10 frames.
  int frame = -1, batches = 0, snapshots = 0;
  for (const std::string& s : obs.seen) {
    const std::string channel = s.substr(0, s.find(' '));
    if (channel == "POSE_1") {
      EXPECT_EQ(s, "POSE_1 " + std::to_string(++frame));
    } else {
      EXPECT_EQ(s, channel + " " + std::to_string(frame)) << "an output of the frame after its POSE";
      EXPECT_NE(channel, "LMAP_EVENT") << "events go batched";
      ++(channel == "LMAP_EVENTS" ? batches : snapshots);
    }
  }
  EXPECT_EQ(frame, 11);
  EXPECT_GT(batches, 0);
  EXPECT_LE(batches, 12) << "one message per frame at this scene's ~10 landmarks in view";
  EXPECT_EQ(snapshots, 2);  // frames 0 and 10
  EXPECT_EQ(static_cast<int>(node.counters().events_sent), obs.batched_events);
  // Each POSE says what follows it: the seq of the frame's last event, and the
  // snapshot's chunks on frames 0 and 10.
  ASSERT_EQ(poses.size(), 12u);
  EXPECT_EQ(poses.back().event_seq, node.event_seq());
  for (const auto& p : poses) EXPECT_EQ(p.snapshot_chunks, p.frame % 10 == 0 ? 1 : 0) << p.frame;
  for (std::size_t i = 1; i < poses.size(); ++i) EXPECT_GE(poses[i].event_seq, poses[i - 1].event_seq);
}

// Without robot.node.batch_events: the same events, one LMAP_EVENT each, in the same
// place in the frame's outputs (after its POSE).
TEST(RobotOnBusSingly, WithoutBatchingEachEventGoesAlone) {
  InProcessTransport bus;
  NodeShell shell{bus, ShellOptions("robot_node 1", "", nullptr)};
  RobotOptions o = load_robot_options(kConfig);
  o.batch_events = false;
  RobotNode node{o, 1};
  RobotPorts<NodeShell> ports{shell, node};
  Observer obs{bus, ""};
  ASSERT_TRUE(ports.open());
  for (const auto& f : robot1_frames(12)) {
    obs.shell().publish(channels::sensor(1), f);
    bus.dispatch_all();
  }
  int frame = -1, events = 0;
  for (const std::string& s : obs.seen) {
    const std::string channel = s.substr(0, s.find(' '));
    EXPECT_NE(channel, "LMAP_EVENTS");
    if (channel == "POSE_1") ++frame;
    if (channel == "LMAP_EVENT") {
      EXPECT_EQ(s, "LMAP_EVENT " + std::to_string(frame));
      ++events;
    }
  }
  EXPECT_EQ(frame, 11);
  EXPECT_GT(events, 12);
  EXPECT_EQ(static_cast<int>(node.counters().events_sent), events);
  EXPECT_EQ(obs.batched_events, 0);
}

// Where each processed frame's time went (FrameStages): one sample per stage per
// processed frame and none for a refused one; "receive" is measured from the
// SENSOR's own stamp, so a frame stamped 50 ms before it is published reads
// between 50 ms and 50 ms plus the whole loop there; the other stages of a frame
// lie within the loop. (Bounds by the measured loop, not by any expected speed.)
TEST_F(RobotOnBus, EveryProcessedFrameIsTimedByStage) {
  std::vector<sensor_frame_t> frames = robot1_frames(6);
  const std::int64_t start = shell.now_utime();
  for (auto& f : frames) {
    f.utime = shell.now_utime() - 50000;  // sent 50 ms ago
    send(f);
  }
  const std::int64_t loop = shell.now_utime() - start;
  send(frames[2]);  // a duplicate: refused, not timed
  const FrameStages& st = ports.stages();
  EXPECT_EQ(node.counters().frames, 6);
  for (const DurationHistogram* h : {&st.receive, &st.frame, &st.outputs, &st.pose}) {
    EXPECT_EQ(h->count(), 6);
    EXPECT_LE(h->max(), h == &st.receive ? 50000 + loop : loop);
  }
  EXPECT_GE(st.receive.quantile(0.5), 50000);
}

/// An in-process bus that says it is in channel groups (grouped_lcm_transport.hpp):
/// what a node subscribes to is then what wakes it. Records the patterns.
class GroupedBus final : public transport::Transport {
 public:
  explicit GroupedBus(InProcessTransport& bus) : bus_(bus) {}
  bool good() const override { return true; }
  const char* kind() const override { return "in-process (channel groups)"; }
  bool publish(const std::string& channel, const void* data, std::size_t size) override {
    return bus_.publish(channel, data, size);
  }
  int subscribe(const std::string& pattern, transport::RawHandler handler, void* context, int queue) override {
    patterns.push_back(pattern);
    return bus_.subscribe(pattern, handler, context, queue);
  }
  void unsubscribe(int id) override { bus_.unsubscribe(id); }
  int handle_timeout(int timeout_ms) override { return bus_.handle_timeout(timeout_ms); }
  bool channel_groups() const override { return true; }
  std::vector<std::string> patterns;

 private:
  InProcessTransport& bus_;
};

// In channel groups a robot does not read its own POSE channel (that would wake it for
// every robot's POSE): a second sender with its id shows on its STATUS channel instead.
TEST(RobotPorts, InChannelGroupsASecondSenderShowsOnTheRobotsStatus) {
  InProcessTransport bus;
  GroupedBus grouped(bus);
  NodeShell shell(grouped, ShellOptions("robot_node 1", "", nullptr));
  RobotNode node(load_robot_options(kConfig), 1);
  node.set_incarnation(100);
  RobotPorts<NodeShell> ports(shell, node);
  ASSERT_TRUE(ports.open());
  EXPECT_EQ(std::count(grouped.patterns.begin(), grouped.patterns.end(), channels::status_robot(1)), 1);
  EXPECT_EQ(std::count(grouped.patterns.begin(), grouped.patterns.end(), channels::pose(1)), 0);

  NodeShell other(bus, ShellOptions("robot_node 1 (second)", "", nullptr));
  pose_estimate_t pose{};
  pose.robot_id = 1;
  pose.incarnation = 200;
  other.publish(channels::pose(1), pose);  // not read: no fault from a POSE
  ports.publish_status();                  // its own STATUS, looped back: no fault
  bus.dispatch_all();
  EXPECT_EQ(node.status_msg(0).fault_flags & node_status_t::FAULT_DUPLICATE_SENDER, 0);
  node_status_t st = node.status_msg(0);
  st.incarnation = 200;  // the second process's STATUS
  other.publish(channels::status_robot(1), st);
  bus.dispatch_all();
  EXPECT_NE(node.status_msg(0).fault_flags & node_status_t::FAULT_DUPLICATE_SENDER, 0);
  EXPECT_EQ(node.counters().foreign_poses, 1);
}

// A robot reads the global map's moving lists from GLOBAL_MOVING, not from GLOBAL_MAP
// (tens of kB a frame in a large world): a lost notice is repaired from the former;
// the same lists in a GLOBAL_MAP change nothing.
TEST_F(RobotOnBus, ALostNoticeIsRepairedFromGlobalMovingAlone) {
  for (const auto& f : robot1_frames(3)) send(f);
  global_map_t m{};
  m.num_chunks = 1;
  m.id_end = 256;
  contract::set_count(&m.moving_ids, &m.num_moving, 1);
  m.moving_ids[0] = 7;
  m.moving_frames.assign(1, 2);
  m.moving_by.assign(1, 2);  // robot 2 found it moving; robot 1 never got the notice
  obs.shell().publish(channels::global_map(), m);
  bus.dispatch_all();
  EXPECT_EQ(node.counters().notices_repaired, 0);
  obs.shell().publish(channels::global_moving(), m);
  bus.dispatch_all();
  EXPECT_EQ(node.counters().notices_repaired, 1);
}

TEST(RobotPorts, BadInputIsCountedByTheNodeAndLoggedByTheShell) {
  InProcessTransport bus;
  std::FILE* log = std::tmpfile();
  NodeShell shell(bus, ShellOptions("robot_node 1", "", log));
  RobotNode node(load_robot_options(kConfig), 1);
  RobotPorts<NodeShell> ports(shell, node);
  ports.open();
  NodeShell other(bus, ShellOptions("other", "", nullptr));
  sensor_frame_t wrong = robot1_frames(1).front();
  wrong.robot_id = 2;  // another robot's frame on our channel
  other.publish(channels::sensor(1), wrong);
  const std::uint8_t garbage[3] = {1, 2, 3};
  bus.publish(channels::sensor(1), garbage, sizeof garbage);
  dynamic_notice_t n{};
  n.landmark_id = 5;
  n.detected_by = 2;
  for (std::int64_t seq : {1, 2, 5}) {  // 3 and 4 lost
    n.seq = seq;
    other.publish(channels::dynamic_notice(), n);
  }
  bus.dispatch_all();
  EXPECT_EQ(node.counters().rejected_inputs, 1);
  EXPECT_EQ(node.counters().decode_errors, 1);
  EXPECT_EQ(node.counters().queue_drops, 2);
  EXPECT_EQ(shell.counters().inputs.refused, 1);
  std::rewind(log);
  char line[512];
  ASSERT_NE(std::fgets(line, sizeof line, log), nullptr);
  EXPECT_STREQ(line, "robot_node 1: sensor frame refused: robot_id is not this robot's (got 2) (warning 1)\n");
  ASSERT_NE(std::fgets(line, sizeof line, log), nullptr);
  EXPECT_STREQ(line, "robot_node 1: cannot decode a sensor_frame_t (warning 2)\n");
  std::fclose(log);
}

landmark_event_t event(int robot, std::int64_t seq, int frame, int kind, int id) {
  return test::event_msg(robot, seq, kind, id, frame, id, 0.0);
}

pose_estimate_t pose(int robot, int frame) { return test::pose_msg(robot, frame, 0.0); }

/// main_robot on its ports over an in-process bus, and an observer of the team's
/// channels that also publishes as the robots.
class MainOnBus : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_TRUE(ports.open()); }
  InProcessTransport bus;
  NodeShell shell{bus, ShellOptions("main_robot", "", nullptr)};
  MainNode node{GlobalMapOptions{}};
  MainPorts<NodeShell> ports{shell, node};
  Observer obs{bus, ""};
};

TEST_F(MainOnBus, GlobalMapWhenEveryRobotFinishedAFrameAndNoticesAtOnce) {
  NodeShell& robots = obs.shell();
  robots.publish(channels::lmap_event(), event(1, 1, 0, landmark_event_t::ADD, 4));
  robots.publish(channels::pose(1), pose(1, 0));  // the only robot seen so far: frame 0 is done
  robots.publish(channels::lmap_event(), event(2, 1, 0, landmark_event_t::ADD, 4));
  robots.publish(channels::pose(2), pose(2, 0));
  robots.publish(channels::pose(1), pose(1, 1));
  robots.publish(channels::lmap_event(), event(2, 2, 1, landmark_event_t::MOVING, 4));
  robots.publish(channels::pose(2), pose(2, 1));
  bus.dispatch_all();
  ports.publish_map(1);
  bus.dispatch_all();
  const std::vector<std::string> expected = {
      "LMAP_EVENT 0", "POSE_1 0", "LMAP_EVENT 0", "POSE_2 0", "POSE_1 1", "LMAP_EVENT 1", "POSE_2 1",
      "GLOBAL_MAP 0",      // after POSE_1 0 (queued behind what was queued then)
      "DYNAMIC_NOTICE 1",  // robot 2's MOVING
      "GLOBAL_MAP 1",      // after POSE_2 1
      "GLOBAL_MAP 1"};     // on request
  EXPECT_EQ(obs.seen, expected);
  EXPECT_EQ(node.counters().events, 3);
  EXPECT_EQ(node.counters().notices_sent, 1);
}

// LMAP_EVENTS on the bus: main_robot applies a batch's events before the POSE that
// follows it, and a refused batch is logged by the shell and counted by the node.
TEST_F(MainOnBus, BatchedEventsAreAppliedBeforeTheFramesPose) {
  NodeShell& robots = obs.shell();
  lmap_events_t b = test::events_msg({event(1, 1, 0, landmark_event_t::ADD, 4), event(1, 2, 0, landmark_event_t::ADD, 6)});
  robots.publish(channels::lmap_events(), b);
  robots.publish(channels::pose(1), pose(1, 0));
  b.events[1].robot_id = 2;  // a header that does not speak for its events
  robots.publish(channels::lmap_events(), b);
  bus.dispatch_all();
  EXPECT_EQ(node.counters().events, 2);
  EXPECT_EQ(node.counters().rejected_inputs, 1);
  const std::vector<std::string> expected = {"LMAP_EVENTS 0", "POSE_1 0", "LMAP_EVENTS 0", "GLOBAL_MAP 0"};
  EXPECT_EQ(obs.seen, expected);
  EXPECT_EQ(node.map().count(GlobalStatus::kStatic), 2);
}

// The POSE goes out before the frame's events and snapshot, saying what follows
// (event_seq, snapshot_chunks): main_robot holds it, and the frame's GLOBAL_MAP goes
// out once those are applied; a robot whose first POSE is held holds the team's map
// back too; events that never come are let go at the robot's next POSE.
TEST_F(MainOnBus, AHeldPoseFinishesItsFrameWhenItsEventsAndSnapshotAreIn) {
  NodeShell& robots = obs.shell();
  std::vector<global_map_t> maps;
  obs.shell().subscribe<global_map_t>(
      channels::global_map(), [&](const global_map_t& m, const std::string&) { maps.push_back(m); },
      transport::kUnboundedQueue);
  auto posed = [](int robot, int frame, std::int64_t seq, int chunks = 0) {
    pose_estimate_t p = pose(robot, frame);
    p.event_seq = seq;
    p.snapshot_chunks = static_cast<std::int16_t>(chunks);
    return p;
  };
  // Frame 0: robot 2's POSE alone, nothing follows; robot 1's POSE, its two events follow.
  robots.publish(channels::pose(2), posed(2, 0, 0));
  robots.publish(channels::pose(1), posed(1, 0, 2));
  bus.dispatch_all();
  ASSERT_EQ(maps.size(), 1u) << "robot 2's frame 0 alone (robot 1 unheard of)";
  robots.publish(channels::lmap_events(),
                 test::events_msg({event(1, 1, 0, landmark_event_t::ADD, 4), event(1, 2, 0, landmark_event_t::ADD, 6)}));
  bus.dispatch_all();
  EXPECT_EQ(node.counters().events, 2);
  ASSERT_EQ(maps.size(), 1u) << "frame 0 was out already; robot 1 finished it now";
  // Frame 1: both POSEs first; robot 1 also sends a snapshot (one chunk).
  robots.publish(channels::pose(1), posed(1, 1, 3, 1));
  robots.publish(channels::pose(2), posed(2, 1, 0));
  robots.publish(channels::lmap_event(), event(1, 3, 1, landmark_event_t::ADD, 9));
  bus.dispatch_all();
  EXPECT_EQ(maps.size(), 1u) << "robot 1's frame 1 waits for its snapshot";
  lmap_snapshot_t snap{};
  snap.robot_id = 1;
  snap.seq = 3;
  snap.frame = 1;
  snap.num_chunks = 1;
  snap.id_end = node.map().max_landmark_id();
  robots.publish(channels::lmap_snapshot(), snap);
  bus.dispatch_all();
  ASSERT_EQ(maps.size(), 2u);
  EXPECT_EQ(maps.back().frame, 1);
  EXPECT_EQ(maps.back().num_landmarks, 3) << "4, 6 and 9: the map has robot 1's frame";
  // Frame 2: robot 1's events are lost. Frame 3's POSE lets frame 2 go.
  robots.publish(channels::pose(2), posed(2, 2, 0));
  robots.publish(channels::pose(1), posed(1, 2, 4));
  bus.dispatch_all();
  EXPECT_EQ(maps.size(), 2u);
  robots.publish(channels::pose(2), posed(2, 3, 0));
  robots.publish(channels::pose(1), posed(1, 3, 5));
  bus.dispatch_all();
  ASSERT_EQ(maps.size(), 3u);
  EXPECT_EQ(maps.back().frame, 2);
  // A robot first heard of with a held POSE holds the team's map back.
  robots.publish(channels::pose(3), posed(3, 4, 1));
  robots.publish(channels::pose(2), posed(2, 4, 0));
  robots.publish(channels::lmap_event(), event(1, 6, 4, landmark_event_t::ADD, 12));
  robots.publish(channels::pose(1), posed(1, 4, 6));
  bus.dispatch_all();
  ASSERT_EQ(maps.size(), 4u) << "frame 3 (robot 1's let go by its frame 4), not frame 4";
  EXPECT_EQ(maps.back().frame, 3);
  robots.publish(channels::lmap_event(), event(3, 1, 4, landmark_event_t::ADD, 13));
  bus.dispatch_all();
  ASSERT_EQ(maps.size(), 5u);
  EXPECT_EQ(maps.back().frame, 4);
  // On separate ports the events and snapshot may come before their POSE: then it
  // finishes the frame at once.
  snap.seq = 7;
  snap.frame = 5;
  robots.publish(channels::lmap_event(), event(1, 7, 5, landmark_event_t::UPDATE, 12));
  robots.publish(channels::lmap_snapshot(), snap);
  robots.publish(channels::pose(2), posed(2, 5, 0));
  robots.publish(channels::pose(3), posed(3, 5, 1));
  robots.publish(channels::pose(1), posed(1, 5, 7, 1));
  bus.dispatch_all();
  ASSERT_EQ(maps.size(), 6u);
  EXPECT_EQ(maps.back().frame, 5);
  EXPECT_EQ(node.counters().rejected_inputs, 0);
}

// A GLOBAL_MAP publication is followed by GLOBAL_MOVING, its moving lists alone (no
// landmarks), the same stamps, over the whole id range (what the robots read), when
// those lists changed since the last GLOBAL_MOVING (main.moving_repeat_s: or when
// that one is old; MainEventBatches below).
TEST_F(MainOnBus, AGlobalMapIsFollowedByItsMovingListsAloneWhenTheyChanged) {
  std::vector<global_map_t> maps, moving;
  obs.shell().subscribe<global_map_t>(
      channels::global_map(), [&](const global_map_t& m, const std::string&) { maps.push_back(m); },
      transport::kUnboundedQueue);
  obs.shell().subscribe<global_map_t>(
      channels::global_moving(), [&](const global_map_t& m, const std::string&) { moving.push_back(m); },
      transport::kUnboundedQueue);
  NodeShell& robots = obs.shell();
  for (int id : {4, 6, 9}) robots.publish(channels::lmap_event(), event(1, id, 0, landmark_event_t::ADD, id));
  robots.publish(channels::lmap_event(), event(1, 10, 0, landmark_event_t::MOVING, 6));
  robots.publish(channels::pose(1), pose(1, 0));
  bus.dispatch_all();
  ASSERT_EQ(maps.size(), 1u);
  ASSERT_EQ(moving.size(), 1u);
  const global_map_t &g = maps[0], &m = moving[0];
  EXPECT_EQ(g.num_landmarks, 2);  // 4 and 9
  EXPECT_EQ(m.num_landmarks, 0);
  EXPECT_EQ(m.moving_ids, g.moving_ids);
  EXPECT_EQ(m.moving_ids, std::vector<std::int32_t>{6});
  EXPECT_EQ(m.moving_frames, g.moving_frames);
  EXPECT_EQ(m.moving_by, g.moving_by);
  EXPECT_EQ(m.moving_by, std::vector<std::int16_t>{1});
  EXPECT_EQ(m.frame, g.frame);
  EXPECT_EQ(m.version, g.version);
  EXPECT_EQ(m.incarnation, g.incarnation);
  EXPECT_EQ(m.utime, g.utime);
  EXPECT_EQ(m.chunk, 0);
  EXPECT_EQ(m.num_chunks, 1);
  EXPECT_EQ(m.id_begin, 0);
  EXPECT_EQ(m.id_end, node.map().max_landmark_id());
  EXPECT_EQ(node.counters().maps_published, 1);  // a moving set is not another map
  EXPECT_EQ(node.counters().map_chunks, 1);
  // Frame 1: the same lists, within the repeat period: the map alone.
  robots.publish(channels::pose(1), pose(1, 1));
  bus.dispatch_all();
  EXPECT_EQ(maps.size(), 2u);
  EXPECT_EQ(moving.size(), 1u);
  // Frame 2: landmark 9 found moving too: the new lists go out with its map.
  robots.publish(channels::lmap_event(), event(1, 11, 2, landmark_event_t::MOVING, 9));
  robots.publish(channels::pose(1), pose(1, 2));
  bus.dispatch_all();
  ASSERT_EQ(moving.size(), 2u);
  EXPECT_EQ(moving[1].moving_ids, (std::vector<std::int32_t>{6, 9}));
  EXPECT_EQ(moving[1].frame, 2);
  EXPECT_EQ(node.counters().moving_sets, 2);
}

// main_robot's timer sends GLOBAL_MAP only when no map went out in its period: a
// finished frame's map makes the next tick quiet (no second map per frame); with
// nothing sent for a period, or never, the tick sends one.
TEST_F(MainOnBus, TheTimersMapGoesOutOnlyWhenNoFramesMapDid) {
  constexpr std::int64_t kHour = 3'600'000'000;
  ports.publish_map_if_quiet(kHour);  // nothing went out yet: the tick sends the map
  bus.dispatch_all();
  obs.shell().publish(channels::pose(1), pose(1, 0));  // frame 0 finished: its map
  bus.dispatch_all();
  ports.publish_map_if_quiet(kHour);  // within the period of that map: quiet
  bus.dispatch_all();
  ports.publish_map_if_quiet(0);  // a period of nothing: the tick sends one
  bus.dispatch_all();
  const std::vector<std::string> expected = {"GLOBAL_MAP -1", "POSE_1 0", "GLOBAL_MAP 0", "GLOBAL_MAP 0"};
  EXPECT_EQ(obs.seen, expected);
}

TEST(Ports, TheChannelSuffixIsInEveryName) {
  InProcessTransport bus;
  NodeShell main_shell(bus, ShellOptions("main_robot", "_T", nullptr));
  MainNode main{GlobalMapOptions{}};
  MainPorts<NodeShell> main_ports(main_shell, main);
  main_ports.open();
  NodeShell robot_shell(bus, ShellOptions("robot_node 1", "_T", nullptr));
  RobotNode robot(load_robot_options(kConfig), 1);
  RobotPorts<NodeShell> robot_ports(robot_shell, robot);
  robot_ports.open();
  Observer plain(bus, ""), suffixed(bus, "_T");
  const auto frames = robot1_frames(2);
  plain.shell().publish(channels::sensor(1), frames[0]);  // not this team's
  bus.dispatch_all();
  EXPECT_EQ(robot.counters().frames, 0);
  plain.shell().publish(channels::sensor(1, "_T"), frames[0]);
  bus.dispatch_all();
  robot_ports.publish_status();
  main_ports.publish_status();
  bus.dispatch_all();
  EXPECT_EQ(robot.counters().frames, 1);
  EXPECT_TRUE(plain.seen.empty());
  ASSERT_FALSE(suffixed.seen.empty());
  EXPECT_EQ(suffixed.seen.back(), "GLOBAL_MAP_T 0");  // after POSE_1_T 0
  EXPECT_EQ(bus.dropped(), 4) << "SENSOR_1, CANDIDATES_1_T (the viewer's) and both STATUS had no subscriber here";
}

TEST(Lockstep, WaitsForEveryRobotsPoseAndRefusesAnotherRobots) {
  InProcessTransport bus;
  std::atomic<bool> stop{false};
  ShellOptions o("simulator", "", nullptr);
  o.stop = &stop;
  NodeShell shell(bus, o);
  sim::LockstepWaiter waiter(shell, {1, 2});
  NodeShell robots(bus, ShellOptions("robots", "", nullptr));
  robots.publish(channels::pose(1), pose(1, 0));
  EXPECT_FALSE(waiter.wait(0, 5)) << "robot 2 has not answered";
  robots.publish(channels::pose(2), pose(1, 0));  // robot 1's pose on POSE_2
  EXPECT_FALSE(waiter.wait(0, 5));
  EXPECT_EQ(waiter.rejected(), 1);
  robots.publish(channels::pose(2), pose(2, 3));
  EXPECT_TRUE(waiter.wait(0, 1000));
  stop = true;
  EXPECT_FALSE(waiter.wait(1, 100000)) << "a stop ends the wait";
}

TEST(Lockstep, WaitForNodesCountsDistinctStatusChannels) {
  InProcessTransport bus;
  NodeShell shell(bus, ShellOptions("simulator", "", nullptr));
  NodeShell nodes(bus, ShellOptions("nodes", "", nullptr));
  node_status_t s{};
  // Published before the wait subscribes: dropped (no subscriber yet), as on LCM.
  nodes.publish(channels::status_main(), s);
  EXPECT_FALSE(sim::wait_for_nodes(shell, 1, 5));
  // A node announcing itself from inside the wait: the transport's first message
  // subscribes a helper that publishes (in one thread, a handler is the only way).
  int calls = 0;
  nodes.subscribe<node_status_t>("STATUS_SIM", [&](const node_status_t&, const std::string&) {
    ++calls;
    nodes.publish(channels::status_robot(1), s);
    nodes.publish(channels::status_robot(1), s);
    nodes.publish(channels::status_main(), s);
  }, transport::kUnboundedQueue);
  nodes.publish(channels::status_sim(), s);
  EXPECT_TRUE(sim::wait_for_nodes(shell, 2, 1000));
  EXPECT_EQ(calls, 1);
}

}  // namespace
}  // namespace elaslam

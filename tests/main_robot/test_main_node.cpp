// SPDX-License-Identifier: Apache-2.0
// MainNode on its own (main_node.hpp): when a team's frame is finished (every robot
// seen has sent its POSE and the events up to that POSE's event_seq, and its snapshot
// when it announced one), what GLOBAL_MAP and GLOBAL_MOVING then carry, when
// MainPorts publishes them (on a fake shell whose clock the test sets), and the
// counters. Every expectation is worked out by hand from the messages sent.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "../support/messages.hpp"
#include "elaslam/main_robot/main_ports.hpp"
#include "team_options.hpp"

namespace elaslam {
namespace {

using test::team_of_three;

// Robot `robot`'s POSE of `frame`, announcing its events up to `event_seq` and a
// snapshot of `snapshot_chunks` chunks.
pose_estimate_t pose(int robot, int frame, std::int64_t event_seq, int snapshot_chunks = 0) {
  pose_estimate_t p = test::pose_msg(robot, frame);
  p.event_seq = event_seq;
  p.snapshot_chunks = static_cast<std::int16_t>(snapshot_chunks);
  return p;
}

landmark_event_t add(int robot, std::int64_t seq, int id, int frame, double x, double y, double var) {
  return test::event_msg(robot, seq, landmark_event_t::ADD, id, frame, x, y, var);
}

// Chunk `chunk` of `num_chunks` of robot `robot`'s snapshot of `frame`: ids
// [16 * chunk, 16 * chunk + 16), landmark `id` in it when given.
lmap_snapshot_t snapshot_chunk(int robot, std::int64_t seq, int frame, int chunk, int num_chunks, int id = -1) {
  lmap_snapshot_t s{};
  s.robot_id = static_cast<std::int16_t>(robot);
  s.seq = seq;
  s.frame = frame;
  s.chunk = static_cast<std::int16_t>(chunk);
  s.num_chunks = static_cast<std::int16_t>(num_chunks);
  s.id_begin = 16 * chunk;
  s.id_end = 16 * chunk + 16;
  if (id >= 0) {
    landmark_estimate_t l{};
    l.id = id;
    l.x = 1.0;
    l.y = 2.0;
    l.cov[0][0] = l.cov[1][1] = 0.01;
    s.landmarks.push_back(l);
    s.num_landmarks = 1;
  }
  return s;
}

// GIVEN robots 1, 2 and 3, each announcing in its POSE how many events follow
// WHEN their POSEs and events of frame 0 arrive interleaved
// THEN frame 0 is finished at the very event that completes the last announcement,
// and not before: a robot whose POSE is held holds every map back.
TEST(MainNodeFrames, AFrameIsFinishedWhenEveryRobotsPoseAndAnnouncedEventsAreIn) {
  MainNode node(team_of_three());
  EXPECT_EQ(node.on_pose(pose(1, 0, 2)), -1) << "robot 1 announces events 1 and 2: held";
  EXPECT_EQ(node.on_pose(pose(2, 0, 0)), -1) << "robot 2 has no events, but robot 1 is held";
  EXPECT_EQ(node.on_pose(pose(3, 0, 1)), -1) << "robot 3 announces event 1: held";
  ASSERT_TRUE(node.on_event(add(1, 1, 3, 0, 1.0, 2.0, 0.01)));
  EXPECT_EQ(node.take_finished(), -1) << "robot 1 still waits for its event 2";
  ASSERT_TRUE(node.on_event(add(3, 1, 5, 0, -1.0, 0.5, 0.04)));
  EXPECT_EQ(node.take_finished(), -1) << "robot 3 is in, robot 1 is not";
  ASSERT_TRUE(node.on_event(add(1, 2, 4, 0, 3.0, -2.0, 0.01)));
  EXPECT_EQ(node.take_finished(), 0) << "robot 1's event 2 completes frame 0";
  EXPECT_EQ(node.take_finished(), -1) << "taken once";

  // Frame 1 without events: finished by the last of the three POSEs, at once.
  EXPECT_EQ(node.on_pose(pose(2, 1, 0)), -1);
  EXPECT_EQ(node.on_pose(pose(1, 1, 2)), -1) << "events up to 2 are in: robot 1 done, robot 3 not";
  EXPECT_EQ(node.on_pose(pose(3, 1, 1)), 1);
  EXPECT_EQ(node.take_finished(), -1) << "on_pose returned it; nothing held finished since";

  const MainCounters& c = node.counters();
  EXPECT_EQ(c.events, 3);
  EXPECT_EQ(c.gaps, 0);
  EXPECT_EQ(c.stale_poses, 0);
  EXPECT_EQ(c.rejected_inputs, 0);
  EXPECT_EQ(c.maps_published, 0) << "finishing a frame makes no map by itself";
}

// GIVEN robots 1 and 2 at frame 4, robot 1's next POSE (frame 5) announcing a
// two-chunk snapshot  THEN frame 5 waits for the snapshot's last chunk, not its
// first; a snapshot that comes in before its POSE counts when the POSE comes.
TEST(MainNodeFrames, AnAnnouncedSnapshotHoldsTheFrameUntilItsLastChunk) {
  MainNode node(team_of_three());
  ASSERT_TRUE(node.on_event(add(1, 1, 3, 4, 1.0, 2.0, 0.01)));
  EXPECT_EQ(node.on_pose(pose(1, 4, 1)), 4);
  EXPECT_EQ(node.on_pose(pose(2, 4, 0)), -1) << "frame 4 was finished already";
  EXPECT_EQ(node.on_pose(pose(2, 5, 0)), -1) << "robot 1 has not finished frame 5";
  EXPECT_EQ(node.on_pose(pose(1, 5, 1, 2)), -1) << "its events are in, its snapshot is not";
  ASSERT_TRUE(node.on_snapshot(snapshot_chunk(1, 1, 5, 0, 2, 3)));
  EXPECT_EQ(node.take_finished(), -1) << "chunk 0 of 2";
  ASSERT_TRUE(node.on_snapshot(snapshot_chunk(1, 1, 5, 1, 2)));
  EXPECT_EQ(node.take_finished(), 5) << "the last chunk finishes frame 5";

  // Frame 6: robot 1's snapshot before its POSE.
  EXPECT_EQ(node.on_pose(pose(2, 6, 0)), -1);
  ASSERT_TRUE(node.on_snapshot(snapshot_chunk(1, 1, 6, 0, 1, 3)));
  EXPECT_EQ(node.take_finished(), -1) << "no POSE of frame 6 from robot 1 yet";
  EXPECT_EQ(node.on_pose(pose(1, 6, 1, 1)), 6) << "the snapshot it announces is in already";
  EXPECT_EQ(node.counters().snapshots, 3);
}

// GIVEN robot 1 alone, its POSE of frame 1 announcing events 1 and 2 that never come
// WHEN its POSE of frame 2 arrives  THEN frame 1 is let go (finished, late events
// counted as a gap, a resync asked for after event 0), frame 2 is held for them in
// its turn; a POSE of a frame already held or finished is ignored and counted.
TEST(MainNodeFrames, AHeldPoseIsLetGoAtTheNextPoseAndItsLostEventsAreAGap) {
  MainNode node(team_of_three());
  EXPECT_EQ(node.on_pose(pose(1, 0, 0)), 0) << "the only robot seen, nothing announced";
  EXPECT_EQ(node.on_pose(pose(1, 1, 2)), -1) << "held for events 1 and 2";
  EXPECT_EQ(node.on_pose(pose(1, 2, 2)), 1) << "frame 1 let go";
  EXPECT_EQ(node.counters().gaps, 1);
  const auto& resyncs = node.take_resyncs(1000);
  ASSERT_EQ(resyncs.size(), 1u);
  EXPECT_EQ(resyncs[0].robot_id, 1);
  EXPECT_EQ(resyncs[0].after_seq, 0);
  EXPECT_EQ(resyncs[0].reason, resync_request_t::GAP);
  EXPECT_EQ(node.counters().resyncs_requested, 1);

  EXPECT_EQ(node.on_pose(pose(1, 1, 2)), -1) << "a late POSE of frame 1";
  EXPECT_EQ(node.on_pose(pose(1, 2, 2)), -1) << "frame 2's POSE again";
  EXPECT_EQ(node.counters().stale_poses, 2);
  ASSERT_TRUE(node.on_event(add(1, 1, 7, 1, 0.0, 0.0, 0.01)));
  ASSERT_TRUE(node.on_event(add(1, 2, 8, 1, 0.0, 1.0, 0.01)));
  EXPECT_EQ(node.take_finished(), 2) << "the late events still come: frame 2 is finished";
  EXPECT_EQ(node.counters().events, 2);
}

// GIVEN frame 0 finished with landmark 3 from robots 1 and 2 and landmark 9 from
// robot 3, then robot 3's MOVING of 9 in frame 1  THEN GLOBAL_MAP of frame 1 carries
// 3 at the information-weighted mean of the two estimates, with both robots as
// contributors, and 9 in its moving lists (found in frame 1 by robot 3).
TEST(MainNodeMaps, TheGlobalMapCarriesTheFusedStaticLandmarksAndTheMovingSet) {
  MainNode node(team_of_three());
  node.set_incarnation(77);
  ASSERT_TRUE(node.on_event(add(1, 1, 3, 0, 1.0, 2.0, 0.01)));   // information 100 per axis
  ASSERT_TRUE(node.on_event(add(2, 1, 3, 0, 1.3, 2.0, 0.02)));   // information 50
  ASSERT_TRUE(node.on_event(add(3, 1, 9, 0, 5.0, 5.0, 0.01)));
  EXPECT_EQ(node.on_pose(pose(1, 0, 1)), 0);
  EXPECT_EQ(node.on_pose(pose(2, 0, 1)), -1);
  EXPECT_EQ(node.on_pose(pose(3, 0, 1)), -1);
  ASSERT_TRUE(node.on_event(test::event_msg(3, 2, landmark_event_t::MOVING, 9, 1)));
  const auto& notices = node.take_notices(5000);
  ASSERT_EQ(notices.size(), 1u);
  EXPECT_EQ(notices[0].landmark_id, 9);
  EXPECT_EQ(notices[0].detected_by, 3);
  EXPECT_EQ(notices[0].frame, 1);
  EXPECT_EQ(notices[0].seq, 1);
  EXPECT_EQ(notices[0].incarnation, 77);
  for (int r = 1; r <= 3; ++r) EXPECT_EQ(node.on_pose(pose(r, 1, r == 3 ? 2 : 1)), r == 3 ? 1 : -1) << r;

  const std::int64_t now = 123456789;
  ASSERT_EQ(node.make_global_map(now, 1), 1) << "two entries fit one chunk";
  const global_map_t& m = node.map_chunk(0);
  EXPECT_EQ(m.frame, 1);
  EXPECT_EQ(m.utime, now);
  EXPECT_EQ(m.incarnation, 77);
  EXPECT_EQ(m.chunk, 0);
  EXPECT_EQ(m.num_chunks, 1);
  EXPECT_EQ(m.id_begin, 0);
  EXPECT_EQ(m.id_end, 32);
  ASSERT_EQ(m.num_landmarks, 1);
  const global_landmark_t& l = m.landmarks[0];
  EXPECT_EQ(l.id, 3);
  EXPECT_NEAR(l.x, (100 * 1.0 + 50 * 1.3) / 150, 1e-12);  // 1.1
  EXPECT_NEAR(l.y, 2.0, 1e-12);
  EXPECT_NEAR(l.cov[0][0], 1.0 / 150, 1e-15);
  EXPECT_NEAR(l.cov[1][1], 1.0 / 150, 1e-15);
  EXPECT_NEAR(l.cov[0][1], 0.0, 1e-15);
  EXPECT_EQ(l.contributors, 0b011) << "robots 1 and 2";
  EXPECT_EQ(l.status, global_landmark_t::STATIC);
  EXPECT_EQ(l.status_frame, 0);
  ASSERT_EQ(m.num_moving, 1);
  EXPECT_EQ(m.moving_ids[0], 9);
  EXPECT_EQ(m.moving_frames[0], 1);
  EXPECT_EQ(m.moving_by[0], 3);

  // Without a frame, the map is stamped with the newest frame the team finished.
  ASSERT_EQ(node.make_global_map(now + 1), 1);
  EXPECT_EQ(node.map_chunk(0).frame, 1);
  // GLOBAL_MOVING: the moving lists alone.
  ASSERT_EQ(node.make_moving_set(now + 2, 1), 1);
  EXPECT_EQ(node.map_chunk(0).num_landmarks, 0);
  ASSERT_EQ(node.map_chunk(0).num_moving, 1);
  EXPECT_EQ(node.map_chunk(0).moving_ids[0], 9);
  EXPECT_EQ(node.counters().maps_published, 2) << "make_moving_set is not a GLOBAL_MAP";
  EXPECT_EQ(node.counters().map_chunks, 2);
  EXPECT_EQ(node.counters().notices_sent, 1);
  EXPECT_EQ(node.counters().events, 4);
}

// A shell for MainPorts without a transport: it keeps the subscribed handlers to
// deliver messages by hand, records every publication as "CHANNEL frame", and its
// clock is whatever the test sets.
class FakeShell {
 public:
  const std::string& suffix() const { return suffix_; }
  std::int64_t now_utime() const { return now; }
  template <class Msg, class Handler>
  int subscribe(const std::string& channel, Handler handle, int /*queue*/) {
    if constexpr (std::is_same_v<Msg, pose_estimate_t>) on_pose = handle;
    if constexpr (std::is_same_v<Msg, landmark_event_t>) on_event = handle;
    if constexpr (std::is_same_v<Msg, lmap_events_t>) on_events = handle;
    if constexpr (std::is_same_v<Msg, lmap_snapshot_t>) on_snapshot = handle;
    if constexpr (std::is_same_v<Msg, track_list_t>) on_tracks = handle;
    channels.push_back(channel);
    return 1;
  }
  template <class Msg>
  void publish(const std::string& channel, const Msg& m) {
    seen.push_back(channel + " " + std::to_string(m.frame));
    if constexpr (std::is_same_v<Msg, global_tracks_t>) {
      last_tracks = m;
      tracks_out.push_back(m);
    }
  }
  void publish(const std::string& channel, const resync_request_t& m) {  // (no frame: the robot asked)
    seen.push_back(channel + " robot " + std::to_string(m.robot_id));
  }
  void stamp_auth(node_status_t*) {}
  void refuse(const std::string& why) { refused.push_back(why); }
  void say(const std::string& what, log::Priority) { said.push_back(what); }
  void on_decode_error(std::function<void()>) {}

  std::int64_t now = 1'000'000'000;
  std::vector<std::string> seen, refused, said, channels;
  std::function<void(const pose_estimate_t&, const std::string&)> on_pose;
  std::function<void(const landmark_event_t&, const std::string&)> on_event;
  std::function<void(const lmap_events_t&, const std::string&)> on_events;
  std::function<void(const lmap_snapshot_t&, const std::string&)> on_snapshot;
  std::function<void(const track_list_t&, const std::string&)> on_tracks;
  global_tracks_t last_tracks{};  // the last GLOBAL_TRACKS chunk published
  std::vector<global_tracks_t> tracks_out;  // every GLOBAL_TRACKS chunk published

 private:
  std::string suffix_;
};

// GIVEN robot 1 alone, GLOBAL_MOVING repeated at most once a second
// THEN GLOBAL_MAP of a frame goes out at the message that finishes the frame (the
// POSE, or the event a held POSE waited for), followed by GLOBAL_MOVING when its lists
// changed or the last went out a second ago or more; a notice goes out at once,
// before the map; the timer adds a map only after a quiet period.
TEST(MainNodePorts, TheMapOfAFrameGoesOutWhenTheFrameIsFinished) {
  GlobalMapOptions o = team_of_three();
  o.moving_repeat_s = 1.0;
  MainNode node(o);
  FakeShell shell;
  MainPorts<FakeShell> ports(shell, node);
  ASSERT_TRUE(ports.open());
  const std::vector<std::string> inputs = {"LMAP_EVENT", "LMAP_EVENTS", "LMAP_SNAPSHOT", channels::any_pose(),
                                           channels::any_tracks()};
  EXPECT_EQ(shell.channels, inputs);
  constexpr std::int64_t ms = 1000;
  const std::int64_t t0 = shell.now;
  auto at = [&](std::int64_t t) { shell.now = t0 + t; };
  auto sent = [&] {
    std::vector<std::string> s;
    s.swap(shell.seen);
    return s;
  };
  using V = std::vector<std::string>;

  shell.on_pose(pose(1, 0, 1), "POSE_1");
  EXPECT_EQ(sent(), V{}) << "held for event 1";
  shell.on_event(add(1, 1, 3, 0, 1.0, 2.0, 0.01), "LMAP_EVENT");
  EXPECT_EQ(sent(), (V{"GLOBAL_MAP 0", "GLOBAL_MOVING 0"})) << "the first moving set is always due";

  at(100 * ms);
  shell.on_pose(pose(1, 1, 1), "POSE_1");
  EXPECT_EQ(sent(), V{"GLOBAL_MAP 1"}) << "nothing announced: finished by the POSE; moving set unchanged";

  at(200 * ms);
  shell.on_pose(pose(1, 2, 2), "POSE_1");
  EXPECT_EQ(sent(), V{});
  shell.on_event(test::event_msg(1, 2, landmark_event_t::MOVING, 3, 2), "LMAP_EVENT");
  EXPECT_EQ(sent(), (V{"DYNAMIC_NOTICE 2", "GLOBAL_MAP 2", "GLOBAL_MOVING 2"})) << "3 moving: the lists changed";

  at(1100 * ms);
  shell.on_pose(pose(1, 3, 2), "POSE_1");
  EXPECT_EQ(sent(), V{"GLOBAL_MAP 3"}) << "0.9 s since the last moving set";
  at(1200 * ms);
  shell.on_pose(pose(1, 4, 2), "POSE_1");
  EXPECT_EQ(sent(), (V{"GLOBAL_MAP 4", "GLOBAL_MOVING 4"})) << "1.0 s since the last: repeated";

  const std::int64_t period = 100 * ms;  // main.publish_rate_hz 10
  at(1250 * ms);
  ports.publish_map_if_quiet(period);
  EXPECT_EQ(sent(), V{}) << "a map went out 50 ms ago";
  at(1300 * ms);
  ports.publish_map_if_quiet(period);
  EXPECT_EQ(sent(), V{"GLOBAL_MAP 4"}) << "a quiet period: the timer's map, of the newest finished frame";

  shell.on_pose(pose(1, 4, 2), "POSE_1");
  EXPECT_EQ(sent(), V{}) << "a repeated POSE finishes nothing";
  EXPECT_TRUE(shell.refused.empty());
  const MainCounters& c = node.counters();
  EXPECT_EQ(c.maps_published, 6);
  EXPECT_EQ(c.map_chunks, 6);
  EXPECT_EQ(c.moving_sets, 3);
  EXPECT_EQ(c.notices_sent, 1);
  EXPECT_EQ(c.stale_poses, 1);
}

// GIVEN robots 1 and 2 tracking landmark 7 (and robot 2 also landmark 9)
// WHEN their TRACKS of frame 0 arrive (after their POSEs of frame 0: the map of
// frame 0 went out already) and then their POSEs of frame 1
// THEN GLOBAL_TRACKS goes out right after the GLOBAL_MAP of frame 1, with landmark 7
// fused from both (contributors 1 and 2, between the two estimates) and 9 from
// robot 2 alone; when the robots' tracks end, one empty GLOBAL_TRACKS follows, then
// none.
TEST(MainNodePorts, FusedTracksGoOutWithEveryGlobalMap) {
  MainNode node(team_of_three());
  FakeShell shell;
  MainPorts<FakeShell> ports(shell, node);
  ASSERT_TRUE(ports.open());
  auto sent = [&] {
    std::vector<std::string> s;
    s.swap(shell.seen);
    return s;
  };
  // The publication after `map` in `out`, "" when none.
  auto after = [](const std::vector<std::string>& out, const std::string& map) {
    for (std::size_t i = 0; i + 1 < out.size(); ++i)
      if (out[i] == map) return out[i + 1];
    return std::string();
  };
  auto has = [](const std::vector<std::string>& out, const std::string& what) {
    return std::find(out.begin(), out.end(), what) != out.end();
  };
  shell.on_pose(pose(1, 0, 0), "POSE_1");
  shell.on_pose(pose(2, 0, 0), "POSE_2");
  std::vector<std::string> out = sent();
  EXPECT_TRUE(has(out, "GLOBAL_MAP 0"));
  EXPECT_FALSE(has(out, "GLOBAL_TRACKS 0")) << "no tracks yet";
  shell.on_tracks(test::tracks_msg(1, 0, {test::track_of(7, 1.0, 2.0, 0.5, 0.0)}), "TRACKS_1");
  shell.on_tracks(test::tracks_msg(2, 0, {test::track_of(9, -3.0, 0.0, 0.0, 0.2, 0.02, 0.01, {0.8f, 0.1f, 0.1f}),
                                          test::track_of(7, 1.2, 2.0, 0.3, 0.0, 0.04, 0.01)}),
                  "TRACKS_2");
  EXPECT_TRUE(sent().empty()) << "tracks go out with the next map";
  shell.on_pose(pose(1, 1, 0), "POSE_1");
  shell.on_pose(pose(2, 1, 0), "POSE_2");
  out = sent();
  EXPECT_EQ(after(out, "GLOBAL_MAP 1"), "GLOBAL_TRACKS 1");
  const global_tracks_t& g = shell.last_tracks;
  ASSERT_EQ(g.num_tracks, 2);
  EXPECT_EQ(g.num_omitted, 0);
  const global_track_t& a = g.tracks[0];
  EXPECT_EQ(a.id, 7);
  EXPECT_EQ(a.contributors, 0b11);
  EXPECT_GT(a.x, 1.0);  // between the two, nearer robot 1's (smaller position variance)
  EXPECT_LT(a.x, 1.1);
  EXPECT_GT(a.vx, 0.3);
  EXPECT_LT(a.vx, 0.5);
  // Robot 1's position and robot 2's velocity are the surer (0.01 against 0.04): the
  // fusion (w = 1/2 by symmetry) has variances 1/62.5 = 0.016, trace 0.064, below
  // either alone's 0.1; x = 0.016 (50 * 1.0 + 12.5 * 1.2) = 1.04.
  EXPECT_NEAR(a.x, 1.04, 1e-6);
  EXPECT_NEAR(a.cov[0] + a.cov[4] + a.cov[7] + a.cov[9], 0.064, 1e-6);
  EXPECT_EQ(a.likeliest, track_t::CONSTANT_VELOCITY);
  const global_track_t& b = g.tracks[1];
  EXPECT_EQ(b.id, 9);
  EXPECT_EQ(b.contributors, 0b10);
  EXPECT_EQ(b.x, -3.0);
  EXPECT_EQ(b.likeliest, track_t::STATIC);
  EXPECT_EQ(b.stopped, 1);
  // The tracks end: one empty GLOBAL_TRACKS, then none.
  shell.on_tracks(test::tracks_msg(1, 1, {}), "TRACKS_1");
  shell.on_tracks(test::tracks_msg(2, 1, {}), "TRACKS_2");
  shell.on_pose(pose(1, 2, 0), "POSE_1");
  shell.on_pose(pose(2, 2, 0), "POSE_2");
  out = sent();
  EXPECT_EQ(after(out, "GLOBAL_MAP 2"), "GLOBAL_TRACKS 2");
  EXPECT_EQ(shell.last_tracks.num_tracks, 0);
  shell.on_pose(pose(1, 3, 0), "POSE_1");
  shell.on_pose(pose(2, 3, 0), "POSE_2");
  out = sent();
  EXPECT_TRUE(has(out, "GLOBAL_MAP 3"));
  EXPECT_FALSE(has(out, "GLOBAL_TRACKS 3"));
  EXPECT_TRUE(shell.refused.empty());
  EXPECT_EQ(node.counters().tracks, 4);
  EXPECT_EQ(node.counters().global_tracks_published, 2);
}

// GIVEN robot 1 tracking 15 landmarks (its TRACKS in two chunks: 12 and 3) and robot
// 2 tracking 5 others, 20 fused tracks in all, more than one GLOBAL_TRACKS chunk
// holds
// WHEN the next map goes out
// THEN GLOBAL_TRACKS follows it in two chunks of that frame (12 and 8, ascending ids
// across them, chunk 0 and 1 of 2), none omitted.
TEST(MainNodePorts, MoreFusedTracksThanOneChunkHoldsGoOutInChunks) {
  MainNode node(team_of_three());
  FakeShell shell;
  MainPorts<FakeShell> ports(shell, node);
  ASSERT_TRUE(ports.open());
  shell.on_pose(pose(1, 0, 0), "POSE_1");
  shell.on_pose(pose(2, 0, 0), "POSE_2");
  std::vector<track_t> first, second, other;
  for (int id = 0; id < 12; ++id) first.push_back(test::track_of(id, id, 0.0, 0.5, 0.0));
  for (int id = 12; id < 15; ++id) second.push_back(test::track_of(id, id, 0.0, 0.5, 0.0));
  for (int id = 20; id < 25; ++id) other.push_back(test::track_of(id, id, 1.0, 0.0, 0.5));
  shell.on_tracks(test::tracks_msg(1, 0, first, 0, 2), "TRACKS_1");
  shell.on_tracks(test::tracks_msg(1, 0, second, 1, 2), "TRACKS_1");
  shell.on_tracks(test::tracks_msg(2, 0, other), "TRACKS_2");
  shell.seen.clear();
  shell.on_pose(pose(1, 1, 0), "POSE_1");
  shell.on_pose(pose(2, 1, 0), "POSE_2");
  const std::vector<std::string> out = shell.seen;
  const auto map = std::find(out.begin(), out.end(), "GLOBAL_MAP 1");
  ASSERT_NE(map, out.end());
  ASSERT_GE(out.end() - map, 3);
  EXPECT_EQ(map[1], "GLOBAL_TRACKS 1");
  EXPECT_EQ(map[2], "GLOBAL_TRACKS 1");
  ASSERT_EQ(shell.tracks_out.size(), 2u);
  std::vector<int> ids;
  for (int c = 0; c < 2; ++c) {
    const global_tracks_t& g = shell.tracks_out[static_cast<std::size_t>(c)];
    EXPECT_EQ(g.chunk, c);
    EXPECT_EQ(g.num_chunks, 2);
    EXPECT_EQ(g.num_omitted, 0);
    EXPECT_EQ(g.frame, 1);
    for (int k = 0; k < g.num_tracks; ++k) ids.push_back(g.tracks[static_cast<std::size_t>(k)].id);
  }
  EXPECT_EQ(shell.tracks_out[0].num_tracks, 12);
  EXPECT_EQ(shell.tracks_out[1].num_tracks, 8);
  std::vector<int> want;
  for (int id = 0; id < 15; ++id) want.push_back(id);
  for (int id = 20; id < 25; ++id) want.push_back(id);
  EXPECT_EQ(ids, want);
  EXPECT_TRUE(shell.refused.empty());
  EXPECT_EQ(node.counters().tracks, 3);
  EXPECT_EQ(node.counters().global_tracks_published, 1);
  EXPECT_EQ(node.counters().global_tracks_omitted, 0);
}

}  // namespace
}  // namespace elaslam

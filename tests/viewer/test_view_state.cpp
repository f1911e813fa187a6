// SPDX-License-Identifier: Apache-2.0
// ViewState: what the viewer draws, from the bus's messages; bad ones change nothing.
#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <map>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "../support/messages.hpp"
#include "elaslam/viewer/view_state.hpp"

namespace elaslam::viewer {
namespace {

pose_estimate_t pose(int robot, int frame, double x, double y) {
  pose_estimate_t p{};
  p.robot_id = static_cast<std::int16_t>(robot);
  p.frame = frame;
  p.x = x, p.y = y, p.theta = 0.5;
  p.cov[0][0] = p.cov[1][1] = 0.01;
  return p;
}

global_landmark_t landmark(int id, double x, double y, std::int8_t status = global_landmark_t::STATIC) {
  global_landmark_t l{};
  l.id = id, l.x = x, l.y = y;
  l.cov[0][0] = l.cov[1][1] = 0.001;
  l.contributors = 0b101;
  l.status = status;
  return l;
}

global_map_t chunk(int id_begin, int id_end, std::vector<global_landmark_t> lms, std::vector<int> moving = {}) {
  global_map_t m{};
  m.frame = 10, m.version = 1, m.chunk = 0, m.num_chunks = 2;
  m.id_begin = id_begin, m.id_end = id_end;
  m.landmarks = std::move(lms);
  m.num_landmarks = static_cast<std::int16_t>(m.landmarks.size());
  for (int id : moving) {
    m.moving_ids.push_back(id);
    m.moving_frames.push_back(9);
    m.moving_by.push_back(1);
  }
  m.num_moving = static_cast<std::int16_t>(moving.size());
  return m;
}

nlohmann::json state(const ViewState& v) { return nlohmann::json::parse(v.to_json(0.0)); }
// What is drawn, without the viewer's own counters.
nlohmann::json drawn(const ViewState& v) {
  nlohmann::json j = state(v);
  j.erase("viewer");
  return j;
}

TEST(ViewState, PosesMakeRobotsWithTrails) {
  ViewState v;
  ASSERT_TRUE(v.on_pose(pose(2, 0, 1.0, 2.0)));
  ASSERT_TRUE(v.on_pose(pose(2, 1, 1.5, 2.5)));
  ASSERT_TRUE(v.on_pose(pose(1, 1, -1.0, 0.0)));
  const auto j = state(v);
  EXPECT_EQ(j["frame"], 1);
  ASSERT_EQ(j["robots"].size(), 2u);
  EXPECT_EQ(j["robots"][0]["id"], 1);
  EXPECT_EQ(j["robots"][1]["id"], 2);
  EXPECT_DOUBLE_EQ(j["robots"][1]["x"], 1.5);
  EXPECT_EQ(j["robots"][1]["trail"].size(), 2u);
  EXPECT_TRUE(j["robots"][1]["health"].is_null());
  EXPECT_TRUE(j["robots"][1]["truth"].is_null());
}

TEST(ViewState, TrailsAreBoundedAndStartOverWhenARobotRestarts) {
  ViewLimits lim;
  lim.trail_points = 5;
  ViewState v(lim);
  for (int f = 0; f < 20; ++f) ASSERT_TRUE(v.on_pose(pose(1, f, f * 0.1, 0.0)));
  EXPECT_EQ(state(v)["robots"][0]["trail"].size(), 5u);
  EXPECT_DOUBLE_EQ(state(v)["robots"][0]["trail"][4][0], 1.9);
  ASSERT_TRUE(v.on_pose(pose(1, 0, 0.0, 0.0)));  // restarted at frame 0
  EXPECT_EQ(state(v)["robots"][0]["trail"].size(), 1u);
}

TEST(ViewState, EachMapChunkReplacesItsIdRangeOnly) {
  ViewState v;
  ASSERT_TRUE(v.on_global_map(chunk(0, 10, {landmark(3, 1, 1), landmark(7, 2, 2)})));
  ASSERT_TRUE(v.on_global_map(chunk(10, 20, {landmark(12, 3, 3)})));
  EXPECT_EQ(state(v)["landmarks"].size(), 3u);
  // The next chunk of [0, 10) no longer has 7 and says 3 moves: 7 is gone, 3 drawn
  // moving where it was last mapped, 12 untouched.
  ASSERT_TRUE(v.on_global_map(chunk(0, 10, {}, {3})));
  const auto j = state(v);
  ASSERT_EQ(j["landmarks"].size(), 2u);
  EXPECT_EQ(j["landmarks"][0]["id"], 3);
  EXPECT_EQ(j["landmarks"][0]["status"], "moving");
  EXPECT_DOUBLE_EQ(j["landmarks"][0]["x"], 1.0);
  EXPECT_EQ(j["landmarks"][1]["id"], 12);
  EXPECT_EQ(j["landmarks"][1]["status"], "static");
  EXPECT_EQ(j["landmarks"][1]["contributors"], nlohmann::json({1, 3}));
}

TEST(ViewState, BadMessagesAreCountedAndChangeNothing) {
  ViewState v;
  ASSERT_TRUE(v.on_pose(pose(1, 3, 1.0, 1.0)));
  ASSERT_TRUE(v.on_global_map(chunk(0, 10, {landmark(3, 1, 1)})));
  const nlohmann::json before = drawn(v);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(v.on_pose(pose(1, 4, nan, 1.0)));
  EXPECT_FALSE(v.on_pose(pose(0, 4, 1.0, 1.0)));          // no robot 0
  EXPECT_FALSE(v.on_pose(pose(1, 4, 1.0e9, 1.0)));        // beyond the world bound
  EXPECT_FALSE(v.on_global_map(chunk(0, 10, {landmark(11, 1, 1)})));  // id outside the chunk
  EXPECT_FALSE(v.on_global_map(chunk(0, 300, {})));       // beyond max_landmark_id
  global_map_t lying = chunk(0, 10, {landmark(3, 1, 1)});
  lying.num_landmarks = 5;                                // count does not match the array
  EXPECT_FALSE(v.on_global_map(lying));
  dynamic_notice_t n{};
  n.landmark_id = 999;
  EXPECT_FALSE(v.on_notice(n));
  EXPECT_EQ(v.bad_messages(), 7);
  EXPECT_EQ(drawn(v), before);
  EXPECT_EQ(state(v)["viewer"]["bad_by_reason"]["POSE not finite"], 1);
}

// A decoder that reuses its message (NodeShell) leaves entries beyond the counts:
// only the counted ones are read.
TEST(ViewState, OnlyTheCountedEntriesOfAChunkAreRead) {
  ViewState v;
  global_map_t m = chunk(0, 10, {landmark(3, 1, 1), landmark(50, 2, 2)}, {4, 60});
  m.num_landmarks = 1;
  m.num_moving = 0;
  ASSERT_TRUE(v.on_global_map(m));
  const auto j = state(v);
  ASSERT_EQ(j["landmarks"].size(), 1u);
  EXPECT_EQ(j["landmarks"][0]["id"], 3);
}

TEST(ViewState, NoticesAreListedOnceNewestLastAndBounded) {
  ViewLimits lim;
  lim.notices = 3;
  ViewState v(lim);
  for (int k = 0; k < 5; ++k) {
    dynamic_notice_t n{};
    n.frame = 10 + k, n.landmark_id = k, n.detected_by = 2;
    ASSERT_TRUE(v.on_notice(n));
    ASSERT_TRUE(v.on_notice(n));  // re-sent: listed once
  }
  const auto j = state(v);
  ASSERT_EQ(j["notices"].size(), 3u);
  EXPECT_EQ(j["notices"][2], nlohmann::json({{"frame", 14}, {"landmark", 4}, {"robot", 2}}));
}

TEST(ViewState, StatusGivesTheHealthRow) {
  ViewState v;
  node_status_t s{};
  s.node_kind = node_status_t::ROBOT, s.node_id = 3;
  s.frames = 120, s.frames_dropped = 2, s.queue_drops = 1;
  s.refused[node_status_t::REFUSED_STALE] = 4;
  s.auth_refused = 1;
  s.fault_flags = node_status_t::FAULT_INCONSISTENT;
  s.processing_us_p50 = 40, s.processing_us_p99 = 400;
  ASSERT_TRUE(v.on_status(s, 1.0));
  const auto h = nlohmann::json::parse(v.to_json(3.5))["robots"][0]["health"];
  EXPECT_EQ(h["frames"], 120);
  EXPECT_EQ(h["refused"], 5);
  EXPECT_EQ(h["faults"], nlohmann::json({"inconsistent"}));
  EXPECT_EQ(h["latency_p99_us"], 400);
  EXPECT_DOUBLE_EQ(h["status_age_s"], 2.5);
  s.node_kind = node_status_t::MAIN;  // main's status is not a robot's row
  EXPECT_FALSE(v.on_status(s, 1.0));
}

// fuzz_viewer's first finding: a forged STATUS whose refusal counters sum beyond
// 2^63 (signed overflow in the health row). Now the sum saturates, and a negative
// counter is refused.
TEST(ViewState, HugeOrNegativeStatusCountersAreHandled) {
  ViewState v;
  node_status_t s{};
  s.node_kind = node_status_t::ROBOT, s.node_id = 1;
  s.refused[0] = s.refused[1] = INT64_MAX;
  ASSERT_TRUE(v.on_status(s, 0.0));
  EXPECT_EQ(state(v)["robots"][0]["health"]["refused"], INT64_MAX);
  s.refused[2] = -1;
  EXPECT_FALSE(v.on_status(s, 0.0));
  EXPECT_EQ(state(v)["viewer"]["bad_by_reason"]["STATUS negative counter"], 1);
}

TEST(ViewState, GroundTruthOverlay) {
  ViewState v;
  ground_truth_t g{};
  g.frame = 5;
  g.num_robots = 1;
  g.robot_ids = {1};
  g.robots.resize(1);
  g.robots[0].x = 2.0;
  g.num_landmarks = 2;
  g.landmarks.resize(2);
  g.landmarks[0].id = 0, g.landmarks[0].x = 1.0;
  g.landmarks[1].id = 1, g.landmarks[1].moving = true;
  ASSERT_TRUE(v.on_truth(g));
  const auto j = state(v);
  EXPECT_DOUBLE_EQ(j["robots"][0]["truth"]["x"], 2.0);
  EXPECT_TRUE(j["robots"][0]["x"].is_null());  // no POSE yet
  ASSERT_EQ(j["truth_landmarks"].size(), 2u);
  EXPECT_EQ(j["truth_landmarks"][1]["moving"], true);
}

TEST(ViewState, TheHeaderFollowsAReplayThatStartsOver) {
  ViewState v;
  ground_truth_t g{};
  g.num_robots = 1;
  g.robot_ids = {1};
  g.robots.resize(1);
  for (int f : {0, 1, 2, 148, 149}) {
    g.frame = f;
    ASSERT_TRUE(v.on_truth(g));
  }
  EXPECT_EQ(v.frame(), 149);
  g.frame = 145;  // a late datagram is not a restart
  ASSERT_TRUE(v.on_truth(g));
  EXPECT_EQ(v.frame(), 149);
  g.frame = 0;  // the replay starts over
  ASSERT_TRUE(v.on_truth(g));
  EXPECT_EQ(v.frame(), 0);
  EXPECT_EQ(state(v)["robots"][0]["truth_trail"].size(), 1u);  // the old run's trail is gone
  g.frame = 1;
  ASSERT_TRUE(v.on_truth(g));
  EXPECT_EQ(v.frame(), 1);
  run_info_t ri{};
  ri.frames = 150;
  ri.frame = 140;
  ASSERT_TRUE(v.on_run_info(ri));
  EXPECT_EQ(v.frame(), 140);
  ri.frame = -1;  // a new run announced before its first frame: the header waits for it
  ASSERT_TRUE(v.on_run_info(ri));
  EXPECT_EQ(v.frame(), 140);
}

candidate_list_t candidates(int robot, int frame, std::vector<int> ids) {
  candidate_list_t m{};
  m.robot_id = static_cast<std::int16_t>(robot);
  m.frame = frame;
  for (int id : ids) {
    landmark_estimate_t l{};
    l.id = id, l.x = id, l.y = 1.0;
    l.cov[0][0] = l.cov[1][1] = 0.01;
    m.candidates.push_back(l);
  }
  m.num_candidates = static_cast<std::int16_t>(ids.size());
  return m;
}

std::map<int, std::string> statuses(const ViewState& v) {
  std::map<int, std::string> out;
  const nlohmann::json j = state(v);
  for (const auto& l : j["landmarks"]) out[l["id"].get<int>()] = l["status"].get<std::string>();
  return out;
}

TEST(ViewState, CandidatesAreDrawnUnlessTheMapHasThemStatic) {
  ViewState v;
  ASSERT_TRUE(v.on_global_map(chunk(0, 10, {landmark(3, 1, 1)}, {4})));
  ASSERT_TRUE(v.on_candidates(candidates(2, 10, {3, 4, 5})));
  // 3 is static in the map; 4 moved and is seen again: a candidate; 5 is new.
  EXPECT_EQ(statuses(v), (std::map<int, std::string>{{3, "static"}, {4, "candidate"}, {5, "candidate"}}));
  ASSERT_TRUE(v.on_candidates(candidates(2, 11, {})));  // robot 2's candidates are gone
  EXPECT_EQ(statuses(v), (std::map<int, std::string>{{3, "static"}}));
  ASSERT_TRUE(v.on_candidates(candidates(1, 11, {6})));
  for (int f = 12; f < 12 + ViewState::kCandidateFrames + 1; ++f) ASSERT_TRUE(v.on_pose(pose(2, f, 0, 0)));
  EXPECT_EQ(statuses(v).count(6), 0u);  // robot 1 went quiet: its list is stale
  EXPECT_FALSE(v.on_candidates(candidates(1, 40, {999})));
}

track_t track(int id, double x, double vx, std::int8_t model = track_t::CONSTANT_VELOCITY) {
  track_t t{};
  t.id = id, t.x = x, t.y = 1.0, t.vx = vx, t.vy = 0.0;
  t.cov[0] = t.cov[4] = 0.01f;  // xx, yy
  t.cov[7] = t.cov[9] = 0.04f;  // vxvx, vyvy
  t.probabilities[0] = 0.1f, t.probabilities[1] = 0.2f, t.probabilities[2] = 0.7f;
  t.likeliest = model;
  t.validated = 1;
  return t;
}

using test::tracks_msg;

global_tracks_t fused(int frame, std::vector<track_t> ts, std::int16_t contributors, int chunk = 0,
                      int num_chunks = 1) {
  global_tracks_t m{};
  m.frame = frame;
  m.chunk = static_cast<std::int16_t>(chunk);
  m.num_chunks = static_cast<std::int16_t>(num_chunks);
  for (const track_t& t : ts) {
    global_track_t g{};
    g.id = t.id, g.x = t.x, g.y = t.y, g.vx = t.vx, g.vy = t.vy, g.likeliest = t.likeliest;
    std::copy(std::begin(t.cov), std::end(t.cov), std::begin(g.cov));
    std::copy(std::begin(t.probabilities), std::end(t.probabilities), std::begin(g.probabilities));
    g.contributors = contributors;
    m.tracks.push_back(g);
  }
  m.num_tracks = static_cast<std::int16_t>(m.tracks.size());
  return m;
}

// A robot's tracks and main's fused ones are in the state as sent (position,
// velocity, model, the fused ones' contributors), the newest list replacing the
// last; a bad message of either kind is refused and changes nothing; a list more
// than kCandidateFrames frames old is not drawn.
TEST(ViewState, TracksAndFusedTracksAreKeptCheckedAndAged) {
  ViewState v;
  ASSERT_TRUE(v.on_pose(pose(2, 10, 0, 0)));
  ASSERT_TRUE(v.on_tracks(tracks_msg(2, 10, {track(4, 1.0, 0.5), track(6, 2.0, 0.0, track_t::STATIC)})));
  ASSERT_TRUE(v.on_global_tracks(fused(10, {track(4, 1.1, 0.4)}, 0b11)));
  nlohmann::json j = state(v);
  ASSERT_EQ(j["robots"].size(), 1u);
  const nlohmann::json& rt = j["robots"][0]["tracks"];
  ASSERT_EQ(rt.size(), 2u);
  EXPECT_EQ(rt[0]["id"], 4);
  EXPECT_EQ(rt[0]["x"], 1.0);
  EXPECT_EQ(rt[0]["vx"], 0.5);
  EXPECT_EQ(rt[0]["model"], "constant_velocity");
  EXPECT_EQ(rt[0]["validated"], true);
  EXPECT_EQ(rt[1]["model"], "static");
  ASSERT_EQ(j["global_tracks"].size(), 1u);
  EXPECT_EQ(j["global_tracks"][0]["x"], 1.1);
  EXPECT_EQ(j["global_tracks"][0]["contributors"], nlohmann::json({1, 2}));

  // Bad ones: refused, counted, nothing changed.
  const long long bad = v.bad_messages();
  track_list_t nan_speed = tracks_msg(2, 11, {track(4, 1.0, std::numeric_limits<double>::quiet_NaN())});
  EXPECT_FALSE(v.on_tracks(nan_speed));
  track_list_t not_psd = tracks_msg(2, 11, {track(4, 1.0, 0.5)});
  not_psd.tracks[0].cov[2] = 1.0f;  // xvx far beyond sqrt(var x * var vx) = 0.02
  EXPECT_FALSE(v.on_tracks(not_psd));
  track_list_t far_id = tracks_msg(2, 11, {track(300, 1.0, 0.5)});  // max_landmark_id 256
  EXPECT_FALSE(v.on_tracks(far_id));
  track_list_t bad_robot = tracks_msg(17, 11, {track(4, 1.0, 0.5)});
  EXPECT_FALSE(v.on_tracks(bad_robot));
  global_tracks_t bad_sum = fused(11, {track(4, 1.0, 0.5)}, 0b1);
  bad_sum.tracks[0].probabilities[2] = 0.9f;  // sums to 1.2
  EXPECT_FALSE(v.on_global_tracks(bad_sum));
  global_tracks_t nobody = fused(11, {track(4, 1.0, 0.5)}, 0);
  EXPECT_FALSE(v.on_global_tracks(nobody));
  global_tracks_t twice = fused(11, {track(4, 1.0, 0.5), track(4, 1.0, 0.5)}, 0b1);
  EXPECT_FALSE(v.on_global_tracks(twice));
  EXPECT_EQ(v.bad_messages(), bad + 7);
  EXPECT_EQ(state(v)["robots"][0]["tracks"], rt);
  EXPECT_EQ(state(v)["global_tracks"], j["global_tracks"]);

  // The newest list replaces the last; an older one is ignored.
  ASSERT_TRUE(v.on_tracks(tracks_msg(2, 12, {track(6, 2.5, 0.1)})));
  ASSERT_TRUE(v.on_tracks(tracks_msg(2, 11, {track(9, 0.0, 0.1)})));
  j = state(v);
  ASSERT_EQ(j["robots"][0]["tracks"].size(), 1u);
  EXPECT_EQ(j["robots"][0]["tracks"][0]["id"], 6);
  // Stale lists are not drawn.
  for (int f = 13; f < 13 + ViewState::kCandidateFrames + 1; ++f) ASSERT_TRUE(v.on_pose(pose(2, f, 0, 0)));
  j = state(v);
  EXPECT_TRUE(j["robots"][0]["tracks"].empty());
  EXPECT_TRUE(j["global_tracks"].empty());
}

std::vector<int> ids(const nlohmann::json& list) {
  std::vector<int> out;
  for (const auto& t : list) out.push_back(t["id"].get<int>());
  return out;
}

// A publication in two chunks: both chunks' tracks are drawn together, a copy of a
// chunk adds nothing, and the next frame's single chunk replaces them. A chunk at
// odds with its frame's others (another num_chunks, a landmark an earlier chunk
// listed, a chunk index out of range) is refused, counted and changes nothing.
TEST(ViewState, TracksInTwoChunksAreDrawnTogether) {
  ViewState v;
  ASSERT_TRUE(v.on_pose(pose(2, 10, 0, 0)));
  ASSERT_TRUE(v.on_tracks(tracks_msg(2, 10, {track(4, 1.0, 0.5), track(6, 2.0, 0.0)}, 0, 2)));
  ASSERT_TRUE(v.on_tracks(tracks_msg(2, 10, {track(8, 3.0, 0.5)}, 1, 2)));
  ASSERT_TRUE(v.on_tracks(tracks_msg(2, 10, {track(8, 3.0, 0.5)}, 1, 2)));  // a copy
  ASSERT_TRUE(v.on_global_tracks(fused(10, {track(4, 1.1, 0.4)}, 0b10, 0, 2)));
  ASSERT_TRUE(v.on_global_tracks(fused(10, {track(8, 3.1, 0.4)}, 0b10, 1, 2)));
  nlohmann::json j = state(v);
  EXPECT_EQ(ids(j["robots"][0]["tracks"]), (std::vector<int>{4, 6, 8}));
  EXPECT_EQ(ids(j["global_tracks"]), (std::vector<int>{4, 8}));

  const long long bad = v.bad_messages();
  ASSERT_TRUE(v.on_tracks(tracks_msg(2, 11, {track(4, 1.2, 0.5)}, 0, 3)));
  EXPECT_FALSE(v.on_tracks(tracks_msg(2, 11, {track(5, 1.0, 0.5)}, 1, 2)));  // num_chunks 2 against 3
  EXPECT_FALSE(v.on_tracks(tracks_msg(2, 11, {track(4, 1.0, 0.5)}, 1, 3)));  // 4 is in chunk 0
  EXPECT_FALSE(v.on_tracks(tracks_msg(2, 11, {track(5, 1.0, 0.5)}, 3, 3)));  // chunk out of range
  EXPECT_FALSE(v.on_tracks(tracks_msg(2, 11, {track(5, 1.0, 0.5)}, 0, 7)));  // more chunks than the contract's
  EXPECT_FALSE(v.on_global_tracks(fused(10, {track(9, 1.0, 0.5)}, 0b10, 0, 1)));  // num_chunks 1 against 2
  EXPECT_TRUE(v.on_global_tracks(fused(10, {track(9, 1.0, 0.5)}, 0b10, 1, 2)));  // chunk 1 held: ignored
  EXPECT_EQ(v.bad_messages(), bad + 5);
  j = state(v);
  EXPECT_EQ(ids(j["robots"][0]["tracks"]), (std::vector<int>{4}));
  EXPECT_EQ(j["robots"][0]["tracks"][0]["x"], 1.2);
  EXPECT_EQ(ids(j["global_tracks"]), (std::vector<int>{4, 8}));

  // Main's second publication of frame 10 (a later utime: a quiet period's repeated
  // map), in one chunk: it replaces the first, not refused for its num_chunks.
  global_tracks_t again = fused(10, {track(6, 2.0, 0.0)}, 0b10);
  again.utime = 5;
  ASSERT_TRUE(v.on_global_tracks(again));
  EXPECT_EQ(ids(state(v)["global_tracks"]), (std::vector<int>{6}));
  EXPECT_EQ(v.bad_messages(), bad + 5);

  ASSERT_TRUE(v.on_tracks(tracks_msg(2, 12, {track(6, 2.5, 0.1)})));
  EXPECT_EQ(ids(state(v)["robots"][0]["tracks"]), (std::vector<int>{6}));
}

}  // namespace
}  // namespace elaslam::viewer

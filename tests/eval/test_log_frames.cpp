// SPDX-License-Identifier: Apache-2.0
// A recorded run as the metrics' frames (eval/log_frames.hpp): what each frame
// takes from the log (poses, sensors, the map), the latencies, what is not
// evaluated and why, the run's facts and the frame accounting, on hand-made events.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iterator>
#include <limits>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "../support/messages.hpp"
#include "elaslam/common/channels.hpp"
#include "elaslam/eval/log_frames.hpp"
#include "elaslam/global_map_t.hpp"
#include "elaslam/global_tracks_t.hpp"
#include "elaslam/ground_truth_t.hpp"
#include "elaslam/node_status_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/run_info_t.hpp"
#include "elaslam/sensor_frame_t.hpp"

namespace elaslam {
namespace {

constexpr std::int64_t kT0 = 1'000'000'000;  // [us] the sensor stamp of frame 0
constexpr std::int64_t kPeriod = 100'000;    // [us] between frames

template <typename Msg>
LogEvent event(const std::string& channel, std::int64_t received, const Msg& m) {
  LogEvent ev;
  ev.timestamp = received;
  ev.channel = channel;
  ev.data.resize(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(ev.data.data(), 0, static_cast<int>(ev.data.size()));
  return ev;
}

ground_truth_t truth(int frame) {
  ground_truth_t g{};
  g.utime = kT0 + frame * kPeriod;
  g.frame = frame;
  g.num_robots = 2;
  g.robot_ids = {1, 2};
  g.robots.resize(2);
  g.robots[0].x = 1.0 * frame;
  g.robots[1].y = 2.0;
  g.num_landmarks = 2;
  g.landmarks.resize(2);
  g.landmarks[0].id = 0;
  g.landmarks[0].x = 5.0;
  g.landmarks[1].id = 1;
  g.landmarks[1].y = 5.0;
  g.landmarks[1].moving = true;
  return g;
}

pose_estimate_t pose(int robot, int frame) {
  pose_estimate_t p{};
  p.robot_id = static_cast<std::int16_t>(robot);
  p.frame = frame;
  p.source_utime = kT0 + frame * kPeriod;
  p.utime = p.source_utime + 2'000;  // published 2 ms after the sensor frame
  p.x = 1.0 * frame;
  p.y = robot == 2 ? 2.0 : 0.0;
  p.cov[0][0] = p.cov[1][1] = p.cov[2][2] = 1e-4;
  p.frames_processed = frame + 1;
  return p;
}

sensor_frame_t sensor(int robot, int frame, int seen) {
  sensor_frame_t s{};
  s.utime = kT0 + frame * kPeriod;
  s.frame = frame;
  s.robot_id = static_cast<std::int16_t>(robot);
  s.num_obs = 1;
  s.obs.resize(1);
  s.obs[0].landmark_id = seen;
  s.obs[0].range = 3.0;
  return s;
}

global_map_t map(int frame, double x) {
  global_map_t g{};
  g.frame = frame;
  g.version = frame + 1;
  g.num_chunks = 1;
  g.id_begin = 0;
  g.id_end = 2;
  g.num_landmarks = 1;
  g.landmarks.resize(1);
  g.landmarks[0].id = 0;
  g.landmarks[0].x = x;
  g.landmarks[0].cov[0][0] = g.landmarks[0].cov[1][1] = 0.01;
  g.num_moving = 1;
  g.moving_ids = {1};
  g.moving_frames = {frame};
  g.moving_by = {1};
  return g;
}

node_status_t status(int robot, int frame, int mode) {
  node_status_t s{};
  s.frame = frame;
  s.node_kind = node_status_t::ROBOT;
  s.node_id = static_cast<std::int16_t>(robot);
  s.mode = static_cast<std::int8_t>(mode);
  s.frames = frame + 1;
  return s;
}

// Three frames, two robots: robot 2's POSE of frame 1 is not in the log; the map
// stamped 0 arrives 30 ms after frame 0's sensors, the next one stamped 2.
LogData three_frames() {
  LogData d;
  for (int k = 0; k < 3; ++k) {
    const std::int64_t t = kT0 + k * kPeriod;
    add_log_event(event(channels::ground_truth(), t, truth(k)), "", &d);
    for (int r = 1; r <= 2; ++r) add_log_event(event(channels::sensor(r), t + 100, sensor(r, k, r - 1)), "", &d);
    for (int r = 1; r <= 2; ++r)
      if (!(r == 2 && k == 1)) add_log_event(event(channels::pose(r), t + 5'000 * r, pose(r, k)), "", &d);
  }
  add_log_event(event(channels::global_map(), kT0 + 30'000, map(0, 5.1)), "", &d);
  add_log_event(event(channels::global_map(), kT0 + 2 * kPeriod + 40'000, map(2, 5.2)), "", &d);
  return d;
}

TEST(LogFrames, EachFrameTakesItsPosesSensorsAndTheNewestMap) {
  LogData d = three_frames();
  ASSERT_EQ(d.truth.size(), 3u);
  const AssembledRun x = assemble_run(d);
  EXPECT_EQ(x.robot_ids, (std::vector<int>{1, 2}));
  ASSERT_EQ(x.r.frames.size(), 3u);
  EXPECT_DOUBLE_EQ(d.truth.at(0).time_s, 0.0) << "times from the first frame";
  EXPECT_NEAR(d.truth.at(2).time_s, 0.2, 1e-9);
  EXPECT_EQ(x.r.estimated[0].size(), 3u);
  EXPECT_EQ(x.r.estimated[1].size(), 2u) << "robot 2's frame 1 has no POSE";
  EXPECT_EQ(d.truth.at(1).map_landmarks.size(), 1u) << "frame 1 keeps the map stamped 0";
  EXPECT_DOUBLE_EQ(d.truth.at(1).map_landmarks[0].second.x(), 5.1);
  EXPECT_DOUBLE_EQ(d.truth.at(2).map_landmarks[0].second.x(), 5.2);
  EXPECT_EQ(d.truth.at(2).observed, (std::vector<int>{0, 1}));
  ASSERT_EQ(x.r.final_map.size(), 1u);
  EXPECT_DOUBLE_EQ(x.r.final_map[0].p.x(), 5.2);
  EXPECT_EQ(x.r.final_moving, (std::vector<int>{1}));
  EXPECT_EQ(x.r.truly_moving, (std::vector<std::uint8_t>{0, 1}));
}

TEST(LogFrames, LatenciesAreReceiveAndPublishTimesMinusTheSensorStamp) {
  LogData d = three_frames();
  const AssembledRun x = assemble_run(d);
  EXPECT_EQ(x.latency[0], (std::vector<std::int64_t>{5'000, 5'000, 5'000}));
  EXPECT_EQ(x.latency[1], (std::vector<std::int64_t>{10'000, 10'000}));
  EXPECT_EQ(x.publish_latency[1], (std::vector<std::int64_t>{2'000, 2'000}));
  EXPECT_EQ(x.all_latency.size(), 5u);
  // The first map stamped >= k minus frame k's SENSOR stamp: frame 1 waits for the
  // map stamped 2.
  EXPECT_EQ(x.map_latency, (std::vector<std::int64_t>{30'000, kPeriod + 40'000, 40'000}));
  const Quantiles q = quantiles(x.all_latency);
  EXPECT_EQ(q.count, 5u);
  EXPECT_EQ(q.max, 10'000);
  EXPECT_EQ(to_json(quantiles({}))["count"], 0);
}

TEST(LogFrames, WhatANodeWouldRefuseOrCannotDecodeIsCountedNotEvaluated) {
  LogData d = three_frames();
  pose_estimate_t forged = pose(1, 2);
  forged.source_utime = kT0 + 10 * kPeriod;  // after its receipt: a negative latency
  LogData fresh;
  add_log_event(event(channels::ground_truth(), kT0, truth(0)), "", &fresh);
  add_log_event(event(channels::pose(1), kT0 + 1'000, forged), "", &fresh);
  EXPECT_TRUE(fresh.poses.empty());
  EXPECT_EQ(fresh.invalid[channels::pose(1)]["malformed"], 1);
  LogEvent garbage{kT0, channels::global_map(), {1, 2, 3}};
  add_log_event(garbage, "", &fresh);
  EXPECT_EQ(fresh.decode_errors[channels::global_map()], 1);
  // Another team's channels (another suffix) are not this team's.
  add_log_event(event(channels::pose(1, "_B"), kT0 + 1'000, pose(1, 0)), "", &fresh);
  EXPECT_TRUE(fresh.poses.empty());
  // A later copy of a robot's POSE of a frame is a duplicate: the first one counts.
  add_log_event(event(channels::pose(1), kT0 + 9'000, pose(1, 0)), "", &d);
  EXPECT_EQ(d.poses.at(0).at(1).received_us, kT0 + 5'000);
}

// The recorded tracks: five frames in which landmark 1 moves along x at 0.5 m/s and
// landmark 0 stands at (5, 0). Robot 1's TRACKS come in two chunks per frame: chunk
// 0 puts landmark 1 0.1 m ahead, chunk 1 landmark 0 where it is; robot 2's single
// chunk puts landmark 1 0.2 m ahead; all with the true velocity. Main's GLOBAL_TRACKS
// come in chunks 0 and 1 of 3 (chunk 2 lost: what came is scored) and put both where
// they are. A second chunk 0 of robot 1's frame 2 (far off) is a later copy and not
// scored; one with a NaN velocity, one whose num_chunks differs from its frame's
// others and a GLOBAL_TRACKS chunk listing a landmark another chunk of its frame
// listed are counted as invalid; main's second publication of frame 4 (another
// utime) is skipped, the frame's first scored. Robots: position RMS sqrt((5 * 0.1^2 + 5 * 0.2^2 +
// 5 * 0) / 15) over 15 samples, speed RMS 0 over the 8 of landmark 1 with a true
// velocity (every frame but the first); fused: position RMS 0 over 10.
TEST(LogFrames, TheRobotsTracksAndMainsFusedTracksAreScoredAgainstTheTruth) {
  LogData d;
  const auto global = [](int frame, int chunk, int id, double x, double y, double vx) {
    global_tracks_t m{};
    m.frame = frame;
    m.chunk = static_cast<std::int16_t>(chunk);
    m.num_chunks = 3;
    m.num_tracks = 1;
    m.tracks.resize(1);
    global_track_t& g = m.tracks[0];
    const track_t t = test::track_of(id, x, y, vx, 0.0);
    g.id = id, g.x = t.x, g.y = t.y, g.vx = t.vx, g.vy = t.vy, g.likeliest = t.likeliest, g.contributors = 0b11;
    std::copy(std::begin(t.cov), std::end(t.cov), std::begin(g.cov));
    std::copy(std::begin(t.probabilities), std::end(t.probabilities), std::begin(g.probabilities));
    return m;
  };
  for (int k = 0; k < 5; ++k) {
    const std::int64_t t = kT0 + k * kPeriod;
    ground_truth_t g = truth(k);
    g.landmarks[1].x = 0.05 * k;
    add_log_event(event(channels::ground_truth(), t, g), "", &d);
    add_log_event(event(channels::tracks(1), t + 1'000,
                        test::tracks_msg(1, k, {test::track_of(1, 0.05 * k + 0.1, 5.0, 0.5, 0.0)}, 0, 2)),
                  "", &d);
    add_log_event(event(channels::tracks(1), t + 1'100, test::tracks_msg(1, k, {test::track_of(0, 5.0, 0.0, 0.0, 0.0)}, 1, 2)),
                  "", &d);
    add_log_event(event(channels::tracks(2), t + 1'200,
                        test::tracks_msg(2, k, {test::track_of(1, 0.05 * k + 0.2, 5.0, 0.5, 0.0)})),
                  "", &d);
    add_log_event(event(channels::global_tracks(), t + 2'000, global(k, 0, 0, 5.0, 0.0, 0.0)), "", &d);
    add_log_event(event(channels::global_tracks(), t + 2'100, global(k, 1, 1, 0.05 * k, 5.0, 0.5)), "", &d);
  }
  add_log_event(event(channels::tracks(1), kT0 + 2 * kPeriod + 3'000,
                      test::tracks_msg(1, 2, {test::track_of(1, 9.0, 5.0, 0.5, 0.0)}, 0, 2)),
                "", &d);
  track_list_t bad = test::tracks_msg(1, 3, {test::track_of(1, 0.0, 5.0, 0.5, 0.0)});
  bad.tracks[0].vx = std::numeric_limits<double>::quiet_NaN();
  add_log_event(event(channels::tracks(1), kT0 + 3 * kPeriod + 3'000, bad), "", &d);
  add_log_event(event(channels::tracks(1), kT0 + 3 * kPeriod + 3'100,
                      test::tracks_msg(1, 3, {test::track_of(2, 0.0, 5.0, 0.5, 0.0)}, 2, 3)),
                "", &d);  // num_chunks 3 against the frame's 2
  add_log_event(event(channels::global_tracks(), kT0 + 4 * kPeriod + 3'000, global(4, 2, 1, 9.0, 5.0, 0.5)), "",
                &d);  // landmark 1 is in chunk 1
  global_tracks_t again = global(4, 0, 1, 9.0, 5.0, 0.5);  // main's second publication of frame 4
  again.utime = 99;
  again.num_chunks = 1;
  add_log_event(event(channels::global_tracks(), kT0 + 4 * kPeriod + 4'000, again), "", &d);
  EXPECT_EQ(d.invalid["TRACKS_1"]["malformed"], 2);
  EXPECT_EQ(d.invalid["GLOBAL_TRACKS"]["malformed"], 0) << "another publication of a frame is not at odds with it";
  EXPECT_EQ(d.invalid["GLOBAL_TRACKS"]["duplicate_id"], 1);
  EXPECT_EQ(d.track_messages, 17);  // valid chunks read: 15, the copy, the one at odds

  const AssembledRun x = assemble_run(d);
  const RunMetrics& m = x.r.metrics;
  ASSERT_TRUE(m.tracks_scored);
  EXPECT_EQ(m.tracks.samples, 15);
  EXPECT_NEAR(m.tracks.position_rms_m, std::sqrt((5 * 0.01 + 5 * 0.04) / 15), 1e-9);
  EXPECT_EQ(m.tracks.moving_samples, 8);
  EXPECT_NEAR(m.tracks.speed_rms_mps, 0.0, 1e-9);
  ASSERT_TRUE(m.global_tracks_scored);
  EXPECT_EQ(m.global_tracks.samples, 10);
  EXPECT_NEAR(m.global_tracks.position_rms_m, 0.0, 1e-12);
  const RunInfo info{"ela", 0.0, 0.0, 0, "run.lcmlog", "", "evaluate"};
  const nlohmann::json j = metrics_json(info, x.r);
  EXPECT_EQ(j["tracks"]["samples"], 15);
  EXPECT_EQ(j["global_tracks"]["samples"], 10);

  // A log without tracks scores none.
  LogData plain = three_frames();
  const AssembledRun y = assemble_run(plain);
  EXPECT_FALSE(y.r.metrics.tracks_scored);
  EXPECT_FALSE(y.r.metrics.global_tracks_scored);
}

TEST(LogFrames, TheRunsFactsComeFromTheLogBeforeTheCommandLine) {
  LogData d = three_frames();
  std::vector<std::string> warnings;
  RunFallbacks a;
  a.source = "run.lcmlog";
  a.mode = "ekf";
  RunInfo info = run_facts(a, d, &warnings);
  EXPECT_EQ(info.mode, "ekf") << "no STATUS, no RUN_INFO: the command line's";
  EXPECT_FALSE(info.simulated);
  EXPECT_DOUBLE_EQ(info.dynamism_percent, 50.0) << "one of two landmarks moves in the ground truth";
  EXPECT_NE(info.data.find("1 of 2 landmarks moving"), std::string::npos) << info.data;
  EXPECT_TRUE(warnings.empty());

  add_log_event(event(channels::status_robot(1), kT0, status(1, 2, node_status_t::MODE_ELA)), "", &d);
  run_info_t ri{};
  ri.source = "simulator";
  ri.seed = 5;
  ri.dynamism_percent = 20.0;
  ri.landmark_speed_mps = 0.3;
  ri.rate_hz = 10.0;
  ri.frames = 3;
  add_log_event(event(channels::run_info(), kT0, ri), "", &d);
  a.seed = 7;
  info = run_facts(a, d, &warnings);
  EXPECT_EQ(info.mode, "ela");
  EXPECT_TRUE(info.simulated);
  EXPECT_EQ(info.seed, 5);
  EXPECT_DOUBLE_EQ(info.dynamism_percent, 20.0);
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_NE(warnings[0].find("--mode ekf"), std::string::npos) << warnings[0];
  EXPECT_NE(warnings[1].find("RUN_INFO"), std::string::npos) << warnings[1];
  EXPECT_EQ(run_info_json(*d.run_info)["seed"], 5);

  add_log_event(event(channels::status_robot(2), kT0, status(2, 2, node_status_t::MODE_EKF)), "", &d);
  bool disagree = false;
  EXPECT_EQ(reported_mode(d, &disagree), "");
  EXPECT_TRUE(disagree);
}

TEST(LogFrames, EveryFrameOfEveryRobotIsAccountedForInMetricsJson) {
  LogData d = three_frames();
  for (int k = 0; k < 3; ++k) add_log_event(event(channels::status_robot(2), kT0, status(2, k, 0)), "", &d);
  const AssembledRun x = assemble_run(d);
  const RunInfo info{"ela", 0.0, 0.0, 0, "run.lcmlog", "", "evaluate"};
  nlohmann::json j = metrics_json(info, x.r);
  add_log_figures(d, x, &j);
  const std::vector<RobotFrameAccount> accounts = account_run_frames(d, x, &j);
  ASSERT_EQ(accounts.size(), 2u);
  EXPECT_EQ(accounts[1].missing_from_log + accounts[1].dropped, 1) << "robot 2's frame 1";
  EXPECT_EQ(j["robots"][1]["latency_us"]["p50"], 10'000);
  EXPECT_EQ(j["latency_us"]["count"], 5);
  EXPECT_EQ(j["log_events"], d.events);
  EXPECT_TRUE(j["authentication"].is_null());
  EXPECT_TRUE(j.contains("frames_dropped"));
  std::ostringstream out;
  print_log_report(out, d, x, info, j, accounts);
  EXPECT_NE(out.str().find("latency_us (sensor -> pose): p50"), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("frames dropped:"), std::string::npos) << out.str();
}

TEST(LogFrames, AReplayedRecordingsLatencyIsNotMeasured) {
  LogData d = three_frames();
  AssembledRun x = assemble_run(d);
  x.all_latency.assign(3, 3'600'000'000);  // an hour: the SENSOR stamps are the recording's
  const RunInfo info{"ela", 0.0, 0.0, 0, "run.lcmlog", "", "evaluate"};
  nlohmann::json j = metrics_json(info, x.r);
  const std::vector<RobotFrameAccount> accounts = account_run_frames(d, x, &j);
  std::ostringstream out;
  print_log_report(out, d, x, info, j, accounts);
  EXPECT_NE(out.str().find("latency: not measured"), std::string::npos) << out.str();
}

class LogFile : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string name = "log_frames_" + std::to_string(::getpid()) + ".lcmlog";
    path_ = (std::filesystem::temp_directory_path() / name).string();
  }
  void TearDown() override { std::filesystem::remove(path_); }
  template <typename Msg>
  void put(lcm::LogFile* log, const std::string& channel, std::int64_t t, const Msg& m) {
    const LogEvent e = event(channel, t, m);
    lcm::LogEvent ev{};
    ev.timestamp = t;
    ev.channel = channel;
    ev.datalen = static_cast<std::int32_t>(e.data.size());
    ev.data = const_cast<std::uint8_t*>(e.data.data());
    log->writeEvent(&ev);
  }
  std::string path_;
};

TEST_F(LogFile, ALogIsReadWholeAndOneWithoutGroundTruthIsRefusedNamingTheChannel) {
  {
    lcm::LogFile log(path_, "w");
    put(&log, channels::pose(1), kT0, pose(1, 0));
  }
  LogData d;
  std::string why;
  EXPECT_FALSE(read_log(path_, "", &d, &why));
  EXPECT_NE(why.find("no GROUND_TRUTH"), std::string::npos) << why;
  {
    lcm::LogFile log(path_, "w");
    put(&log, channels::ground_truth(), kT0, truth(0));
    put(&log, channels::pose(1), kT0 + 5'000, pose(1, 0));
  }
  LogData ok;
  EXPECT_TRUE(read_log(path_, "", &ok, &why)) << why;
  EXPECT_EQ(ok.events, 2);
  EXPECT_TRUE(ok.complete);
  EXPECT_EQ(ok.bytes_skipped, 0);
  LogData none;
  EXPECT_FALSE(read_log(path_ + ".absent", "", &none, &why));
  EXPECT_FALSE(why.empty());
}

}  // namespace
}  // namespace elaslam

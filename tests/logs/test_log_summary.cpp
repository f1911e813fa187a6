// SPDX-License-Identifier: Apache-2.0
// Frame accounting (account_frames) on hand-built POSE / STATUS / SENSOR records, and
// the log summary (summarize_log, log_info) on a synthetic LCM log whose every
// number is known: counts, bytes, rates, time span, RUN_INFO, per-robot accounting,
// an undecodable event; a truncated copy, a non-LCM file and a missing file.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "elaslam/ground_truth_t.hpp"
#include "elaslam/logs/log_summary.hpp"
#include "elaslam/node_status_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/run_info_t.hpp"
#include "elaslam/sensor_frame_t.hpp"
#include "../support/expect_has.hpp"

namespace elaslam {
namespace {

using Ranges = std::vector<std::pair<int, int>>;

// POSEs of frames [from, to] of a robot that processed every one of them, the first
// with frames_processed = n_first.
std::vector<PoseCheckpoint> poses(int from, int to, std::int64_t n_first = 1) {
  std::vector<PoseCheckpoint> v;
  for (int f = from; f <= to; ++f) v.push_back({f, n_first + (f - from)});
  return v;
}

std::vector<PoseCheckpoint> operator+(std::vector<PoseCheckpoint> a, const std::vector<PoseCheckpoint>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

std::vector<int> frames(int from, int to) {
  std::vector<int> v;
  for (int f = from; f <= to; ++f) v.push_back(f);
  return v;
}

void expect_invariant(const RobotFrameAccount& a) {
  EXPECT_EQ(a.poses_logged + a.not_started + a.dropped + a.missing_from_log, a.frames_in_run);
}

// The four counts every frame of the run falls in exactly one of.
struct Counts {
  int poses_logged, not_started, dropped, missing_from_log;
  bool operator==(const Counts& o) const {
    return poses_logged == o.poses_logged && not_started == o.not_started && dropped == o.dropped &&
           missing_from_log == o.missing_from_log;
  }
};

std::ostream& operator<<(std::ostream& out, const Counts& c) {
  return out << "poses_logged " << c.poses_logged << ", not_started " << c.not_started << ", dropped " << c.dropped
             << ", missing_from_log " << c.missing_from_log;
}

// a's four counts are `want`, and they add up to the run.
void expect_counts(const RobotFrameAccount& a, const Counts& want) {
  EXPECT_EQ((Counts{a.poses_logged, a.not_started, a.dropped, a.missing_from_log}), want);
  expect_invariant(a);
}

// ---------------------------------------------------------------------------------
// account_frames
// ---------------------------------------------------------------------------------

TEST(AccountFrames, CleanRunHasEveryPose) {
  const auto a = account_frames(1, 0, 99, poses(0, 99), {{99, 100, 0}}, frames(0, 99));
  EXPECT_EQ(a.robot_id, 1);
  EXPECT_EQ(a.frames_in_run, 100);
  expect_counts(a, {100, 0, 0, 0});
  EXPECT_EQ(a.restarts, 0);
  EXPECT_TRUE(a.missing_pose_ranges.empty());
  EXPECT_TRUE(a.sensor_recorded);
  EXPECT_EQ(a.sensors_logged, 100);
  EXPECT_TRUE(a.missing_sensor_ranges.empty());
  EXPECT_EQ(a.node_reported_dropped, 0);
}

TEST(AccountFrames, PoseLostByTheRecorderIsMissingFromLogNotDropped) {
  // GIVEN a robot that processed frames 0..99, and a recorder that lost POSE 40
  auto p = poses(0, 99);
  p.erase(p.begin() + 40);
  // WHEN accounted THEN frames_processed jumping by 2 across the gap says "processed"
  const auto a = account_frames(1, 0, 99, p, {}, frames(0, 99));
  expect_counts(a, {99, 0, 0, 1});
  EXPECT_EQ(a.missing_pose_ranges, (Ranges{{40, 40}}));
  EXPECT_EQ(a.node_reported_dropped, -1);
}

TEST(AccountFrames, FramesTheRobotDidNotProcessAreDropped) {
  // frames_processed grows by 1 from frame 39 to frame 42: 40 and 41 were never processed
  const auto a = account_frames(2, 0, 99, poses(0, 39) + poses(42, 99, 41), {{99, 98, 2}}, frames(0, 99));
  expect_counts(a, {98, 0, 2, 0});
  EXPECT_EQ(a.missing_pose_ranges, (Ranges{{40, 41}}));
  EXPECT_EQ(a.node_reported_dropped, 2);
}

TEST(AccountFrames, RobotThatJoinedLateHasNotStartedFramesNotDrops) {
  const auto a = account_frames(3, 0, 99, poses(15, 99), {}, frames(0, 99));
  expect_counts(a, {85, 15, 0, 0});
  EXPECT_EQ(a.missing_pose_ranges, (Ranges{{0, 14}}));
}

TEST(AccountFrames, FirstTwoPosesLostByTheRecorder) {
  // The first POSE logged (frame 2) says it is the robot's third frame.
  const auto a = account_frames(1, 0, 99, poses(2, 99, 3), {}, frames(0, 99));
  expect_counts(a, {98, 0, 0, 2});
  EXPECT_EQ(a.missing_pose_ranges, (Ranges{{0, 1}}));
}

TEST(AccountFrames, RobotKilledAndRestartedCountsOneRestart) {
  // GIVEN a robot killed after frame 60 and restarted at frame 70 (count from 1 again)
  const auto a = account_frames(1, 0, 99, poses(0, 60) + poses(70, 99, 1), {{99, 30, 0}}, frames(0, 99));
  // THEN 61..69 are dropped and one restart is seen
  EXPECT_EQ(a.restarts, 1);
  expect_counts(a, {91, 0, 9, 0});
  EXPECT_EQ(a.missing_pose_ranges, (Ranges{{61, 69}}));
}

TEST(AccountFrames, RestartedRobotWhoseFirstPoseAfterTheRestartWasLost) {
  // The restarted node processed 70 (POSE lost) and 71 (frames_processed 2).
  const auto a = account_frames(1, 0, 99, poses(0, 60) + poses(71, 99, 2), {}, frames(0, 99));
  EXPECT_EQ(a.restarts, 1);
  EXPECT_EQ(a.missing_from_log, 1);
  EXPECT_EQ(a.dropped, 9);
  EXPECT_EQ(a.missing_pose_ranges, (Ranges{{61, 70}}));
  expect_invariant(a);
}

TEST(AccountFrames, RobotThatDiedAtFrame100WithALaterStatus) {
  // GIVEN a run of frames 0..149; the robot processed 0..100 and died; the recorder
  // lost POSEs 96..100; its last STATUS (frame 100, 101 frames) came after POSE 95.
  const std::vector<StatusCheckpoint> st = {{50, 51, 0}, {100, 101, 0}};
  const auto a = account_frames(1, 0, 149, poses(0, 95), st, frames(0, 149));
  // 96..100 missing from the log: processed, says the STATUS; 101..149 dropped: the robot was gone
  expect_counts(a, {96, 0, 49, 5});
  EXPECT_EQ(a.restarts, 0);
  EXPECT_EQ(a.missing_pose_ranges, (Ranges{{96, 149}}));

  // Without a STATUS after the last POSE, the tail is dropped (nothing proves otherwise).
  const auto b = account_frames(1, 0, 149, poses(0, 95), {{50, 51, 0}}, frames(0, 149));
  EXPECT_EQ(b.missing_from_log, 0);
  EXPECT_EQ(b.dropped, 54);
  expect_invariant(b);
}

TEST(AccountFrames, StatusAfterARestartPastTheLastPose) {
  // Last POSE at 60 (61 processed); a STATUS at frame 80 counts 5: a restart, 5 processed.
  const auto a = account_frames(1, 0, 99, poses(0, 60), {{80, 5, 0}}, {});
  EXPECT_EQ(a.restarts, 1);
  EXPECT_EQ(a.missing_from_log, 5);
  EXPECT_EQ(a.dropped, 34);
  expect_invariant(a);
}

TEST(AccountFrames, DuplicatesKeepTheFirstAndOutOfRangePosesAreIgnored) {
  // GIVEN frames 10..19 in reverse order, an exact duplicate, a later second POSE of
  // frame 15 that would look like a restart if kept, and POSEs outside the run
  std::vector<PoseCheckpoint> q = {{25, 200}, {12, 3}};
  for (int f = 19; f >= 10; --f) q.push_back({f, f - 9});
  q.push_back({15, 1});
  q.push_back({5, 100});
  const auto a = account_frames(1, 10, 19, q, {}, {10, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 30});
  expect_counts(a, {10, 0, 0, 0});
  EXPECT_EQ(a.restarts, 0);
  EXPECT_EQ(a.sensors_logged, 10);
  EXPECT_TRUE(a.missing_sensor_ranges.empty());
}

TEST(AccountFrames, NoPoseAtAll) {
  // A STATUS proves 30 frames were processed: their POSEs were lost; the rest not started.
  const auto a = account_frames(4, 0, 99, {}, {{29, 30, 0}}, {});
  expect_counts(a, {0, 70, 0, 30});
  EXPECT_FALSE(a.sensor_recorded);
  EXPECT_TRUE(a.missing_sensor_ranges.empty());
  EXPECT_EQ(a.missing_pose_ranges, (Ranges{{0, 99}}));

  const auto b = account_frames(4, 0, 99, {}, {}, {});
  EXPECT_EQ(b.not_started, 100);
  EXPECT_EQ(b.node_reported_dropped, -1);
  expect_invariant(b);

  const auto c = account_frames(4, 5, 4, poses(0, 9), {}, {});  // an empty run
  EXPECT_EQ(c.frames_in_run, 0);
  EXPECT_EQ(c.poses_logged, 0);
  expect_invariant(c);

  // Frame numbers of a damaged log: no overflow, the invariant holds.
  const int lo = std::numeric_limits<int>::min(), hi = std::numeric_limits<int>::max();
  const auto d = account_frames(4, lo, hi, {{lo, 1}, {0, 5}, {hi, 2}}, {{hi, 9, 0}}, {lo, hi});
  EXPECT_EQ(d.frames_in_run, hi / 2);
  EXPECT_EQ(d.poses_logged, 1);
  expect_invariant(d);
}

TEST(AccountFrames, SensorFramesMissingAreRanges) {
  auto s = frames(0, 99);
  s.erase(s.begin() + 50, s.begin() + 53);  // 50, 51, 52
  s.pop_back();                             // 99
  const auto a = account_frames(1, 0, 99, poses(0, 99), {}, s);
  EXPECT_EQ(a.sensors_logged, 96);
  EXPECT_EQ(a.missing_sensor_ranges, (Ranges{{50, 52}, {99, 99}}));
}

TEST(AccountFrames, InvariantHoldsOnRandomInputs) {
  std::mt19937 rng(20240501);
  auto uni = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
  for (int trial = 0; trial < 5000; ++trial) {
    const int first = uni(-5, 50);
    const int last = first + uni(-2, 150);
    std::vector<PoseCheckpoint> p;
    std::set<int> distinct;
    const int n = uni(0, 200);
    for (int i = 0; i < n; ++i) {
      const int f = uni(first - 10, last + 10);
      // mostly plausible counts, sometimes garbage from the wire
      const std::int64_t c = uni(0, 9) == 0 ? std::int64_t{uni(-1000000, 1000000)} * 1000000000000LL : uni(-5, 300);
      p.push_back({f, c});
      if (f >= first && f <= last) distinct.insert(f);
    }
    std::vector<StatusCheckpoint> st;
    for (int i = uni(0, 3); i > 0; --i) st.push_back({uni(first - 5, last + 5), uni(-5, 300), uni(0, 10)});
    std::vector<int> sensors;
    for (int i = uni(0, 100); i > 0; --i) sensors.push_back(uni(first - 5, last + 5));
    const auto a = account_frames(1, first, last, p, st, sensors);
    SCOPED_TRACE("trial " + std::to_string(trial));
    ASSERT_EQ(a.frames_in_run, std::max(0, last - first + 1));
    ASSERT_EQ(a.poses_logged, static_cast<int>(distinct.size()));
    ASSERT_GE(a.not_started, 0);
    ASSERT_GE(a.dropped, 0);
    ASSERT_GE(a.missing_from_log, 0);
    ASSERT_EQ(a.poses_logged + a.not_started + a.dropped + a.missing_from_log, a.frames_in_run);
    int in_ranges = 0;
    for (const auto& [x, y] : a.missing_pose_ranges) {
      ASSERT_LE(x, y);
      in_ranges += y - x + 1;
    }
    ASSERT_EQ(in_ranges, a.frames_in_run - a.poses_logged);
  }
}

TEST(Ranges, AbsentAndFormatted) {
  EXPECT_EQ(absent_ranges(0, 9, {}), (Ranges{{0, 9}}));
  EXPECT_EQ(absent_ranges(0, 9, frames(0, 9)), Ranges{});
  EXPECT_EQ(absent_ranges(0, 9, {0, 2, 3, 9}), (Ranges{{1, 1}, {4, 8}}));
  EXPECT_EQ(absent_ranges(5, 4, {}), Ranges{});
  EXPECT_EQ(format_ranges({{2, 2}, {40, 42}}), "2, 40-42");
  EXPECT_EQ(format_ranges({}), "none");
  EXPECT_EQ(status_mode_name(node_status_t::MODE_CONSENSUS), "consensus");
  EXPECT_EQ(status_mode_name(9), "unknown(9)");
  EXPECT_EQ(iso_utc(1700000000123456LL), "2023-11-14T22:13:20.123456Z");
  EXPECT_EQ(printable("POSE_1"), "POSE_1");
  EXPECT_EQ(printable("d\xc3\xa9j\xc3\xa0"), "d\xc3\xa9j\xc3\xa0");  // UTF-8 kept
  EXPECT_EQ(printable(std::string("A\x1b[2J\xff\xc3", 7)), "A\\x1b[2J\\xff\\xc3");
  EXPECT_EQ(printable(std::string("\0\xed\xa0\x80", 4)), "\\x00\\xed\\xa0\\x80");  // NUL, a surrogate
}

// ---------------------------------------------------------------------------------
// summarize_log on a synthetic log
// ---------------------------------------------------------------------------------

constexpr std::int64_t kT0 = 1700000000000000LL;  // [us] 2023-11-14T22:13:20Z, frame 0
constexpr std::int64_t kFrameUs = 100000;          // 10 Hz

class SyntheticLog : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::path(testing::TempDir()) /
           ("log_summary_" + std::to_string(::getpid()) + "_" +
            testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
    path_ = (dir_ / "run.lcmlog").string();
    write_log();
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // What print_log_summary prints of `s`.
  static std::string printed(const LogSummary& s) {
    std::ostringstream out;
    print_log_summary(out, s);
    return out.str();
  }

  // Out of line: inlined with a known message, g++ 12 sees LCM's encoder of an empty
  // variable-length array (ground_truth_t) write past the buffer (it does not).
  template <typename Msg>
  [[gnu::noinline]] void put(lcm::LogFile* log, const std::string& channel, std::int64_t t, const Msg& m) {
    std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
    ASSERT_EQ(m.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
    put_raw(log, channel, t, buf);
  }
  void put_raw(lcm::LogFile* log, const std::string& channel, std::int64_t t, std::vector<std::uint8_t> data) {
    lcm::LogEvent ev{};
    ev.timestamp = t;
    ev.channel = channel;
    ev.datalen = static_cast<std::int32_t>(data.size());
    ev.data = data.data();
    ASSERT_EQ(log->writeEvent(&ev), 0);
    bytes_[channel] += static_cast<std::int64_t>(data.size());
    ends_.push_back(static_cast<std::int64_t>(ftello(log->getFilePtr())));
  }

  // Frames 0..9 at 10 Hz, robots 1 and 2.
  // Robot 1: processed every frame; the recorder lost POSE 2; one garbage POSE_1 event.
  // Robot 2: started at frame 2; SENSOR 6 lost, so it never processed frame 6.
  void write_log() {
    lcm::LogFile log(path_, "w");
    ASSERT_TRUE(log.good());
    put_raw(&log, "LCM_SELF_TEST", kT0 - 500000, {'l', 'c', 'm', ' ', 's', 'e', 'l', 'f', ' ', 't', 'e', 's', 't'});
    run_info_t info{};
    info.schema_version = run_info_t::SCHEMA_VERSION;
    info.source = "simulator";
    info.version = "simulator (elaslam 9.9.9, git abc1234)";
    info.scenario = "config/paper.yaml";
    info.mode = "ela";
    info.seed = 7;
    info.dynamism_percent = 20.0;
    info.landmark_speed_mps = 0.5;
    info.rate_hz = 10.0;
    info.frames = 10;
    info.num_robots = 2;
    info.robot_ids = {1, 2};
    info.config_yaml = "scenario: {}\n";
    std::int64_t n2 = 0;
    for (int k = 0; k < 10; ++k) {
      const std::int64_t t = kT0 + k * kFrameUs;
      if (k % 5 == 0) {
        info.utime = t;
        info.frame = k - 1;
        put(&log, "RUN_INFO", t, info);
      }
      ground_truth_t gt{};
      gt.utime = t;
      gt.frame = k;
      gt.num_robots = 2;
      gt.robot_ids = {1, 2};
      gt.robots.resize(2);
      put(&log, "GROUND_TRUTH", t, gt);
      for (int r = 1; r <= 2; ++r) {
        if (r == 2 && k == 6) continue;
        sensor_frame_t s{};
        s.utime = t;
        s.frame = k;
        s.robot_id = static_cast<std::int16_t>(r);
        put(&log, "SENSOR_" + std::to_string(r), t + 1000, s);
      }
      pose_estimate_t p{};
      p.robot_id = 1;
      p.frame = k;
      p.frames_processed = k + 1;
      if (k != 2) put(&log, "POSE_1", t + 5000, p);
      if (k == 5) put_raw(&log, "POSE_1", t + 6000, std::vector<std::uint8_t>(37, 0xAB));
      if (k >= 2 && k != 6) {
        p.robot_id = 2;
        p.frames_processed = ++n2;
        put(&log, "POSE_2", t + 5000, p);
      }
      if (k == 4 || k == 9) {
        node_status_t st{};
        st.utime = t + 8000;
        st.frame = k;
        st.node_kind = node_status_t::ROBOT;
        st.node_id = 1;
        st.mode = node_status_t::MODE_ELA;
        st.frames = k + 1;
        st.frames_dropped = 0;
        put(&log, "STATUS_ROBOT_1", t + 8000, st);
      }
    }
  }

  const ChannelSummary& channel(const LogSummary& s, const std::string& name) {
    for (const auto& c : s.channels)
      if (c.name == name) return c;
    ADD_FAILURE() << "no channel " << name;
    static const ChannelSummary none;
    return none;
  }

  std::string copy_prefix(std::int64_t bytes) {
    const std::string out = (dir_ / ("cut_" + std::to_string(bytes) + ".lcmlog")).string();
    std::ifstream in(path_, std::ios::binary);
    std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream(out, std::ios::binary).write(data.data(), bytes);
    return out;
  }

  // A copy of the log with the events of the channels `keep` accepts.
  template <typename Keep>
  std::string copy_channels(const std::string& name, Keep keep) {
    const std::string out_path = (dir_ / name).string();
    lcm::LogFile in(path_, "r");
    lcm::LogFile out(out_path, "w");
    while (const lcm::LogEvent* ev = in.readNextEvent()) {
      if (!keep(ev->channel)) continue;
      lcm::LogEvent copy = *ev;
      EXPECT_EQ(out.writeEvent(&copy), 0);
    }
    return out_path;
  }

  std::filesystem::path dir_;
  std::string path_;
  std::map<std::string, std::int64_t> bytes_;  // payload bytes written per channel
  std::vector<std::int64_t> ends_;             // file offset after each event
};

TEST_F(SyntheticLog, EveryNumberOfTheSummary) {
  const LogSummary s = summarize_log(path_);
  EXPECT_EQ(s.file, path_);
  EXPECT_EQ(s.size_bytes, static_cast<std::int64_t>(std::filesystem::file_size(path_)));
  EXPECT_EQ(s.events, 51);  // 1 self test + 2 RUN_INFO + 10 GT + 19 SENSOR + 10 POSE_1 + 7 POSE_2 + 2 STATUS
  EXPECT_EQ(s.events, static_cast<long>(ends_.size()));
  EXPECT_TRUE(s.complete);
  EXPECT_EQ(s.bytes_read, s.size_bytes);
  EXPECT_EQ(s.bytes_skipped, 0);
  EXPECT_EQ(s.first_us, kT0 - 500000);
  EXPECT_EQ(s.last_us, kT0 + 9 * kFrameUs + 8000);
  EXPECT_DOUBLE_EQ(s.duration_s(), 1.408);

  // Channels, sorted by name.
  std::vector<std::string> names;
  for (const auto& c : s.channels) names.push_back(c.name);
  EXPECT_EQ(names, (std::vector<std::string>{"GROUND_TRUTH", "LCM_SELF_TEST", "POSE_1", "POSE_2", "RUN_INFO",
                                              "SENSOR_1", "SENSOR_2", "STATUS_ROBOT_1"}));
  struct Want {
    const char* name;
    const char* type;
    long count;
    double rate_hz;
    long decode_errors;
  };
  for (const Want& w : {Want{"GROUND_TRUTH", "ground_truth_t", 10, 9 / 0.9, 0},
                        Want{"LCM_SELF_TEST", "other", 1, 0.0, 0},
                        Want{"POSE_1", "pose_estimate_t", 10, 9 / 0.9, 1},
                        Want{"POSE_2", "pose_estimate_t", 7, 6 / 0.7, 0},
                        Want{"RUN_INFO", "run_info_t", 2, 1 / 0.5, 0},
                        Want{"SENSOR_1", "sensor_frame_t", 10, 9 / 0.9, 0},
                        Want{"SENSOR_2", "sensor_frame_t", 9, 8 / 0.9, 0},
                        Want{"STATUS_ROBOT_1", "node_status_t", 2, 1 / 0.5, 0}}) {
    SCOPED_TRACE(w.name);
    const ChannelSummary& c = channel(s, w.name);
    EXPECT_EQ(c.type, w.type);
    EXPECT_EQ(c.count, w.count);
    EXPECT_EQ(c.bytes, bytes_[w.name]);
    EXPECT_NEAR(c.rate_hz, w.rate_hz, 1e-9);
    EXPECT_EQ(c.decode_errors, w.decode_errors);
    EXPECT_EQ(c.fingerprint_mismatches, w.decode_errors);  // the garbage's first 8 bytes are no fingerprint
  }
  EXPECT_EQ(channel(s, "POSE_1").bytes, 9 * pose_estimate_t{}.getEncodedSize() + 37);

  // RUN_INFO: the last one.
  const RunInfoSummary& r = s.run_info;
  ASSERT_TRUE(r.present);
  EXPECT_EQ(r.messages, 2);
  EXPECT_FALSE(r.varies);
  EXPECT_EQ(r.schema_version, run_info_t::SCHEMA_VERSION);
  EXPECT_EQ(r.frame, 4);
  EXPECT_EQ(r.source, "simulator");
  EXPECT_EQ(r.version, "simulator (elaslam 9.9.9, git abc1234)");
  EXPECT_EQ(r.scenario, "config/paper.yaml");
  EXPECT_EQ(r.mode, "ela");
  EXPECT_EQ(r.seed, 7);
  EXPECT_DOUBLE_EQ(r.dynamism_percent, 20.0);
  EXPECT_DOUBLE_EQ(r.landmark_speed_mps, 0.5);
  EXPECT_DOUBLE_EQ(r.rate_hz, 10.0);
  EXPECT_EQ(r.frames, 10);
  EXPECT_EQ(r.robot_ids, (std::vector<int>{1, 2}));

  // Frames and robots.
  EXPECT_EQ(s.frames_source, "GROUND_TRUTH");
  EXPECT_EQ(s.first_frame, 0);
  EXPECT_EQ(s.last_frame, 9);
  EXPECT_EQ(s.frames_logged, 10);
  EXPECT_TRUE(s.frames_missing.empty());
  ASSERT_EQ(s.robots.size(), 2u);

  const RobotSummary& r1 = s.robots[0];
  EXPECT_EQ(r1.robot_id, 1);
  EXPECT_EQ(r1.modes, (std::vector<int>{node_status_t::MODE_ELA}));
  EXPECT_EQ(r1.status_events, 2);
  EXPECT_EQ(r1.pose_events, 10);
  EXPECT_EQ(r1.pose_undecodable, 1);
  EXPECT_TRUE(r1.outputs_recorded());
  EXPECT_EQ(r1.account.frames_in_run, 10);
  expect_counts(r1.account, {9, 0, 0, 1});
  EXPECT_EQ(r1.account.missing_pose_ranges, (Ranges{{2, 2}}));
  EXPECT_EQ(r1.account.sensors_logged, 10);
  EXPECT_TRUE(r1.account.missing_sensor_ranges.empty());
  EXPECT_EQ(r1.account.node_reported_dropped, 0);

  const RobotSummary& r2 = s.robots[1];
  EXPECT_EQ(r2.robot_id, 2);
  EXPECT_TRUE(r2.modes.empty());
  EXPECT_EQ(r2.status_events, 0);
  EXPECT_EQ(r2.pose_events, 7);
  expect_counts(r2.account, {7, 2, 1, 0});
  EXPECT_EQ(r2.account.missing_pose_ranges, (Ranges{{0, 1}, {6, 6}}));
  EXPECT_EQ(r2.account.sensors_logged, 9);
  EXPECT_EQ(r2.account.missing_sensor_ranges, (Ranges{{6, 6}}));
  EXPECT_EQ(r2.account.node_reported_dropped, -1);
}

TEST_F(SyntheticLog, JsonCarriesTheSameNumbersWithUnitsInTheKeys) {
  const nlohmann::json j = to_json(summarize_log(path_));
  EXPECT_EQ(j["events"], 51);
  EXPECT_DOUBLE_EQ(j["duration_s"].get<double>(), 1.408);
  EXPECT_EQ(j["start_utc"], "2023-11-14T22:13:19.500000Z");
  EXPECT_EQ(j["end_utc"], "2023-11-14T22:13:20.908000Z");
  EXPECT_EQ(j["channels"][0]["name"], "GROUND_TRUTH");
  EXPECT_NEAR(j["channels"][0]["rate_hz"].get<double>(), 10.0, 1e-9);
  EXPECT_TRUE(j["channels"][1]["rate_hz"].is_null());  // one event: no rate
  EXPECT_TRUE(j["channels"][1]["decode_errors"].is_null());  // LCM_SELF_TEST: not ours to decode
  EXPECT_EQ(j["channels"][2]["decode_errors"], 1);
  EXPECT_EQ(j["run_info"]["seed"], 7);
  EXPECT_DOUBLE_EQ(j["run_info"]["landmark_speed_mps"].get<double>(), 0.5);
  EXPECT_EQ(j["frames"]["source"], "GROUND_TRUTH");
  EXPECT_EQ(j["robots"][0]["modes"], nlohmann::json::array({"ela"}));
  EXPECT_EQ(j["robots"][0]["missing_pose_ranges"], nlohmann::json::parse("[[2,2]]"));
  EXPECT_EQ(j["robots"][1]["not_started"], 2);
  EXPECT_TRUE(j["robots"][1]["node_reported_dropped"].is_null());
}

TEST_F(SyntheticLog, PrintedSummaryNamesTheLossesCompactly) {
  const std::string text = printed(summarize_log(path_));
  EXPECT_NE(text.find("events:    51, read to the end"), std::string::npos) << text;
  EXPECT_NE(text.find("duration:  1.408 s"), std::string::npos) << text;
  EXPECT_NE(text.find("seed 7, dynamism 20 %, speed 0.5 m/s, rate 10 Hz, 10 frames, robots 1 2"), std::string::npos)
      << text;
  EXPECT_NE(text.find("POSE missing 2 (1 frame); SENSOR missing none"), std::string::npos) << text;
  EXPECT_NE(text.find("POSE missing 0-1, 6 (3 frames); SENSOR missing 6 (1 frame)"), std::string::npos) << text;
}

TEST_F(SyntheticLog, TruncatedCopyIsReadUpToTheCut) {
  const LogSummary full = summarize_log(path_);
  // Cut inside the header of event k, then inside its payload: the events before k are read.
  for (const std::size_t k : {std::size_t{1}, std::size_t{20}, ends_.size() - 1}) {
    for (const std::int64_t into : {std::int64_t{10}, (ends_[k] - ends_[k - 1]) / 2 + 14}) {
      const std::int64_t cut = ends_[k - 1] + into;
      ASSERT_LT(cut, ends_[k]);
      SCOPED_TRACE("event " + std::to_string(k) + " cut at byte " + std::to_string(cut));
      const LogSummary s = summarize_log(copy_prefix(cut));
      EXPECT_EQ(s.events, static_cast<long>(k));
      EXPECT_FALSE(s.complete);
      EXPECT_EQ(s.bytes_read, ends_[k - 1]);
      EXPECT_EQ(s.size_bytes, cut);
      EXPECT_HAS(printed(s), "truncated or corrupt");
    }
  }
  // A cut between events is a complete (shorter) log.
  const LogSummary s = summarize_log(copy_prefix(ends_[20]));
  EXPECT_EQ(s.events, 21);
  EXPECT_TRUE(s.complete);
  EXPECT_LT(s.events, full.events);
}

TEST_F(SyntheticLog, StrayBytesAndABrokenEventAreSkippedAndCounted) {
  std::ifstream in(path_, std::ios::binary);
  const std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // GIVEN 23 stray bytes after event 10 and the marker of event 30 overwritten
  std::string bad = data.substr(0, static_cast<std::size_t>(ends_[10])) + std::string(23, 'Z') +
                    data.substr(static_cast<std::size_t>(ends_[10]));
  bad[static_cast<std::size_t>(ends_[29] + 23)] = 'X';
  const std::string path = (dir_ / "damaged.lcmlog").string();
  std::ofstream(path, std::ios::binary) << bad;
  // WHEN summarized THEN every other event is read, and the skipped bytes are counted
  const LogSummary s = summarize_log(path);
  EXPECT_EQ(s.events, 50);
  EXPECT_TRUE(s.complete);
  EXPECT_EQ(s.bytes_skipped, 23 + (ends_[30] - ends_[29]));
  EXPECT_HAS(printed(s), "bytes between events skipped");
}

TEST_F(SyntheticLog, RandomDamageNeverBreaksTheSummary) {
  std::ifstream in(path_, std::ios::binary);
  const std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::mt19937 rng(7);
  const std::string path = (dir_ / "damaged.lcmlog").string();
  for (int trial = 0; trial < 200; ++trial) {
    // GIVEN the log with a few bytes overwritten (never the first marker) and maybe cut
    std::string bad = data;
    std::uniform_int_distribution<std::size_t> at(4, bad.size() - 1);
    for (int i = std::uniform_int_distribution<int>(1, 8)(rng); i > 0; --i)
      bad[at(rng)] = static_cast<char>(std::uniform_int_distribution<int>(0, 255)(rng));
    if (trial % 3 == 0) bad.resize(at(rng));
    std::ofstream(path, std::ios::binary | std::ios::trunc) << bad;
    // WHEN summarized THEN no crash, no throw, and the accounts still add up
    SCOPED_TRACE("trial " + std::to_string(trial));
    const LogSummary s = summarize_log(path);
    EXPECT_LE(s.bytes_read, s.size_bytes);
    long counted = 0;
    for (const auto& c : s.channels) counted += c.count;
    EXPECT_EQ(counted, s.events);
    for (const auto& r : s.robots) expect_invariant(r.account);
    printed(s);
    EXPECT_FALSE(to_json(s).dump().empty());
  }
}

TEST_F(SyntheticLog, ExtremeFramesAndTimestampsDoNotOverflow) {
  // GIVEN GROUND_TRUTH frames and event timestamps at the ends of their types
  const std::string path = (dir_ / "extreme.lcmlog").string();
  {
    lcm::LogFile log(path, "w");
    for (const int frame : {std::numeric_limits<int>::min(), std::numeric_limits<int>::max()}) {
      ground_truth_t gt{};
      gt.frame = frame;
      put(&log, "GROUND_TRUTH", frame < 0 ? std::numeric_limits<std::int64_t>::min() : std::numeric_limits<std::int64_t>::max(), gt);
      pose_estimate_t p{};
      p.frame = frame;
      p.frames_processed = frame;
      put(&log, "POSE_1", 0, p);
    }
  }
  const LogSummary s = summarize_log(path);
  EXPECT_EQ(s.events, 4);
  EXPECT_GT(s.duration_s(), 1e12);
  ASSERT_EQ(s.robots.size(), 1u);
  expect_invariant(s.robots[0].account);
  EXPECT_HAS(printed(s), "2 of 4294967296 logged");
  EXPECT_FALSE(to_json(s).dump().empty());
}

TEST_F(SyntheticLog, NotAnLcmLogAndMissingFileAreClearErrors) {
  // summarize_log's error for `path` (a failure when it has none).
  auto error_of = [](const std::string& path) -> std::string {
    try {
      summarize_log(path);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    ADD_FAILURE() << "no error for " << path;
    return "";
  };
  const std::string text = (dir_ / "notes.txt").string();
  std::ofstream(text) << "hello, this is not a log\n";
  const std::string not_a_log = error_of(text);
  EXPECT_HAS(not_a_log, "is not an LCM log");
  EXPECT_HAS(not_a_log, text);
  const std::string missing = (dir_ / "nothing.lcmlog").string();
  const std::string no_file = error_of(missing);
  EXPECT_HAS(no_file, "no such file");
  EXPECT_HAS(no_file, missing);
  EXPECT_THROW(summarize_log(dir_.string()), std::runtime_error);  // a directory
  // An empty file is a log of no events (a recorder that heard nothing).
  const std::string empty = (dir_ / "empty.lcmlog").string();
  std::ofstream(empty).close();
  const LogSummary s = summarize_log(empty);
  EXPECT_EQ(s.events, 0);
  EXPECT_TRUE(s.complete);
  EXPECT_TRUE(s.frames_source.empty());
  EXPECT_FALSE(s.run_info.present);
}

TEST_F(SyntheticLog, LogWithoutRunInfoTakesRobotsFromChannelNames) {
  // An older log: the same events without RUN_INFO.
  const LogSummary s = summarize_log(copy_channels("old.lcmlog", [](const std::string& ch) { return ch != "RUN_INFO"; }));
  EXPECT_EQ(s.events, 49);
  EXPECT_FALSE(s.run_info.present);
  ASSERT_EQ(s.robots.size(), 2u);
  EXPECT_EQ(s.robots[0].robot_id, 1);
  EXPECT_EQ(s.robots[1].account.not_started, 2);
  EXPECT_HAS(printed(s), "run info:  none in the log");
}

TEST_F(SyntheticLog, InputOnlyLogSaysRobotOutputsWereNotRecorded) {
  // GIVEN what mrclam_import writes: RUN_INFO, GROUND_TRUTH and SENSOR_<r> only
  const LogSummary s = summarize_log(copy_channels("inputs.lcmlog", [](const std::string& ch) {
    return ch == "RUN_INFO" || ch == "GROUND_TRUTH" || ch.rfind("SENSOR_", 0) == 0;
  }));
  ASSERT_EQ(s.robots.size(), 2u);
  EXPECT_FALSE(s.robots[0].outputs_recorded());
  EXPECT_HAS(printed(s), "no POSE_2 or STATUS_ROBOT_2 in the log (robot outputs not recorded); SENSOR missing 6");
}

TEST_F(SyntheticLog, AnotherVersionOfATypeIsReportedByItsFingerprint) {
  // GIVEN POSE_1 events that carry another type's encoding (as a log recorded before
  // pose_estimate_t gained a field would), and the garbage POSE_1 event
  const std::string path = (dir_ / "other_version.lcmlog").string();
  {
    lcm::LogFile log(path, "w");
    for (int k = 0; k < 2; ++k) {
      node_status_t other{};
      other.frame = k;
      std::vector<std::uint8_t> buf(static_cast<std::size_t>(other.getEncodedSize()));
      other.encode(buf.data(), 0, static_cast<int>(buf.size()));
      lcm::LogEvent ev{};
      ev.timestamp = kT0 + k * kFrameUs;
      ev.channel = "POSE_1";
      ev.datalen = static_cast<std::int32_t>(buf.size());
      ev.data = buf.data();
      ASSERT_EQ(log.writeEvent(&ev), 0);
    }
  }
  const LogSummary s = summarize_log(path);
  ASSERT_EQ(s.channels.size(), 1u);
  EXPECT_EQ(s.channels[0].decode_errors, 2);
  EXPECT_EQ(s.channels[0].fingerprint_mismatches, 2);
  ASSERT_EQ(s.robots.size(), 1u);
  EXPECT_EQ(s.robots[0].pose_undecodable, 2);
  EXPECT_TRUE(s.frames_source.empty());
  EXPECT_HAS(printed(s), "2 of 2 POSE_1 events carry another fingerprint than this build's pose_estimate_t");
}

// The program: exit status and output (skipped when log_info is not built).
TEST_F(SyntheticLog, ProgramExitStatus) {
  const std::string tool = std::string(ELASLAM_BINARY_DIR) + "/bin/log_info";
  if (!std::filesystem::exists(tool)) GTEST_SKIP() << "log_info not built at " << tool;
  auto run = [&](const std::string& args) {
    const int rc = std::system((tool + " " + args + " > " + (dir_ / "out.txt").string() + " 2>&1").c_str());
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  };
  auto output = [&] {
    std::ifstream in(dir_ / "out.txt");
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  EXPECT_EQ(run(path_), 0);
  EXPECT_NE(output().find("POSE missing 2 (1 frame)"), std::string::npos) << output();
  EXPECT_EQ(run(path_ + " --json"), 0);
  EXPECT_EQ(nlohmann::json::parse(output())["events"], 51);
  EXPECT_EQ(run("--help"), 0);
  EXPECT_EQ(run(""), 2);
  EXPECT_EQ(run(path_ + " --bogus"), 2);
  EXPECT_EQ(run((dir_ / "nothing.lcmlog").string()), 2);
  EXPECT_NE(output().find("log_info: cannot open the log"), std::string::npos) << output();
}

}  // namespace
}  // namespace elaslam

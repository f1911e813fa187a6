// SPDX-License-Identifier: Apache-2.0
// mrclam_import's recording without a file (dataset/import_log.hpp): the messages of
// the tiny dataset's 20 frames in log order, RUN_INFO's content, a writer that fails,
// and the summary table.
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "elaslam/dataset/import_log.hpp"

namespace elaslam::mrclam {
namespace {

const std::string kTiny = std::string(ELASLAM_SOURCE_DIR) + "/tests/dataset/data/tiny";

struct Event {
  std::string channel;
  std::int64_t utime;
  std::vector<std::uint8_t> bytes;
};

struct Tiny {
  Tiny() : d(Dataset::load(kTiny, {1, 2})), src(d, options()) {}
  static Options options() {
    Options o;
    o.robots = {1, 2};
    o.rate_hz = 10.0;
    return o;
  }
  Dataset d;
  FrameSource src;
};

TEST(ImportLog, EveryFrameInLogOrderWithRunInfoOnceASecond) {
  const Tiny t;
  const run_info_t info = import_run_info(t.src, Tiny::options(), "data/tiny", "dataset:\n  rate_hz: 5\n");
  EXPECT_EQ(info.source, "mrclam_import");
  EXPECT_EQ(info.scenario, "data/tiny");
  EXPECT_EQ(info.frames, 20);
  EXPECT_EQ(info.seed, -1);
  ASSERT_EQ(info.num_robots, 2);
  EXPECT_EQ(info.robot_ids[1], 2);
  EXPECT_NE(info.config_yaml.find("rate_hz: 10"), std::string::npos) << info.config_yaml;  // as run, not as in the file
  EXPECT_NE(info.config_yaml.find("robots: 1,2"), std::string::npos) << info.config_yaml;
  std::vector<Event> log;
  int failed = -1;
  ASSERT_TRUE(write_import_log(
      t.src, info, 10.0,
      [&](const std::string& ch, std::int64_t utime, const std::uint8_t* data, int size) {
        log.push_back({ch, utime, std::vector<std::uint8_t>(data, data + size)});
        return true;
      },
      &failed));
  EXPECT_EQ(failed, -1);
  ASSERT_EQ(log.size(), 20u * 3 + 2);  // GROUND_TRUTH and two SENSORs per frame; RUN_INFO at frames 0 and 10
  EXPECT_EQ(log[0].channel, "RUN_INFO");
  EXPECT_EQ(log[1].channel, "GROUND_TRUTH");
  EXPECT_EQ(log[2].channel, "SENSOR_1");
  EXPECT_EQ(log[3].channel, "SENSOR_2");
  EXPECT_EQ(log[4].channel, "GROUND_TRUTH");
  EXPECT_EQ(log[31].channel, "RUN_INFO");  // 1 + 10 frames x 3 messages
  EXPECT_EQ(log[1].utime, t.src.frame_utime(0));
  run_info_t again;
  ASSERT_EQ(again.decode(log[31].bytes.data(), 0, static_cast<int>(log[31].bytes.size())),
            static_cast<int>(log[31].bytes.size()));
  EXPECT_EQ(again.frame, 9);  // before frame 10's messages: frames 0..9 are out
  EXPECT_EQ(again.utime, t.src.frame_utime(10));
  sensor_frame_t s;
  ASSERT_GT(s.decode(log[3].bytes.data(), 0, static_cast<int>(log[3].bytes.size())), 0);
  EXPECT_EQ(s.robot_id, 2);
  EXPECT_EQ(s.frame, 0);
}

TEST(ImportLog, AFailedWriteNamesItsFrame) {
  const Tiny t;
  int calls = 0, failed = -1;
  EXPECT_FALSE(write_import_log(
      t.src, import_run_info(t.src, Tiny::options(), "tiny", ""), 10.0,
      [&](const std::string&, std::int64_t, const std::uint8_t*, int) { return ++calls < 8; }, &failed));
  EXPECT_EQ(failed, 2);  // messages 1-4 frame 0 (with RUN_INFO), 5-7 frame 1, the 8th frame 2's first
  EXPECT_EQ(calls, 8);
}

TEST(ImportLog, SummaryTable) {
  Stats s;
  RobotStats r;
  r.id = 3, r.measurements = 100, r.used = 90, r.misreads = 4, r.robot_barcodes = 2, r.duplicates = 4;
  r.odometry_gaps = 1, r.max_odometry_gap_s = 0.75;
  s.robots = {r};
  s.frames = 50, s.start_time = 1000.0, s.end_time = 1004.9;
  std::ostringstream out;
  print_import_stats(out, s, 10.0);
  EXPECT_EQ(out.str(),
            "robot  measurements     used  misreads   robot_bc  duplicates  odo_gaps   max_gap[s]\n"
            "3               100       90         4          2           4         1        0.750\n"
            "frames: 50 at 10 Hz, 4.900 s (Unix 1000.000 .. 1004.900)\n");
}

}  // namespace
}  // namespace elaslam::mrclam

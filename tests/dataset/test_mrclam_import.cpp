// SPDX-License-Identifier: Apache-2.0
// mrclam_import end to end: the LCM log it writes for the tiny dataset holds one
// GROUND_TRUTH and one SENSOR_<r> per robot per frame, in order, and each decodes to
// exactly what mrclam::FrameSource gives for that frame; a RUN_INFO before frame 0
// and then once a second of log time says what the recording is. Bad arguments and
// bad data exit with 2 and 1.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "elaslam/dataset/mrclam.hpp"
#include "elaslam/run_info_t.hpp"

namespace elaslam {
namespace {

const std::string kTiny = std::string(ELASLAM_SOURCE_DIR) + "/tests/dataset/data/tiny";
const std::string kConfig = std::string(ELASLAM_SOURCE_DIR) + "/config/mrclam.yaml";
const std::string kTool = std::string(ELASLAM_BINARY_DIR) + "/bin/mrclam_import";

int run(const std::string& args) {
  const int rc = std::system((kTool + " " + args + " > /dev/null 2>&1").c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

TEST(MrclamImportTool, LogHoldsEveryFrameAsTheFrameSourceGivesIt) {
  const std::string log = testing::TempDir() + "/tiny.lcmlog";
  ASSERT_EQ(run("--dataset " + kTiny + " --config " + kConfig + " --robots 1,2 --with-robot-barcodes --out " + log), 0);
  mrclam::Options o = mrclam::load_options(kConfig);
  o.robots = {1, 2};
  o.with_robot_barcodes = true;
  const mrclam::Dataset d = mrclam::Dataset::load(kTiny, o.robots);
  const mrclam::FrameSource src(d, o);
  ASSERT_GT(src.num_frames(), 0);

  lcm::LogFile file(log, "r");
  ASSERT_TRUE(file.good());
  std::map<std::string, int> count;
  ground_truth_t want_gt;
  std::vector<sensor_frame_t> want;
  int frame = -1;
  for (const lcm::LogEvent* e = file.readNextEvent(); e != nullptr; e = file.readNextEvent()) {
    ++count[e->channel];
    if (e->channel == "RUN_INFO") {
      run_info_t info;
      ASSERT_EQ(info.decode(e->data, 0, e->datalen), e->datalen);
      EXPECT_EQ(info.frame, frame) << "RUN_INFO comes before its frame's messages";
      EXPECT_EQ(info.source, "mrclam_import");
      EXPECT_EQ(info.scenario, kTiny);
      EXPECT_EQ(info.frames, src.num_frames());
      EXPECT_EQ(info.rate_hz, o.rate_hz);
      EXPECT_EQ(info.seed, -1) << "real data: no seed";
      ASSERT_EQ(info.num_robots, 2);
      EXPECT_EQ(info.robot_ids[0], 1);
      EXPECT_EQ(info.robot_ids[1], 2);
      EXPECT_NE(info.config_yaml.find("with_robot_barcodes: true"), std::string::npos) << info.config_yaml;
      continue;
    }
    if (e->channel == "GROUND_TRUTH") {
      ground_truth_t gt;
      ASSERT_EQ(gt.decode(e->data, 0, e->datalen), e->datalen);
      ASSERT_EQ(gt.frame, frame + 1) << "frames in order, ground truth first";
      frame = gt.frame;
      src.frame(frame, &want_gt, &want);
      EXPECT_EQ(e->timestamp, src.frame_utime(frame));
      EXPECT_EQ(gt.utime, want_gt.utime);
      ASSERT_EQ(gt.num_robots, want_gt.num_robots);
      for (int i = 0; i < gt.num_robots; ++i) {
        EXPECT_EQ(gt.robots[i].x, want_gt.robots[i].x);
        EXPECT_EQ(gt.robots[i].theta, want_gt.robots[i].theta);
      }
      EXPECT_EQ(gt.num_landmarks, want_gt.num_landmarks);
    } else {
      sensor_frame_t s;
      ASSERT_EQ(s.decode(e->data, 0, e->datalen), e->datalen);
      ASSERT_EQ(e->channel, "SENSOR_" + std::to_string(s.robot_id));
      ASSERT_EQ(s.frame, frame);
      const sensor_frame_t& w = want[s.robot_id == 1 ? 0 : 1];
      EXPECT_EQ(s.odom_x, w.odom_x);
      EXPECT_EQ(s.odom_theta, w.odom_theta);
      ASSERT_EQ(s.num_obs, w.num_obs);
      for (int k = 0; k < s.num_obs; ++k) {
        EXPECT_EQ(s.obs[k].landmark_id, w.obs[k].landmark_id);
        EXPECT_EQ(s.obs[k].range, w.obs[k].range);
        EXPECT_EQ(s.obs[k].bearing, w.obs[k].bearing);
      }
    }
  }
  EXPECT_EQ(count["GROUND_TRUTH"], src.num_frames());
  EXPECT_EQ(count["SENSOR_1"], src.num_frames());
  EXPECT_EQ(count["SENSOR_2"], src.num_frames());
  const int per_second = static_cast<int>(o.rate_hz);
  EXPECT_EQ(count["RUN_INFO"], (src.num_frames() + per_second - 1) / per_second);
  EXPECT_EQ(count.size(), 4u);
}

TEST(MrclamImportTool, BadArgumentsAndBadDataAreRefused) {
  const std::string log = testing::TempDir() + "/bad.lcmlog";
  EXPECT_EQ(run("--dataset " + kTiny + " --config " + kConfig + " --robots 1,9 --out " + log), 2);
  EXPECT_EQ(run("--dataset " + kTiny + " --config " + kConfig + " --rate -3 --out " + log), 2);
  EXPECT_EQ(run("--dataset " + kTiny + " --config " + kConfig + " --robots 1,2,3 --out " + log), 1);  // no Robot3 files
}

}  // namespace
}  // namespace elaslam

// The team on real data: two minutes of all five robots of UTIAS MRCLAM dataset6
// (when the data is beside the project, ../shared/data/mrclam/dataset6), against
// Vicon, with config/mrclam.yaml. Bounds are stated next to the figures measured
// with `run_dataset --report --duration 120` (docs/mrclam.md).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "elaslam/team/dataset_run.hpp"

namespace elaslam {
namespace {

const std::string kData = std::string(ELASLAM_SOURCE_DIR) + "/../shared/data/mrclam/dataset6";
const std::string kConfig = std::string(ELASLAM_SOURCE_DIR) + "/config/mrclam.yaml";

double mean_of_rms(const RunResult& r) {
  double m = 0.0;
  for (const auto& rm : r.metrics.robots) m += rm.error_rms / static_cast<double>(r.metrics.robots.size());
  return m;
}

long robot_corrections(const RunResult& r) {
  long n = 0;
  for (int id = 1; id <= mrclam::kMaxRobotSubject; ++id) n += r.corrections_by_landmark[static_cast<std::size_t>(id)];
  return n;
}

class RealSlice : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(kData)) GTEST_SKIP() << "no MRCLAM data at " << kData;
    cfg_ = load_dataset_config(kConfig);
    cfg_.dataset.duration_s = 120.0;
    data_ = std::make_unique<mrclam::Dataset>(mrclam::Dataset::load(kData, cfg_.dataset.robots));
  }
  RunResult run(Mode mode, bool barcodes) {
    mrclam::Options o = cfg_.dataset;
    o.with_robot_barcodes = barcodes;
    const mrclam::FrameSource src(*data_, o);
    dr_ = dead_reckoning(src);
    RobotOptions ro = cfg_.robot;
    ro.mode = mode;
    DatasetFrames frames(src);
    return run_team(ro, cfg_.main, frames);
  }
  double dead_reckoning_mean() const {
    double m = 0.0;
    for (const auto& d : dr_) m += d.error_rms / static_cast<double>(dr_.size());
    return m;
  }
  DatasetConfig cfg_;
  std::unique_ptr<mrclam::Dataset> data_;
  std::vector<DeadReckoning> dr_;
};

TEST_F(RealSlice, ElaLocalisesEveryRobotWellBelowDeadReckoning) {
  const RunResult r = run(Mode::kEla, false);
  ASSERT_EQ(r.metrics.frames, 1200);
  ASSERT_EQ(r.metrics.robots.size(), 5u);
  for (const auto& rm : r.metrics.robots) {
    EXPECT_EQ(rm.frames, 1200) << "robot " << rm.id;
    // Measured 0.06-0.36, and 0.82 for robot 2, which maps its first landmarks while
    // drifting in every mode (ekf and gated: 0.83; its dead reckoning: 0.75).
    EXPECT_LT(rm.error_rms, 1.0) << "robot " << rm.id;
  }
  // Measured: 0.317 m against dead reckoning's 0.570 m.
  EXPECT_LT(mean_of_rms(r), 0.40);
  EXPECT_LT(mean_of_rms(r), 0.7 * dead_reckoning_mean());
  EXPECT_LT(r.metrics.landmark_error_mean, 0.35);
  // The dataset's 15 landmarks mapped; at 120 s the expected-but-missing rule has
  // 2 of them on probation (a camera misses landmarks in bursts: docs/mrclam.md).
  EXPECT_GE(r.final_map.size(), 13u);
}

TEST_F(RealSlice, RobotBarcodesHurtEkfAndElaKeepsMostOfThemOut) {
  const RunResult ekf_without = run(Mode::kEkf, false);
  const RunResult ekf_with = run(Mode::kEkf, true);
  const RunResult ela_with = run(Mode::kEla, true);
  const RunResult ela_without = run(Mode::kEla, false);
  // Measured (2026-12-04): ela 0.186 -> 0.206 m with the other robots kept in
  // (+11 %; over the whole run +9 %, docs/mrclam.md). Before robot.ela.lone_needs_check
  // 0.195 -> 0.207 m: the rule made the run without barcodes better and left the
  // one with them as it was, so this slice's bound is 1.15, not 1.1.
  EXPECT_GT(mean_of_rms(ekf_with), 1.5 * mean_of_rms(ekf_without));
  EXPECT_LT(mean_of_rms(ela_with), 1.15 * mean_of_rms(ela_without));
  // ekf lets every sighting of a robot correct a pose (632); ela 242.
  EXPECT_LT(robot_corrections(ela_with), robot_corrections(ekf_with) / 2);
  EXPECT_GT(ela_with.metrics.flagged, 0);
}

TEST(DatasetConfig, RefusesAFilterTooSmallForTheSubjectIds) {
  const std::string path = testing::TempDir() + "/mrclam_small.yaml";
  std::ifstream in(kConfig);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto pos = text.find("    max_landmark_id: 32");
  ASSERT_NE(pos, std::string::npos);
  text.replace(pos, 23, "    max_landmark_id: 16");
  text.replace(text.find("    capacity: 32"), 16, "    capacity: 16");
  std::ofstream(path) << text;
  try {
    load_dataset_config(path);
    FAIL() << "accepted";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("max_landmark_id"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace elaslam

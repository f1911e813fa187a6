// SPDX-License-Identifier: Apache-2.0
// The team on real data: two minutes of all five robots of UTIAS MRCLAM dataset6
// (when the data is in the repository, data/mrclam/dataset6: tools/get_mrclam.sh), against
// Vicon, with config/mrclam.yaml. Bounds are stated next to the figures measured
// with `run_dataset --report --duration 120` (docs/mrclam.md).
#include <gtest/gtest.h>

#include <cstdio>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "elaslam/team/dataset_run.hpp"

namespace elaslam {
namespace {

const std::string kData = std::string(ELASLAM_SOURCE_DIR) + "/data/mrclam/dataset6";
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
  RunResult run(Mode mode, bool barcodes, double body_radius_m = -1.0, double start_s = 0.0,
                double team_check = -1.0) {
    mrclam::Options o = cfg_.dataset;
    o.with_robot_barcodes = barcodes;
    o.start_s = start_s;
    const mrclam::FrameSource src(*data_, o);
    dr_ = dead_reckoning(src);
    RobotOptions ro = cfg_.robot;
    ro.mode = mode;
    DatasetFrames frames(src);
    GlobalMapOptions mo = cfg_.main;
    if (body_radius_m >= 0.0) mo.body_radius_m = body_radius_m;
    if (team_check >= 0.0) mo.team_map_check_probability = team_check;
    return run_team(ro, mo, frames);
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
  // Measured (main.body_radius_m 0.17): ela 0.186 -> 0.197 m with the
  // other robots kept in (+6 %; over the whole run +5 %, docs/mrclam.md); without
  // the body rule 0.206 m (+11 %).
  EXPECT_GT(mean_of_rms(ekf_with), 1.5 * mean_of_rms(ekf_without));
  EXPECT_LT(mean_of_rms(ela_with), 1.1 * mean_of_rms(ela_without));
  // ekf lets every sighting of a robot correct a pose (632); ela 154.
  EXPECT_LT(robot_corrections(ela_with), robot_corrections(ekf_with) / 2);
  EXPECT_GT(ela_with.metrics.flagged, 0);
  // The body rule found robots standing still (6 times) and no static landmark; the
  // ekf baseline never uses it.
  EXPECT_GT(ela_with.occupied, 0);
  EXPECT_EQ(ela_without.occupied, 0);
  EXPECT_EQ(ekf_with.occupied, 0);
  EXPECT_EQ(ekf_without.occupied, 0);
}

// main.body_radius_m: a robot standing still is mapped by the others as a landmark,
// and steers their poses once it drives off. Taken as moving where a robot is, its
// barcode corrects fewer poses (242 -> 154) and the team's error goes down (0.206 ->
// 0.197 m) on the slice.
TEST_F(RealSlice, ALandmarkWhereARobotIsIsTakenAsMoving) {
  const RunResult with_rule = run(Mode::kEla, true);
  const RunResult without_rule = run(Mode::kEla, true, 0.0);
  EXPECT_EQ(without_rule.occupied, 0);
  EXPECT_GT(with_rule.occupied, 0);
  EXPECT_LT(robot_corrections(with_rule), 0.8 * robot_corrections(without_rule));
  EXPECT_LT(mean_of_rms(with_rule), mean_of_rms(without_rule));
  EXPECT_LT(with_rule.metrics.landmark_error_mean, without_rule.metrics.landmark_error_mean);
}

// main.team_map_check_probability: one robot's map must not pull the others. From
// 550 s with the robots' barcodes, robot 5 is steered 0.4 m by robot 4's barcode
// (confirmed while robot 4 stood still, then followed for 20 s as it crept off) and
// its map goes wrong around it. Without the check, the other robots' team maps carry
// that map: robot 1 ends the two minutes at 0.67 m RMS, robot 3 at 0.52 m (measured).
// With it, main leaves robot 5 out of their team maps (64 of the 120 rounds) and they
// stay at 0.35 and 0.20 m; robot 5 itself is no worse (0.24 m either way).
// Measured with the odometer as it reports (robot.odometry_calibration at 1, 1, 0):
// with config/mrclam.yaml's calibration robot 5 is steered differently on this
// slice and the scene of the test is another.
TEST_F(RealSlice, OneRobotsWrongMapDoesNotPullTheOthers) {
  cfg_.robot.ekf.calibration.prior = OdometryCalibration{};
  const RunResult with_check = run(Mode::kEla, true, -1.0, 550.0);
  const RunResult without = run(Mode::kEla, true, -1.0, 550.0, 0.0);
  ASSERT_EQ(with_check.metrics.robots.size(), 5u);
  ASSERT_EQ(with_check.team_map_left_out.size(), 5u);
  EXPECT_GT(with_check.team_map_left_out[4], 30);  // robot 5
  for (const long long n : without.team_map_left_out) EXPECT_EQ(n, 0);
  for (const std::size_t i : {std::size_t{0}, std::size_t{2}})  // robots 1 and 3
    EXPECT_LT(with_check.metrics.robots[i].error_rms, 0.7 * without.metrics.robots[i].error_rms) << "robot " << i + 1;
  EXPECT_LT(with_check.metrics.robots[4].error_rms, 1.1 * without.metrics.robots[4].error_rms);
  EXPECT_LT(mean_of_rms(with_check), 0.8 * mean_of_rms(without));
}

// The gauge test (Robot::apply_team_map) never moves a robot on dataset6, whose
// maps agree with the team's or disagree in ways no rigid motion explains: `ela`,
// with and without the robots' barcodes, from three start times to the end of the
// recording (tools/mrclam_starts.py gives the fourteen starts of docs/mrclam.md),
// each run as it would be without the test, to the digit.
TEST_F(RealSlice, TheGaugeTestNeverMovesARobotOnDataset6) {
  cfg_.dataset.duration_s = 0.0;
  for (const double start : {0.0, 250.0, 550.0}) {
    for (const bool barcodes : {false, true}) {
      SCOPED_TRACE("start " + std::to_string(start) + (barcodes ? ", barcodes" : ""));
      const RunResult with = run(Mode::kEla, barcodes, -1.0, start);
      cfg_.robot.team_map_gauge_test = false;
      const RunResult without = run(Mode::kEla, barcodes, -1.0, start);
      cfg_.robot.team_map_gauge_test = true;
      ASSERT_EQ(with.metrics.robots.size(), without.metrics.robots.size());
      for (std::size_t i = 0; i < with.metrics.robots.size(); ++i) {
        EXPECT_EQ(with.metrics.robots[i].relocalised, 0) << "robot " << i + 1;
        EXPECT_EQ(with.metrics.robots[i].error_rms, without.metrics.robots[i].error_rms) << "robot " << i + 1;
      }
    }
  }
}

// No gate on a drifted filter (robot.team_map.drift_check): on dataset6, robots kept
// with their barcodes, the own filters drift from the aided ones in a good part of
// the frames, and those frames find no mover. Over the whole recording that flags
// fewer static landmarks as moving (precision up), finds every moving robot as
// before, as fast, and leaves the robots' mean error no worse.
// Measured with the odometer as it reports (robot.odometry_calibration at 1, 1, 0):
// with config/mrclam.yaml's calibration the own filters drift less and no static
// landmark is flagged either way (precision 0.625 with and without the check).
TEST_F(RealSlice, ADriftedOwnFilterFlagsNoStaticLandmark) {
  cfg_.robot.ekf.calibration.prior = OdometryCalibration{};
  cfg_.dataset.duration_s = 0.0;
  const RunResult with = run(Mode::kEla, true);
  cfg_.robot.team_map_drift_check = false;
  const RunResult without = run(Mode::kEla, true);
  cfg_.robot.team_map_drift_check = true;
  std::int64_t drifted = 0;
  for (const auto& rm : with.metrics.robots) drifted += rm.own_drifted_frames;
  for (const auto& rm : without.metrics.robots) EXPECT_EQ(rm.own_drifted_frames, 0);
  std::printf("drifted frames %lld; precision %.3f -> %.3f, recall %.3f -> %.3f, mean RMS %.3f -> %.3f m\n",
              static_cast<long long>(drifted), without.metrics.precision, with.metrics.precision, without.metrics.recall,
              with.metrics.recall, mean_of_rms(without), mean_of_rms(with));
  EXPECT_GT(drifted, 1000);
  EXPECT_GT(with.metrics.precision, without.metrics.precision);
  EXPECT_EQ(with.metrics.recall, without.metrics.recall);
  EXPECT_LE(mean_of_rms(with), mean_of_rms(without) + 0.002);
}

// main.team_map_check_probability is checked like every key: outside 0 or
// [0.5, 0.999999], or not a number, stops the start with the key's name; 0 is off.
TEST(DatasetConfig, ATeamMapCheckProbabilityOutOfRangeIsRefusedNamingTheKey) {
  std::ifstream in(kConfig);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string key = "  team_map_check_probability: 0.9999\n";
  ASSERT_NE(text.find(key), std::string::npos);
  EXPECT_DOUBLE_EQ(load_dataset_config(kConfig).main.team_map_check_probability, 0.9999);
  const auto with = [&](const std::string& value) {
    std::string edited = text;
    edited.replace(edited.find(key), key.size(), "  team_map_check_probability: " + value + "\n");
    const std::string path = ::testing::TempDir() + "team_check.yaml";
    std::ofstream(path) << edited;
    return path;
  };
  for (const char* bad : {"0.3", "1.0", "-0.1", ".nan", "yes"}) {
    try {
      load_dataset_config(with(bad));
      ADD_FAILURE() << bad << " was accepted";
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find("main.team_map_check_probability"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(load_dataset_config(with("0")).main.team_map_check_probability, 0.0);
}

// robot.ela.lone_needs_check without the team map: valid, but on dataset1 one robot
// diverged to 1.8 m that way; robot_node and run_dataset say so at start-up.
TEST(DatasetConfig, LoneNeedsCheckWithoutTheTeamMapIsWarnedOf) {
  RobotOptions o = load_dataset_config(kConfig).robot;  // as committed: both on
  ASSERT_TRUE(o.lone_needs_check);
  ASSERT_TRUE(o.team_map_fuse);
  EXPECT_EQ(config_advice(o), "");
  o.team_map_fuse = false;
  const std::string advice = config_advice(o);
  EXPECT_NE(advice.find("robot.ela.lone_needs_check"), std::string::npos) << advice;
  EXPECT_NE(advice.find("robot.team_map.fuse"), std::string::npos) << advice;
  o.mode = Mode::kEkf;  // a mode that does not use it
  EXPECT_EQ(config_advice(o), "");
  o.mode = Mode::kConsensus;
  o.lone_needs_check = false;
  EXPECT_EQ(config_advice(o), "");
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

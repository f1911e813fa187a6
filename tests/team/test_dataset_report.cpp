// SPDX-License-Identifier: Apache-2.0
// run_dataset's runs and files (team/dataset_report.hpp) on the hand-written tiny
// recording (tests/dataset/data/tiny: robots 1 and 2, 20 frames at 10 Hz): the runs'
// order, the mode list, report.md's text against a reference, metrics.json's
// dataset section, and the team run and its files end to end.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <unistd.h>

#include <gtest/gtest.h>

#include "elaslam/team/dataset_report.hpp"

namespace elaslam {
namespace {

namespace fs = std::filesystem;
const std::string kTiny = std::string(ELASLAM_SOURCE_DIR) + "/tests/dataset/data/tiny";
const std::string kConfig = std::string(ELASLAM_SOURCE_DIR) + "/config/mrclam.yaml";

mrclam::Options tiny_options() {
  mrclam::Options o;
  o.robots = {1, 2};
  o.rate_hz = 10.0;
  return o;
}

TEST(DatasetReport, RobotCorrectionsCountRobotSubjectsOnly) {
  RunResult r;
  r.corrections_by_landmark = {100, 1, 2, 3, 4, 5, 60, 70};  // index = subject; 0 and 6.. are not robots
  EXPECT_EQ(robot_corrections(r), 15);
  r.corrections_by_landmark = {100, 1, 2};
  EXPECT_EQ(robot_corrections(r), 3);
}

TEST(DatasetReport, RunsPerModeWithoutThenWithBarcodes) {
  const auto all = dataset_runs({"ekf", "ela"}, true, false);
  ASSERT_EQ(all.size(), 4u);
  EXPECT_EQ(all[0].mode, "ekf");
  EXPECT_FALSE(all[0].barcodes);
  EXPECT_TRUE(all[1].barcodes);
  EXPECT_EQ(all[2].mode, "ela");
  const auto with = dataset_runs({"ekf", "ela"}, false, true);
  ASSERT_EQ(with.size(), 2u);
  EXPECT_TRUE(with[0].barcodes && with[1].barcodes);
  const auto without = dataset_runs({"gated"}, false, false);
  ASSERT_EQ(without.size(), 1u);
  EXPECT_FALSE(without[0].barcodes);
}

TEST(DatasetReport, ModeList) {
  std::vector<std::string> modes;
  std::string why;
  EXPECT_TRUE(parse_mode_list("ekf,consensus", &modes, &why));
  EXPECT_EQ(modes, (std::vector<std::string>{"ekf", "consensus"}));
  modes.clear();
  EXPECT_FALSE(parse_mode_list("ekf,fast", &modes, &why));
  EXPECT_EQ(why, "unknown mode 'fast' (ekf, gated, ela, consensus)");
}

TEST(DatasetReport, SourcesOnlyAsAsked) {
  const DatasetSources src = load_sources(kTiny, tiny_options(), false, true);
  EXPECT_EQ(src.without, nullptr);
  ASSERT_NE(src.with, nullptr);
  EXPECT_EQ(&src.any(), src.with.get());
  EXPECT_EQ(src.any().num_frames(), 20);
  EXPECT_THROW(load_sources(kTiny + "/none", tiny_options(), true, false), mrclam::DatasetError);
}

DatasetRun run_of(const std::string& mode, bool barcodes, double rms1, double rms2) {
  DatasetRun run{mode, barcodes, {}, 7};
  for (int id : {1, 2}) {
    RobotMetrics m;
    m.id = id;
    m.error_rms = id == 1 ? rms1 : rms2;
    m.error_mean = m.error_rms / 2;
    run.result.metrics.robots.push_back(m);
  }
  run.result.metrics.landmark_error_mean = 0.25;
  return run;
}

TEST(DatasetReport, ReportTextAgainstReference) {
  const DatasetSources src = load_sources(kTiny, tiny_options(), true, false);
  const std::vector<DeadReckoning> dr{{1, 0.1, 0.2}, {2, 0.3, 0.4}};
  std::ostringstream out;
  write_dataset_report(out, src.any(), dr, {run_of("ekf", false, 1.0, 2.0), run_of("ekf", true, 0.5, 0.25)}, "cmd x");
  EXPECT_EQ(out.str(),
            "# MRCLAM run report\n\nCommand: `cmd x`\n\n20 frames at 10 Hz (2.000 s), robots 1 2.\n\n"
            "Position error against Vicon per robot, RMS / mean over the frames [m]; the last column is the mean "
            "over robots of each robot's RMS (the reference figures' statistic).\n\n"
            "| run | robot 1 | robot 2 | mean of RMS | global map error [m] | robot-barcode corrections |\n"
            "|---|---|---|---|---|---|\n"
            "| dead reckoning | 0.200 / 0.100 | 0.400 / 0.300 | 0.300 | - | - |\n"
            "| ekf | 1.000 / 0.500 | 2.000 / 1.000 | **1.500** | 0.250 | - |\n"
            "| ekf, robot barcodes kept | 0.500 / 0.250 | 0.250 / 0.125 | **0.375** | 0.250 | 7 |\n"
            "\nRobot-barcode corrections: observations of another robot's barcode that corrected a robot's pose "
            "(summed over robots; candidates' landmark-only updates not counted). Sightings available: 2.\n");
}

TEST(DatasetReport, CalibrationSectionWhenARunEstimatedIt) {
  const DatasetSources src = load_sources(kTiny, tiny_options(), true, false);
  DatasetRun run = run_of("ela", false, 1.0, 1.0);
  RobotMetrics& m = run.result.metrics.robots[1];
  m.calibration_estimated = true;
  m.turn_scale = 1.01, m.turn_scale_sigma = 0.002, m.speed_scale = 0.99, m.speed_scale_sigma = 0.003;
  m.turn_bias_rad_s = -0.001, m.turn_bias_sigma_rad_s = 0.0005;
  std::ostringstream out;
  write_dataset_report(out, src.any(), {{1, 0, 0}, {2, 0, 0}}, {run}, "cmd");
  const std::string text = out.str();
  EXPECT_NE(text.find("| run | robot | turn scale | speed scale | turn bias [rad/s] |\n"), std::string::npos);
  EXPECT_NE(text.find("| ela | 2 | 1.0100 ± 0.0020 | 0.9900 ± 0.0030 | -0.00100 ± 0.00050 |\n"), std::string::npos);
  EXPECT_EQ(text.find("| ela | 1 |"), std::string::npos);  // robot 1 estimated nothing
  // The offline fits: one line per robot for the run and its second half.
  EXPECT_NE(text.find("| offline fit (Vicon), the run | 1 | "), std::string::npos);
  EXPECT_NE(text.find("| offline fit (Vicon), its second half | 2 | "), std::string::npos);
}

TEST(DatasetReport, DatasetJson) {
  const DatasetSources src = load_sources(kTiny, tiny_options(), true, false);
  const nlohmann::json j = dataset_json(src.any(), tiny_options(), "data/tiny", {{1, 0.1, 0.2}, {2, 0.3, 0.4}});
  EXPECT_EQ(j["dir"], "data/tiny");
  EXPECT_EQ(j["frames"], 20);
  EXPECT_EQ(j["rate_hz"], 10.0);
  EXPECT_EQ(j["with_robot_barcodes"], false);
  EXPECT_EQ(j["start_utime"], 1000050000LL);
  ASSERT_EQ(j["robots"].size(), 2u);
  EXPECT_EQ(j["robots"][1]["id"], 2);
  EXPECT_EQ(j["robots"][1]["dead_reckoning_error_rms"], 0.4);
  EXPECT_EQ(j["robots"][0]["measurements"], src.any().stats().robots[0].measurements);
}

TEST(DatasetReport, RunsAndTheirFilesEndToEnd) {
  DatasetConfig cfg = load_dataset_config(kConfig);
  cfg.dataset.robots = {1, 2};
  const DatasetSources src = load_sources(kTiny, cfg.dataset, true, true);
  std::vector<DatasetRun> runs = dataset_runs({"ekf", "ela"}, true, false);
  run_dataset_runs(cfg, src, 2, &runs);
  for (const auto& r : runs) EXPECT_EQ(r.result.metrics.robots.size(), 2u) << r.mode;
  const fs::path dir = fs::temp_directory_path() / ("dataset_report_" + std::to_string(::getpid()));
  DatasetOutputs out{kTiny, kConfig, dir.string(), "build/bin/run_dataset --report", true};
  std::ostringstream log;
  const std::vector<std::string> dirs = write_dataset_runs(out, cfg, src, dead_reckoning(src.any()), runs, log);
  ASSERT_EQ(dirs.size(), 4u);
  EXPECT_EQ(dirs[1], dir.string() + "/ekf_barcodes");
  for (const auto& d : dirs) EXPECT_TRUE(fs::exists(d + "/metrics.json")) << d;
  EXPECT_TRUE(fs::exists(dir / "report.md"));
  EXPECT_TRUE(fs::exists(dir / "report.json"));
  EXPECT_NE(log.str().find("== ela, robot barcodes kept\n"), std::string::npos);
  EXPECT_NE(log.str().find("wrote " + dir.string() + "/report.md\n"), std::string::npos);
  std::ifstream metrics(dirs[1] + "/metrics.json");
  const nlohmann::json j = nlohmann::json::parse(metrics);
  EXPECT_EQ(j["dataset"]["with_robot_barcodes"], true);
  EXPECT_EQ(j["robot_barcode_corrections"], runs[1].robot_corrections);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace elaslam

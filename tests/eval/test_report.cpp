// SPDX-License-Identifier: Apache-2.0
// The metrics of hand-made frames (eval/metrics.hpp, docs/design.md section 7) and
// the output files and JSON of a run (eval/report.hpp), without running a team.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

#include "elaslam/eval/metrics.hpp"
#include "elaslam/eval/report.hpp"

namespace elaslam {
namespace {

// Two landmarks (1 moves), one robot estimated 0.3 m off; the map holds landmark 0
// 0.4 m off and flags landmark 1 as moving.
FrameData frame(int k) {
  FrameData f;
  f.frame = k;
  f.time_s = 0.1 * k;
  f.robot_ids = {1};
  f.true_poses = {Pose2{1.0, 0.0, 0.0}};
  f.true_landmarks = {Eigen::Vector2d(5.0, 0.0), Eigen::Vector2d(0.0, 5.0)};
  f.truly_moving = {0, 1};
  f.has_pose = {1};
  f.est_poses = {Pose2{1.3, 0.0, 0.0}};
  f.mean_diag_p = {0.01 * (k + 1)};
  f.processing_us = {100};
  f.map_landmarks = {{0, Eigen::Vector2d(5.4, 0.0)}};
  f.map_moving = {1};
  f.observed = {0, 1};
  return f;
}

RunResult run_of(int frames) {
  MetricsAccumulator acc;
  RunResult r;
  r.estimated.resize(1);
  r.truth.resize(1);
  for (int k = 0; k < frames; ++k) {
    const FrameData f = frame(k);
    acc.add(f);
    r.estimated[0].push_back({f.time_s, f.est_poses[0]});
    r.truth[0].push_back({f.time_s, f.true_poses[0]});
  }
  r.metrics = acc.finish();
  r.frames = acc.frames();
  r.robot_ids = acc.robot_ids();
  r.final_map = {{0, Eigen::Vector2d(5.4, 0.0), Eigen::Matrix2d::Identity() * 0.01}};
  r.final_moving = {1};
  r.final_truth = frame(0).true_landmarks;
  r.truly_moving = {0, 1};
  return r;
}

TEST(Metrics, ErrorsUncertaintyAndDetectionOfKnownFrames) {
  const RunResult r = run_of(3);
  const RunMetrics& m = r.metrics;
  EXPECT_EQ(m.frames, 3);
  EXPECT_NEAR(m.landmark_error_mean, 0.4, 1e-12);
  EXPECT_NEAR(m.landmark_error_static, 0.4, 1e-12);
  ASSERT_EQ(m.robots.size(), 1u);
  EXPECT_NEAR(m.robots[0].error_mean, 0.3, 1e-12);
  EXPECT_NEAR(m.robots[0].error_rms, 0.3, 1e-12);
  EXPECT_NEAR(m.robots[0].final_uncertainty, 0.03, 1e-12) << "the last frame's (eq 19)";
  EXPECT_EQ(m.flagged, 1);
  EXPECT_EQ(m.true_positives, 1);
  EXPECT_DOUBLE_EQ(m.precision, 1.0);
  EXPECT_DOUBLE_EQ(m.recall, 1.0);
  ASSERT_EQ(r.frames.size(), 3u);
  EXPECT_EQ(r.frames[2].map_moving, 1);
}

TEST(Report, MetricsJsonCarriesTheFiguresAndTheConfigTyped) {
  const RunResult r = run_of(2);
  const RunInfo info{"ela", 20.0, 0.3, 7, "paper.yaml", "robot:\n  mode: ela\nscenario:\n  seed: 7\n", "run_scenario"};
  const nlohmann::json j = metrics_json(info, r);
  EXPECT_EQ(j["schema_version"], kMetricsSchemaVersion);
  EXPECT_EQ(j["mode"], "ela");
  EXPECT_EQ(j["frames"], 2);
  EXPECT_EQ(j["robots"][0]["id"], 1);
  EXPECT_FALSE(j["robots"][0].contains("filter_full")) << "no node counters in this run";
  EXPECT_EQ(j["final_map"]["moving"], 1);
  EXPECT_EQ(j["config"]["scenario"]["seed"], 7);
  EXPECT_EQ(j["config"]["robot"]["mode"], "ela");
  EXPECT_TRUE(yaml_text_to_json("").is_null());
  const nlohmann::json b = baseline_json(info, r, "in process");
  EXPECT_FALSE(b.contains("config"));
  EXPECT_FALSE(b.contains("command_line"));
  EXPECT_EQ(b["how"], "in process");
}

TEST(Report, TumLinesAreARotationAboutZ) {
  std::ostringstream out;
  write_tum(out, {{0.5, Pose2{1.0, 2.0, M_PI}, Eigen::Matrix3d::Zero()}});
  std::istringstream in(out.str());
  std::string header;
  std::getline(in, header);
  double t, x, y, z, qx, qy, qz, qw;
  in >> t >> x >> y >> z >> qx >> qy >> qz >> qw;
  EXPECT_DOUBLE_EQ(t, 0.5);
  EXPECT_DOUBLE_EQ(x, 1.0);
  EXPECT_DOUBLE_EQ(y, 2.0);
  EXPECT_NEAR(qz, 1.0, 1e-9);
  EXPECT_NEAR(qw, 0.0, 1e-9);
}

TEST(Report, EveryOutputFileIsWritten) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("report_" + std::to_string(::getpid()));
  const RunResult r = run_of(2);
  write_outputs(dir.string(), metrics_json(RunInfo{}, r), r);
  for (const char* f :
       {"metrics.json", "frames.csv", "map.csv", "trajectories/robot1.tum", "trajectories/robot1_gt.tum"})
    EXPECT_TRUE(fs::exists(dir / f)) << f;
  std::ifstream frames(dir / "frames.csv");
  std::string line;
  int lines = 0;
  while (std::getline(frames, line)) ++lines;
  EXPECT_EQ(lines, 3) << "a header and a line per frame";
  fs::remove_all(dir);
  std::ostringstream summary;
  print_summary(summary, RunInfo{}, r);
  EXPECT_NE(summary.str().find("moving landmarks: precision"), std::string::npos) << summary.str();
}

}  // namespace
}  // namespace elaslam

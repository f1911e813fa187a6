// SPDX-License-Identifier: Apache-2.0
// The sweep's library (team/sweep.hpp): its lists and their refusals, the jobs'
// order, a run's summary, the files of a small hand-made grid against the values
// computed by hand (mean ± sample sd, cells won), and the parallel run.
#include <cmath>
#include <filesystem>
#include <string>

#include <unistd.h>

#include <gtest/gtest.h>

#include "elaslam/team/sweep.hpp"
#include "../support/read_file.hpp"

namespace elaslam {
namespace {

namespace fs = std::filesystem;

std::string refusal(const std::string& text, double lo = 0.0, double hi = 100.0) {
  try {
    parse_number_list(text, "--speed", lo, hi);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(Sweep, NumberListsAndTheirRefusals) {
  EXPECT_EQ(parse_number_list("5,20.5,80", "--dynamism", 0, 100), (std::vector<double>{5, 20.5, 80}));
  EXPECT_EQ(refusal("1,x"), "--speed: 'x' is not a number");
  EXPECT_EQ(refusal("1e999"), "--speed: '1e999' is not a finite number");
  EXPECT_EQ(refusal("nan"), "--speed: 'nan' is not a finite number");
  EXPECT_EQ(refusal("0.5abc"), "--speed: '0.5abc' is not a number");
  EXPECT_EQ(refusal("3", 0.0, 2.0), "--speed: '3' is out of range: expected a number in [0, 2]");
  EXPECT_EQ(refusal(""), "--speed: empty list");
}

TEST(Sweep, ModeNames) {
  EXPECT_EQ(parse_mode_names("ekf,consensus"), (std::vector<Mode>{Mode::kEkf, Mode::kConsensus}));
  EXPECT_THROW(parse_mode_names("ekf,slow"), std::invalid_argument);
  EXPECT_THROW(parse_mode_names(""), std::invalid_argument);
  const SweepGrid g = make_grid("ela", "5,20", "0.1", 3);
  EXPECT_EQ(g.dynamism, (std::vector<double>{5, 20}));
  EXPECT_EQ(g.runs, 3);
  EXPECT_THROW(make_grid("ela", "101", "0.1", 3), std::invalid_argument);  // dynamism in [0, 100] %
}

TEST(Sweep, JobsInFileOrderWithSharedSeeds) {
  SweepGrid g;
  g.modes = {Mode::kEkf, Mode::kEla};
  g.dynamism = {5, 20};
  g.speed = {0.1};
  g.runs = 2;
  const std::vector<SweepJob> jobs = make_jobs(g, 7);
  ASSERT_EQ(jobs.size(), 8u);
  EXPECT_EQ(jobs[0].mode, Mode::kEkf);
  EXPECT_EQ(jobs[1].seed, 8);
  EXPECT_EQ(jobs[2].dynamism, 20);
  EXPECT_EQ(jobs[4].mode, Mode::kEla);
  EXPECT_EQ(jobs[4].seed, 7);  // the same worlds for every mode
  const RunOverrides map = map_run(g, 7);
  EXPECT_EQ(*map.mode, Mode::kEla);
  EXPECT_EQ(*map.dynamism_percent, 20);  // the middle cell: index size / 2
  g.modes = {Mode::kGated, Mode::kEkf};
  EXPECT_EQ(*map_run(g, 7).mode, Mode::kGated);  // no ela: the first mode
}

TEST(Sweep, SummaryMeansFrameErrorsOverRobotsWithEstimates) {
  RunResult r;
  r.metrics.landmark_error_mean = 1.5;
  r.metrics.flagged = 3;
  RobotMetrics m;
  m.error_mean = 0.2;
  r.metrics.robots = {m};
  FrameMetrics f;
  f.landmark_error = 2.0;
  f.robot_error = {1.0, NAN, 3.0};
  r.frames = {f};
  f.robot_error = {NAN};
  r.frames.push_back(f);
  const SweepResult s = summarise(r);
  EXPECT_EQ(s.landmark_error, 1.5);
  EXPECT_EQ(s.flagged, 3);
  EXPECT_EQ(s.robot_error, (std::vector<double>{0.2}));
  ASSERT_EQ(s.frame_robot_error.size(), 2u);
  EXPECT_EQ(s.frame_robot_error[0], 2.0);
  EXPECT_TRUE(std::isnan(s.frame_robot_error[1]));
}

TEST(Sweep, FilesOfAHandMadeGrid) {
  SweepGrid g;
  g.modes = {Mode::kEkf, Mode::kEla};
  g.dynamism = {5};
  g.speed = {0.1};
  g.runs = 2;
  g.robot_ids = {1};
  const std::vector<SweepJob> jobs = make_jobs(g, 1);
  std::vector<SweepResult> res(4);
  const double lm[4] = {1.0, 3.0, 0.5, 0.5};  // ekf: mean 2, sd sqrt(2); ela: 0.5 ± 0
  for (int i = 0; i < 4; ++i) {
    res[i].landmark_error = lm[i];
    res[i].robot_error = {0.1 * (i + 1)};
    res[i].robot_rms = {0.2};
    res[i].robot_uncertainty = {0.01};
    res[i].frame_landmark_error = {lm[i], NAN};
    res[i].frame_robot_error = {NAN, 1.0};
  }
  const fs::path dir = fs::temp_directory_path() / ("sweep_files_" + std::to_string(::getpid()));
  write_sweep(dir.string(), g, jobs, res);
  const std::string runs = test::read_file(dir / "runs.csv");
  EXPECT_EQ(runs.substr(0, runs.find('\n')),
            "mode,dynamism,speed,run,seed,landmark_error,landmark_rms,robot1_error,robot1_rms,robot1_uncertainty,"
            "precision,recall,static_landmark_error,frames_to_detect,flagged");
  EXPECT_NE(runs.find("\nekf,5,0.1,1,2,3,0,0.2,0.2,0.01,1,1,0,0,0\n"), std::string::npos);
  const std::string frames = test::read_file(dir / "frames.csv");
  EXPECT_NE(frames.find("\nekf,5,0.1,0,2,nan\nekf,5,0.1,1,nan,1\nela,5,0.1,0,0.5,nan\n"), std::string::npos);
  const std::string tables = test::read_file(dir / "tables.md");
  EXPECT_NE(tables.find("### Table 1: landmark error of the global map [m]\n\n| dynamism [%] | 0.1 m/s ekf | "
                        "0.1 m/s ela |\n|---|---|---|\n| 5 | 2.000 ± 1.414 | 0.500 ± 0.000 |\n"),
            std::string::npos);
  EXPECT_NE(tables.find("| landmark error | 0 | 1 |\n"), std::string::npos);
  EXPECT_NE(tables.find("| robot 1 error | 1 | 0 |\n"), std::string::npos);  // ekf 0.15, ela 0.35
  EXPECT_NE(tables.find("over 2 runs"), std::string::npos);
  EXPECT_EQ(tables.find("Oracle runs"), std::string::npos);
  fs::remove_all(dir);
}

TEST(Sweep, RunsInParallelLandAtTheirIndex) {
  TeamConfig base = load_team_config(std::string(ELASLAM_SOURCE_DIR) + "/config/paper.yaml");
  RunOverrides shorter;
  shorter.frames = 20;
  base = apply_overrides(base, shorter);
  SweepGrid g = make_grid("ekf", "20", "0.5", 3);
  check_grid(base, g);
  const std::vector<SweepJob> jobs = make_jobs(g, 1);
  std::vector<SweepResult> one, two;
  std::size_t calls = 0, last = 0;
  run_sweep(base, jobs, 1, &one);
  run_sweep(base, jobs, 2, &two, [&](std::size_t done, std::size_t total) {
    ++calls;
    last = done;
    EXPECT_EQ(total, 3u);
  });
  EXPECT_EQ(calls, 3u);
  EXPECT_EQ(last, 3u);
  ASSERT_EQ(two.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(one[i].landmark_error, two[i].landmark_error) << i;
    EXPECT_EQ(one[i].frame_landmark_error.size(), 20u);
  }
  EXPECT_NE(one[0].landmark_error, one[1].landmark_error);  // another seed, another world
}

}  // namespace
}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// The sweep's grid, its per-run results and the files it writes (runs.csv,
// frames.csv, tables.md in the layout of the paper's Tables 1-4).
#pragma once

#include <string>
#include <vector>

#include "elaslam/robot_node/robot_options.hpp"
#include "elaslam/team/team_run.hpp"

namespace elaslam {

struct SweepGrid {
  std::vector<Mode> modes;
  std::vector<double> dynamism;  // [%]
  std::vector<double> speed;     // [m/s]
  int runs = 10;
  std::vector<int> robot_ids;
  bool oracle = false;  // runs with the moving landmarks' observations removed
};

struct SweepJob {
  Mode mode = Mode::kEla;
  double dynamism = 0.0, speed = 0.0;
  int run = 0, seed = 0;
};

/// What the tables need of one run (the full RunResult is dropped).
struct SweepResult {
  double landmark_error = 0.0, landmark_rms = 0.0, landmark_static = 0.0;
  std::vector<double> robot_error, robot_rms, robot_uncertainty;
  double precision = 1.0, recall = 1.0, frames_to_detect = 0.0;
  int flagged = 0;
  std::vector<double> frame_landmark_error, frame_robot_error;  // per frame (robot: mean over robots)
};

SweepResult summarise(const RunResult& r);

/// Jobs in file order: mode, then dynamism, then speed, then run.
std::vector<SweepJob> make_jobs(const SweepGrid& g, int seed_base);

/// runs.csv, frames.csv and tables.md into `dir` (created). Throws on I/O errors.
void write_sweep(const std::string& dir, const SweepGrid& g, const std::vector<SweepJob>& jobs,
                 const std::vector<SweepResult>& results);

}  // namespace elaslam

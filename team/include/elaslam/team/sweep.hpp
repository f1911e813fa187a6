// SPDX-License-Identifier: Apache-2.0
// The sweep: the paper's experiment grid (section 4, Tables 1-4, Figs 5-8) through
// the in-process team run, in parallel; its grid, its per-run results and the files
// it writes (runs.csv, frames.csv, tables.md in the layout of the paper's Tables 1-4).
// Run r of every cell and mode uses seed seed_base + r: every mode sees the same
// worlds, so differences between modes are the methods', not the draws'.
#pragma once

#include <cstddef>
#include <functional>
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

/// A comma-separated list of numbers, each finite and in [lo, hi]; throws
/// std::invalid_argument naming the option (`what`) and the item.
std::vector<double> parse_number_list(const std::string& text, const char* what, double lo, double hi);
/// A comma-separated list of modes; throws std::invalid_argument naming the item.
std::vector<Mode> parse_mode_names(const std::string& text);

/// The grid of the command line's lists (modes, dynamism [%], speed [m/s]) with the
/// simulator's bounds; throws std::invalid_argument on a bad list.
SweepGrid make_grid(const std::string& modes, const std::string& dynamism, const std::string& speed, int runs);
/// Every cell's scenario applied to `base` (a speed too fast for the rate throws
/// std::invalid_argument, as apply_overrides does).
void check_grid(const TeamConfig& base, const SweepGrid& g);

SweepResult summarise(const RunResult& r);

/// Jobs in file order: mode, then dynamism, then speed, then run.
std::vector<SweepJob> make_jobs(const SweepGrid& g, int seed_base);

/// Called after each finished run, one call at a time: runs done, of how many.
using SweepProgress = std::function<void(std::size_t done, std::size_t total)>;
/// Run every job on `threads` threads; results land at their job's index (the files
/// are identical whatever the thread count). The first exception of any run is
/// rethrown after every thread has ended.
void run_sweep(const TeamConfig& base, const std::vector<SweepJob>& jobs, int threads, std::vector<SweepResult>* out,
               const SweepProgress& progress = nullptr);

/// The run drawn as the sweep's map (like the paper's Fig 4): the middle cell's
/// first run, in ela when the grid has it, else in its first mode.
RunOverrides map_run(const SweepGrid& g, int seed_base);

/// runs.csv, frames.csv and tables.md into `dir` (created). Throws on I/O errors.
void write_sweep(const std::string& dir, const SweepGrid& g, const std::vector<SweepJob>& jobs,
                 const std::vector<SweepResult>& results);

}  // namespace elaslam

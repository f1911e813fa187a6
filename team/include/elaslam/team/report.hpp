// Output files of a run: metrics.json, frames.csv, trajectories/robot<R>.tum and
// robot<R>_gt.tum, and a short summary table. Shared by run_scenario and evaluate.
#pragma once

#include <iosfwd>
#include <string>

#include <nlohmann/json.hpp>

#include "elaslam/team/team_run.hpp"

namespace elaslam {

/// Run facts echoed into metrics.json beside the figures.
struct RunInfo {
  std::string mode;
  double dynamism_percent = 0.0;
  double speed_mps = 0.0;
  long long seed = 0;
  std::string source;              // config file or log
  std::string effective_config;    // YAML text, echoed as a parsed object
};

nlohmann::json metrics_json(const RunInfo& info, const RunResult& r);

/// Write every output file into `dir` (created). Throws std::runtime_error naming
/// the file that could not be written.
void write_outputs(const std::string& dir, const nlohmann::json& metrics, const RunResult& r);

/// A TUM trajectory line per point: "t x y z qx qy qz qw" (z = 0, rotation about z).
void write_tum(std::ostream& out, const std::vector<TrajectoryPoint>& traj);

void print_summary(std::ostream& out, const RunInfo& info, const RunResult& r);

}  // namespace elaslam

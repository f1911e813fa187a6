// SPDX-License-Identifier: Apache-2.0
// Output files of a run: metrics.json, frames.csv, trajectories/robot<R>.tum and
// robot<R>_gt.tum, and a short summary table. Shared by run_scenario, run_dataset,
// sweep and evaluate.
#pragma once

#include <iosfwd>
#include <string>

#include <nlohmann/json.hpp>

#include "elaslam/eval/run_result.hpp"

namespace elaslam {

/// Run facts echoed into metrics.json beside the figures.
struct RunInfo {
  std::string mode;
  double dynamism_percent = 0.0;
  double speed_mps = 0.0;
  long long seed = 0;
  std::string source;              // config file or log
  std::string effective_config;    // YAML text, echoed as a parsed object ("" -> null)
  std::string command_line;        // the command that made the file (provenance)
  // Real (recorded) data has no dynamism, speed or seed: the summary then says what
  // the data is (`data`, e.g. "MRCLAM dataset6, robot barcodes kept") instead.
  bool simulated = true;
  std::string data = "";
};

/// Version of metrics.json's layout; docs/data_dictionary.md describes every key.
/// 2: provenance (schema_version, elaslam_version, command_line, config in live runs).
constexpr int kMetricsSchemaVersion = 2;

nlohmann::json metrics_json(const RunInfo& info, const RunResult& r);
/// metrics.json's "tracks": the track scores, a figure null when nothing was scored for it.
nlohmann::json tracks_json(const TrackMetrics& t);

/// The YAML text as a JSON value (scalars typed as numbers / booleans where they
/// parse); null for empty text.
nlohmann::json yaml_text_to_json(const std::string& yaml);

/// Write every output file into `dir` (created). Throws std::runtime_error naming
/// the file that could not be written.
void write_outputs(const std::string& dir, const nlohmann::json& metrics, const RunResult& r);

/// A TUM trajectory line per point: "t x y z qx qy qz qw" (z = 0, rotation about z).
void write_tum(std::ostream& out, const std::vector<TrajectoryPoint>& traj);

void print_summary(std::ostream& out, const RunInfo& info, const RunResult& r);

/// This run against a baseline on the same scenario and seed (e.g. plain ekf), side
/// by side: landmark error, each robot's error, the final map, detection. `how` says
/// how the baseline was obtained ("in process").
void print_comparison(std::ostream& out, const RunInfo& info, const RunResult& r, const RunInfo& base_info,
                      const RunResult& base, const std::string& how);

/// The baseline's figures for metrics.json ("baseline"): its metrics_json without
/// the config and command line (the same as the run's but for the mode), plus `how`.
nlohmann::json baseline_json(const RunInfo& base_info, const RunResult& base, const std::string& how);

}  // namespace elaslam

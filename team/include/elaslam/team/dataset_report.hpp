// SPDX-License-Identifier: Apache-2.0
// run_dataset's runs and what it writes of them: the team in every (mode, robot
// barcodes) combination asked for, in parallel on one loaded recording; each run's
// output files, metrics.json's dataset section and printed summary; and report.md,
// the runs side by side against dead reckoning with the odometer calibration.
#pragma once

#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "elaslam/dataset/mrclam.hpp"
#include "elaslam/eval/run_result.hpp"
#include "elaslam/team/dataset_run.hpp"

namespace elaslam {

/// One run of the team on the recording.
struct DatasetRun {
  std::string mode;
  bool barcodes = false;  // other robots' barcodes kept (moving landmarks)
  RunResult result;
  long robot_corrections = 0;  // observations of robot subjects that corrected a pose
};

/// Observations of robot subjects (1..5) that corrected a pose, summed over robots.
long robot_corrections(const RunResult& r);

/// The runs in order: per mode, without then with the robots' barcodes (`report`:
/// both; else the one `barcodes` says).
std::vector<DatasetRun> dataset_runs(const std::vector<std::string>& modes, bool report, bool barcodes);

/// "ekf,ela" -> {"ekf", "ela"}; false and *why on a name that is not a mode.
bool parse_mode_list(const std::string& text, std::vector<std::string>* modes, std::string* why);

/// The recording, loaded once, and a frame source per barcode setting needed.
struct DatasetSources {
  std::unique_ptr<mrclam::Dataset> data;
  std::unique_ptr<mrclam::FrameSource> without, with;
  const mrclam::FrameSource& any() const { return without ? *without : *with; }
  const mrclam::FrameSource& of(bool barcodes) const { return barcodes ? *with : *without; }
};
/// Throws mrclam::DatasetError (files) or std::invalid_argument (options).
DatasetSources load_sources(const std::string& dir, const mrclam::Options& o, bool without, bool with);

/// Every run on up to `jobs` threads (results at their run's index); the first
/// exception of any run is rethrown after every thread has ended.
void run_dataset_runs(const DatasetConfig& cfg, const DatasetSources& src, int jobs, std::vector<DatasetRun>* runs);

/// metrics.json's "dataset": the source's options, frames and per-robot counts
/// with the dead reckoning's errors.
nlohmann::json dataset_json(const mrclam::FrameSource& src, const mrclam::Options& o, const std::string& dir,
                            const std::vector<DeadReckoning>& dr);

/// Where and how run_dataset writes its runs.
struct DatasetOutputs {
  std::string dataset_dir, config_path, out_dir, command;
  bool report = false;  // a directory per run (<mode>[_barcodes]), report.md and report.json
};

/// Every run's output files, its summary on `log`, and with `report` report.md and
/// report.json. Returns the run directories. Throws std::runtime_error on I/O errors.
std::vector<std::string> write_dataset_runs(const DatasetOutputs& out, const DatasetConfig& cfg,
                                            const DatasetSources& src, const std::vector<DeadReckoning>& dr,
                                            const std::vector<DatasetRun>& runs, std::ostream& log);

/// report.md: per robot RMS and mean position error of dead reckoning and of every
/// run, the mean of the robots' RMS, the global map error, the robot-barcode
/// corrections, and the odometer calibration when a run estimated it.
void write_dataset_report(std::ostream& out, const mrclam::FrameSource& src, const std::vector<DeadReckoning>& dr,
                          const std::vector<DatasetRun>& runs, const std::string& command);

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// The in-process team beside a run that was already made (run_scenario's, or a live
// team's recording read by evaluate): the team config that run used, and the same
// scenario and seed run again in process with another mode (the baseline).
#pragma once

#include <iosfwd>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "elaslam/eval/report.hpp"
#include "elaslam/run_info_t.hpp"
#include "elaslam/team/team_config.hpp"

namespace elaslam {

/// The team config that ran a recorded run: `cfg` (the team's config file) with the
/// run's facts over it (mode, dynamism, speed, seed from `info`; rate and frames
/// from `recorded`, the log's RUN_INFO, when the simulator made it). Throws
/// std::invalid_argument when the facts do not fit the config.
TeamConfig team_config_of_run(const TeamConfig& cfg, const RunInfo& info, const std::optional<run_info_t>& recorded);

/// The baseline of a run, in process: `config` (the run's scenario and seed, read
/// from `config_path`) with the robots' mode `mode`, run now; printed beside the run
/// to `out` (nullptr: not printed). Returns its baseline_json for metrics.json.
nlohmann::json run_baseline(const TeamConfig& config, const std::string& config_path, const std::string& mode,
                            const RunInfo& info, const RunResult& r, std::ostream* out);

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// RUN_INFO (run_info_t) as the programs that start a run (the simulator,
// mrclam_import) begin it: what every such message says the same way.
#pragma once

#include <string>
#include <vector>

#include "elaslam/run_info_t.hpp"

namespace elaslam {

/// RUN_INFO before the first frame (frame -1) with the schema version, `program` as
/// its source and that program's version line, and the robots' ids (at most
/// contract::kMaxRobots: the callers' own checks hold that). The caller adds what it
/// knows of the run: scenario, mode, seed, rate, frames, the effective config.
run_info_t run_info_start(const std::string& program, const std::vector<int>& robot_ids);

}  // namespace elaslam

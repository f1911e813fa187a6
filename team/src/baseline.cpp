// SPDX-License-Identifier: Apache-2.0
#include "elaslam/team/baseline.hpp"

#include <ostream>

#include "elaslam/robot_node/robot_options.hpp"
#include "elaslam/team/team_run.hpp"

namespace elaslam {

TeamConfig team_config_of_run(const TeamConfig& cfg, const RunInfo& info, const std::optional<run_info_t>& recorded) {
  RunOverrides ov;
  Mode m;
  if (parse_mode(info.mode, &m)) ov.mode = m;
  ov.dynamism_percent = info.dynamism_percent;
  ov.landmark_speed_mps = info.speed_mps;
  ov.seed = static_cast<int>(info.seed);
  if (recorded && recorded->seed >= 0) {
    ov.rate_hz = recorded->rate_hz;
    ov.frames = recorded->frames;
  }
  return apply_overrides(cfg, ov);
}

nlohmann::json run_baseline(const TeamConfig& config, const std::string& config_path, const std::string& mode,
                            const RunInfo& info, const RunResult& r, std::ostream* out) {
  RunOverrides o;
  o.mode = Mode::kEkf;
  parse_mode(mode, &*o.mode);  // the programs accept only known modes
  const TeamConfig bc = apply_overrides(config, o);
  const RunResult base = run_team(bc);
  const RunInfo base_info{mode, info.dynamism_percent, info.speed_mps, info.seed, config_path, bc.effective_yaml,
                          info.command_line};
  if (out) print_comparison(*out, info, r, base_info, base, "in process");
  return baseline_json(base_info, base, "in process, same scenario and seed");
}

}  // namespace elaslam

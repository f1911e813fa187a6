// SPDX-License-Identifier: Apache-2.0
#include "elaslam/common/run_info.hpp"

#include "elaslam/common/cli.hpp"
#include "elaslam/common/contract.hpp"

namespace elaslam {

run_info_t run_info_start(const std::string& program, const std::vector<int>& robot_ids) {
  run_info_t m{};
  m.frame = -1;
  m.schema_version = run_info_t::SCHEMA_VERSION;
  m.source = program;
  m.version = cli::version_line(program);
  contract::set_count(&m.robot_ids, &m.num_robots, static_cast<int>(robot_ids.size()));
  for (std::size_t i = 0; i < robot_ids.size(); ++i) m.robot_ids[i] = static_cast<std::int16_t>(robot_ids[i]);
  return m;
}

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// run_info_start: RUN_INFO as a run's first message begins it.
#include "elaslam/common/run_info.hpp"

#include <gtest/gtest.h>

#include "elaslam/common/cli.hpp"

namespace elaslam {
namespace {

TEST(RunInfo, AProgramsRunStartsBeforeItsFirstFrameWithItsRobots) {
  const run_info_t m = run_info_start("mrclam_import", {1, 3, 5});
  EXPECT_EQ(m.frame, -1);
  EXPECT_EQ(m.schema_version, run_info_t::SCHEMA_VERSION);
  EXPECT_EQ(m.source, "mrclam_import");
  EXPECT_EQ(m.version, cli::version_line("mrclam_import"));
  ASSERT_EQ(m.num_robots, 3);
  EXPECT_EQ(m.robot_ids, (std::vector<std::int16_t>{1, 3, 5}));
  EXPECT_EQ(run_info_start("simulator", {}).num_robots, 0);
}

}  // namespace
}  // namespace elaslam

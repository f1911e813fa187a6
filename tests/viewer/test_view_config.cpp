// SPDX-License-Identifier: Apache-2.0
// What the viewer reads of the config (the main: section's bounds) and the counters
// it adds to its state's JSON (view_state.hpp).
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "elaslam/common/config.hpp"
#include "elaslam/viewer/view_state.hpp"

namespace elaslam::viewer {
namespace {

const std::string kConfig = std::string(ELASLAM_SOURCE_DIR) + "/config/";

TEST(ViewConfig, TheMainSectionsBounds) {
  const ViewLimits paper = load_view_limits(kConfig + "paper.yaml");
  EXPECT_EQ(paper.max_landmark_id, 256);
  EXPECT_EQ(paper.world_bound_m, 1.0e4);
  EXPECT_EQ(load_view_limits(kConfig + "large.yaml").max_landmark_id, 1024);
  // main.limits.world_bound_m (the last world_bound_m of paper.yaml) read from a copy.
  std::ifstream in(kConfig + "paper.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  const std::size_t at = yaml.rfind("world_bound_m: 1.0e4");
  ASSERT_NE(at, std::string::npos);
  yaml.replace(at, 20, "world_bound_m: 2500");
  const std::string path = ::testing::TempDir() + "view_config_" + std::to_string(::getpid()) + ".yaml";
  std::ofstream(path) << yaml;
  EXPECT_EQ(load_view_limits(path).world_bound_m, 2500.0);
  std::remove(path.c_str());
  EXPECT_THROW(load_view_limits(kConfig + "no_such.yaml"), config::ConfigError);
}

TEST(ViewConfig, CountersJson) {
  const std::string j = viewer_counters_json(12, 3, 4, 2, 20.0);
  EXPECT_EQ(j, R"({"messages":12,"bad_messages":3,"queue_drops":4,"clients":2,"updates_per_s":20})");
  EXPECT_EQ(nlohmann::json::parse(viewer_counters_json(0, 0, 0, 0, 2.5))["updates_per_s"], 2.5);
}

}  // namespace
}  // namespace elaslam::viewer

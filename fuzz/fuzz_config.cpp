// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: the one config loader (common/config.hpp) and every component's
// parse function on it: the scenario (simulator), robot (robot_node), main
// (main_robot) and dataset (the MRCLAM importer) sections, as the programs read
// them. A bad config must end in config::ConfigError (the programs' exit 2), never
// in another exception, a crash or a hang.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "elaslam/common/config.hpp"
#include "elaslam/dataset/mrclam.hpp"
#include "elaslam/main_robot/global_map.hpp"
#include "elaslam/robot_node/robot_options.hpp"
#include "elaslam/simulator/scenario.hpp"

namespace {

using namespace elaslam;

template <class Fn>
void expect_config_error_only(const char* what, Fn fn) {
  try {
    fn();
  } catch (const config::ConfigError&) {
    // a refusal: what bad input should get
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz_config: %s: an exception other than ConfigError escaped: %s\n", what, e.what());
    std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  expect_config_error_only("robot", [&] {
    config::Document doc = config::Document::from_string(text, "<fuzz>");
    (void)config::read_component<RobotOptions>(doc, "robot");
  });
  expect_config_error_only("main", [&] {
    config::Document doc = config::Document::from_string(text, "<fuzz>");
    (void)config::read_component<GlobalMapOptions>(doc, "main");
  });
  expect_config_error_only("scenario", [&] {
    (void)sim::load_scenario_text(text, "<fuzz>");  // parse + check_scenario, as the simulator
  });
  expect_config_error_only("dataset", [&] {
    config::Document doc = config::Document::from_string(text, "<fuzz>");
    (void)config::read_component<mrclam::Options>(doc, "dataset");
  });
  return 0;
}

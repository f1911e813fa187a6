// Scenario configuration: the default file loads, every kind of bad input is
// rejected with its key path and a message that says what was expected.
#include <string>

#include <gtest/gtest.h>

#include "elaslam/common/config.hpp"
#include "elaslam/simulator/scenario.hpp"
#include "sim_test_util.hpp"

namespace elaslam::sim {
namespace {

// A small valid scenario; tests swap one piece of text for a broken one.
const std::string kBase = R"(
scenario:
  world: {x_min_m: -10.0, x_max_m: 10.0, y_min_m: -10.0, y_max_m: 10.0}
  frames: 150
  rate_hz: 10.0
  seed: 1
  sensor:
    fov_diameter_m: 8.0
    min_range_m: 0.1
    range_sigma_m: 0.05
    bearing_sigma_deg: 1.0
    detection_probability: 1.0
  odometry: {var_trans_per_m: 4.0e-4, var_rot_per_rad: 1.0e-3, var_rot_per_m: 3.0e-4}
  landmarks: {layout: grid, count: 72, grid_columns: 9, grid_rows: 8}
  dynamism_percent: 20.0
  landmark_speed_mps: 0.5
  reversal_period_frames: 20
  robots:
    - {id: 1, center_m: [0.0, 0.0], radius_m: 6.0, start_angle_deg: -90.0, direction: ccw, speed_mps: 1.2}
    - {id: 2, center_m: [0.0, 0.0], radius_m: 3.0, start_angle_deg: 0.0, direction: cw, speed_mps: 0.6}
)";

std::string with(const std::string& from, const std::string& to) {
  std::string s = kBase;
  const auto pos = s.find(from);
  EXPECT_NE(pos, std::string::npos) << "test bug: '" << from << "' not in the base scenario";
  if (pos != std::string::npos) s.replace(pos, from.size(), to);
  return s;
}

/// Loading `yaml` fails and one problem names `key` and contains `text`.
void expect_rejected(const std::string& yaml, const std::string& key, const std::string& text) {
  try {
    load_scenario_text(yaml, "test.yaml");
    FAIL() << "accepted, expected a problem at " << key;
  } catch (const config::ConfigError& e) {
    bool found = false;
    for (const auto& p : e.problems()) found = found || (p.find(key) == 0 && p.find(text) != std::string::npos);
    EXPECT_TRUE(found) << "no problem '" << key << ": ..." << text << "...' in:\n" << e.what();
    EXPECT_NE(std::string(e.what()).find("test.yaml"), std::string::npos) << "the source is not named";
  }
}

TEST(SimScenario, PaperConfigLoads) {
  const ScenarioOptions o = test::paper();
  EXPECT_EQ(o.frames, 150);
  EXPECT_DOUBLE_EQ(o.rate_hz, 10.0);
  EXPECT_EQ(o.landmarks.count, 72);
  EXPECT_EQ(o.landmarks.layout, Layout::kGrid);
  ASSERT_EQ(o.robots.size(), 3u);
  EXPECT_DOUBLE_EQ(o.world.x_max_m - o.world.x_min_m, 20.0);
  EXPECT_DOUBLE_EQ(o.world.y_max_m - o.world.y_min_m, 20.0);
  EXPECT_EQ(o.reversal_period_frames, 20);
  EXPECT_TRUE(check_scenario(o).empty());
}

TEST(SimScenario, BaseLoadsAndOtherSectionsAreAllowed) {
  // GIVEN the sections of the other components WHEN loading THEN they are left alone.
  const ScenarioOptions o = load_scenario_text(kBase + "robot: {anything: 1}\nmain: {}\ndataset: {}\n");
  EXPECT_EQ(o.robots.size(), 2u);
  EXPECT_FALSE(o.robots[1].ccw);
  EXPECT_DOUBLE_EQ(o.robots[1].radius_m, 3.0);
  // Any other top-level key is a mistake (a typo of a section): refused with the known ones.
  try {
    load_scenario_text(kBase + "robto: {}\n");
    FAIL() << "an unknown section was accepted";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("robto: unknown section (known sections: scenario, dataset, robot, main, team)"),
              std::string::npos)
        << e.what();
  }
}

TEST(SimScenario, MovingCountIsRoundedShareOfLandmarks) {
  ScenarioOptions o = test::paper();
  const double dyn[] = {0, 5, 20, 35, 50, 65, 80, 100};
  const int expected[] = {0, 4, 14, 25, 36, 47, 58, 72};  // round(p / 100 * 72)
  for (int i = 0; i < 8; ++i) {
    o.dynamism_percent = dyn[i];
    EXPECT_EQ(o.moving_count(), expected[i]) << dyn[i] << " %";
  }
}

TEST(SimScenario, MissingKey) { expect_rejected(with("  frames: 150\n", ""), "scenario.frames", "missing"); }

TEST(SimScenario, MissingSection) {
  expect_rejected("robot: {}\n", "scenario", "missing (required section)");
}

TEST(SimScenario, WrongType) {
  expect_rejected(with("rate_hz: 10.0", "rate_hz: fast"), "scenario.rate_hz", "wrong type: expected a number");
  expect_rejected(with("center_m: [0.0, 0.0], radius_m: 6.0", "center_m: 3, radius_m: 6.0"),
                  "scenario.robots[0].center_m", "expected a list of 2 numbers");
}

TEST(SimScenario, OutOfRange) {
  expect_rejected(with("detection_probability: 1.0", "detection_probability: 1.5"),
                  "scenario.sensor.detection_probability", "out of range: got 1.5");
  expect_rejected(with("dynamism_percent: 20.0", "dynamism_percent: 101"), "scenario.dynamism_percent",
                  "out of range");
  expect_rejected(with("count: 72, grid_columns: 9", "count: 40000, grid_columns: 9"), "scenario.landmarks.count",
                  "expected an integer in [1, 32767]");
  expect_rejected(with("{id: 2,", "{id: 17,"), "scenario.robots[1].id", "expected an integer in [1, 16]");
}

TEST(SimScenario, UnknownKeyAndSection) {
  expect_rejected(with("    min_range_m: 0.1\n", "    min_range_m: 0.1\n    fov_deg: 90\n"), "scenario.sensor.fov_deg",
                  "unknown key");
  expect_rejected(kBase + "simulatr: {}\n", "simulatr", "unknown section");
}

TEST(SimScenario, BadEnum) {
  expect_rejected(with("direction: cw", "direction: clockwise"), "scenario.robots[1].direction",
                  "expected one of: ccw, cw");
  expect_rejected(with("layout: grid", "layout: spiral"), "scenario.landmarks.layout",
                  "expected one of: grid, cloister, random");
}

TEST(SimScenario, MalformedYaml) {
  try {
    load_scenario_text("scenario:\n  frames: [1, 2\n", "bad.yaml");
    FAIL() << "accepted malformed YAML";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("malformed YAML at line"), std::string::npos) << e.what();
  }
}

TEST(SimScenario, MissingFile) {
  try {
    load_scenario("/nonexistent/paper.yaml");
    FAIL() << "accepted a missing file";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos) << e.what();
  }
}

TEST(SimScenario, RobotTooFastForSensor) {
  // 100 m/s at 10 Hz is 10 m per frame > D = 8 m (paper eq 14 and after).
  expect_rejected(with("speed_mps: 1.2", "speed_mps: 100.0"), "scenario.robots[0].speed_mps",
                  "must stay below the sensor's diameter D = 8 m");
}

TEST(SimScenario, CrossFieldChecks) {
  expect_rejected(with("radius_m: 6.0", "radius_m: 12.0"), "scenario.robots[0]", "the path leaves the world");
  expect_rejected(with("{id: 2,", "{id: 1,"), "scenario.robots[1].id", "duplicate robot id 1");
  expect_rejected(with("grid_rows: 8", "grid_rows: 7"), "scenario.landmarks", "must equal count = 72");
  expect_rejected(with("landmark_speed_mps: 0.5", "landmark_speed_mps: 90"), "scenario.landmark_speed_mps",
                  "must stay below D = 8 m");
  expect_rejected(with("x_max_m: 10.0", "x_max_m: -20.0"), "scenario.world.x_max_m", "greater than");
  expect_rejected(with("min_range_m: 0.1", "min_range_m: 5.0"), "scenario.sensor.min_range_m",
                  "below the sensor range");
  expect_rejected(with("layout: grid, count: 72, grid_columns: 9, grid_rows: 8",
                       "layout: random, count: 72, min_spacing_m: 5.0"),
                  "scenario.landmarks", "could not place 72 landmarks");
}

TEST(SimScenario, LayoutKeysRequiredOnlyForTheChosenLayout) {
  expect_rejected(with("layout: grid, count: 72, grid_columns: 9, grid_rows: 8", "layout: cloister, count: 72"),
                  "scenario.landmarks.cloister_rings", "missing");
  const ScenarioOptions o = load_scenario_text(with(
      "layout: grid, count: 72, grid_columns: 9, grid_rows: 8",
      "layout: random, count: 72, min_spacing_m: 1.0, grid_columns: 9"));  // a spare grid key is fine
  EXPECT_EQ(o.landmarks.layout, Layout::kRandom);
}

TEST(SimScenario, RobotListLength) {
  expect_rejected(with("  robots:\n    - {id: 1,", "  robots: []\n  unused:\n    - {id: 1,"), "scenario.robots",
                  "wrong length");
}

TEST(SimScenario, AllProblemsReportedAtOnce) {
  std::string s = with("rate_hz: 10.0", "rate_hz: -1");
  s.replace(s.find("seed: 1"), 7, "seed: x");
  try {
    load_scenario_text(s);
    FAIL();
  } catch (const config::ConfigError& e) {
    EXPECT_GE(e.problems().size(), 2u) << e.what();
  }
}

}  // namespace
}  // namespace elaslam::sim

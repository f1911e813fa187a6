// SPDX-License-Identifier: Apache-2.0
// Scenario configuration: the default file loads, every kind of bad input is
// rejected with its key path and a message that says what was expected.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

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
    EXPECT_EQ(o.moving_count(72), expected[i]) << dyn[i] << " %";
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

// ---- Systematic odometer error, turns in place, empty regions ---------------------

TEST(SimScenario, OdometerErrorIsNoneByDefaultForEveryRobotOrPerRobot) {
  // GIVEN no odometer keys THEN no robot's odometer has an error
  for (const RobotPathOptions& p : load_scenario_text(kBase).robots) {
    EXPECT_TRUE(p.odometer.none());
    EXPECT_EQ(p.spin.duration_s, 0.0);
  }
  EXPECT_FALSE(load_scenario_text(kBase).landmarks.empty_region.enabled);
  // GIVEN scenario.odometry's keys THEN every robot has them
  const std::string every = with("var_rot_per_m: 3.0e-4}",
                                 "var_rot_per_m: 3.0e-4, turn_scale: 0.95, speed_scale: 1.02, turn_bias_rad_s: -0.01}");
  for (const RobotPathOptions& p : load_scenario_text(every).robots) {
    EXPECT_EQ(p.odometer.turn_scale, 0.95);
    EXPECT_EQ(p.odometer.speed_scale, 1.02);
    EXPECT_EQ(p.odometer.turn_bias_rad_s, -0.01);
  }
  // GIVEN robot 1's own keys THEN they apply to robot 1 only, the others' keys
  // default to scenario.odometry's
  std::string own = every;
  own.replace(own.find("speed_mps: 1.2}"), 15, "speed_mps: 1.2, odometry: {turn_scale: 0.9}}");
  const ScenarioOptions o = load_scenario_text(own);
  EXPECT_EQ(o.robots[0].odometer.turn_scale, 0.9);
  EXPECT_EQ(o.robots[0].odometer.speed_scale, 1.02);
  EXPECT_EQ(o.robots[0].odometer.turn_bias_rad_s, -0.01);
  EXPECT_EQ(o.robots[1].odometer.turn_scale, 0.95);
  // AND the effective configuration says what each robot got
  const std::string path = ::testing::TempDir() + "sim_scenario_odometer.yaml";
  FILE* f = std::fopen(path.c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fputs(own.c_str(), f);
  std::fclose(f);
  std::string effective;
  load_scenario(path, &effective);
  std::remove(path.c_str());
  const YAML::Node echo = YAML::Load(effective)["scenario"];
  EXPECT_EQ(echo["odometry"]["turn_scale"].as<double>(), 0.95) << effective;
  EXPECT_EQ(echo["robots"][0]["odometry"]["turn_scale"].as<double>(), 0.9) << effective;
  EXPECT_EQ(echo["robots"][0]["odometry"]["speed_scale"].as<double>(), 1.02) << effective;
  EXPECT_FALSE(echo["robots"][1]["odometry"].IsDefined()) << effective;  // scenario.odometry's
  EXPECT_FALSE(echo["robots"][1]["spin"].IsDefined()) << effective;
  EXPECT_FALSE(echo["landmarks"]["empty_region"].IsDefined()) << effective;
}

TEST(SimScenario, OdometerErrorBadKeysAreNamed) {
  expect_rejected(with("var_rot_per_m: 3.0e-4}", "var_rot_per_m: 3.0e-4, turn_scale: 0.3}"),
                  "scenario.odometry.turn_scale", "out of range: got 0.3, expected a value in [0.5, 2]");
  expect_rejected(with("speed_mps: 1.2}", "speed_mps: 1.2, odometry: {speed_scale: 2.5}}"),
                  "scenario.robots[0].odometry.speed_scale", "out of range: got 2.5");
  expect_rejected(with("speed_mps: 0.6}", "speed_mps: 0.6, odometry: {turn_bias_rad_s: 0.7}}"),
                  "scenario.robots[1].odometry.turn_bias_rad_s", "expected a value in [-0.5, 0.5]");
  expect_rejected(with("speed_mps: 1.2}", "speed_mps: 1.2, odometry: {turn_scale: fast}}"),
                  "scenario.robots[0].odometry.turn_scale", "wrong type: expected a number");
  expect_rejected(with("speed_mps: 1.2}", "speed_mps: 1.2, odometry: {var_trans_per_m: 1.0e-3}}"),
                  "scenario.robots[0].odometry.var_trans_per_m",
                  "unknown key (known keys here: turn_scale, speed_scale, turn_bias_rad_s)");
  expect_rejected(with("var_rot_per_m: 3.0e-4}", "var_rot_per_m: 3.0e-4, turn_scael: 0.9}"),
                  "scenario.odometry.turn_scael", "unknown key");
  // Options built in code get the same bounds from check_scenario.
  ScenarioOptions o = test::paper();
  o.robots[2].odometer.turn_scale = 0.0;
  const std::vector<Problem> problems = check_scenario(o);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0].key, "robots[2].odometry.turn_scale");
  EXPECT_EQ(problems[0].what, "must be in [0.5, 2], got 0");
}

TEST(SimScenario, SpinKeysAndChecks) {
  const std::string spin = "speed_mps: 0.6, spin: {start_s: 2.0, duration_s: 3.0, turn_deg: 115.0}}";
  const ScenarioOptions o = load_scenario_text(with("speed_mps: 0.6}", spin));
  EXPECT_EQ(o.robots[1].spin.start_s, 2.0);
  EXPECT_EQ(o.robots[1].spin.duration_s, 3.0);
  EXPECT_EQ(o.robots[1].spin.turn_deg, 115.0);
  EXPECT_EQ(o.robots[0].spin.duration_s, 0.0);
  expect_rejected(with("speed_mps: 0.6}", "speed_mps: 0.6, spin: {start_s: 2.0, duration_s: 3.0}}"),
                  "scenario.robots[1].spin.turn_deg", "missing (required key)");
  expect_rejected(with("speed_mps: 0.6}", "speed_mps: 0.6, spin: {start_s: 2.0, duration_s: 0.0, turn_deg: 90}}"),
                  "scenario.robots[1].spin.duration_s", "out of range");
  expect_rejected(with("speed_mps: 0.6}", "speed_mps: 0.6, spin: {start_s: 2, duration_s: 3, turn_deg: 90, "
                                          "rate_deg_s: 1}}"),
                  "scenario.robots[1].spin.rate_deg_s", "unknown key");
  // 3600 deg in 1 s at 10 Hz: 360 deg a frame, ambiguous.
  expect_rejected(with("speed_mps: 0.6}", "speed_mps: 0.6, spin: {start_s: 2.0, duration_s: 1.0, turn_deg: 3600}}"),
                  "scenario.robots[1]", "would report up to 361.1");
  // A turn rate bias can do it too: at 0.3 Hz robot 1 turns 0.67 rad a frame, the
  // bias adds 1.67 rad, and a turn scale of 0.5 doubles the report: 267 deg.
  std::string slow = with("rate_hz: 10.0", "rate_hz: 0.3");
  slow.replace(slow.find("speed_mps: 1.2}"), 15, "speed_mps: 1.2, odometry: {turn_scale: 0.5, turn_bias_rad_s: 0.5}}");
  expect_rejected(slow, "scenario.robots[0]",
                  "would report up to 267.38 deg of turn in a frame, which must stay below 180");
  // The rest of the path turns with the spin and may leave the world.
  expect_rejected(with("speed_mps: 1.2}", "speed_mps: 1.2, spin: {start_s: 3.0, duration_s: 3.0, turn_deg: -115}}"),
                  "scenario.robots[0]", "the path leaves the world at (");
  expect_rejected(with("speed_mps: 1.2}", "speed_mps: 1.2, spin: {start_s: 3.0, duration_s: 3.0, turn_deg: -115}}"),
                  "scenario.robots[0]", "or change spin (the rest of the path turns with it)");
}

TEST(SimScenario, EmptyRegionKeysAndChecks) {
  const std::string region = "grid_rows: 8, empty_region: {x_min_m: 0.1, x_max_m: 8.4, y_min_m: -8.4, y_max_m: -0.1}}";
  const ScenarioOptions o = load_scenario_text(with("grid_rows: 8}", region));
  EXPECT_TRUE(o.landmarks.empty_region.enabled);
  EXPECT_EQ(o.landmarks.empty_region.x_max_m, 8.4);
  EXPECT_EQ(o.landmarks.empty_region.y_min_m, -8.4);
  expect_rejected(with("grid_rows: 8}", "grid_rows: 8, empty_region: {x_min_m: 0.1, x_max_m: 8.4, y_min_m: -8.4}}"),
                  "scenario.landmarks.empty_region.y_max_m", "missing (required key)");
  expect_rejected(
      with("grid_rows: 8}", "grid_rows: 8, empty_region: {x_min_m: 5, x_max_m: 1, y_min_m: -8.4, y_max_m: -0.1}}"),
      "scenario.landmarks.empty_region.x_max_m", "must be greater than landmarks.empty_region.x_min_m");
  expect_rejected(
      with("grid_rows: 8}", "grid_rows: 8, empty_region: {x_min_m: 11, x_max_m: 12, y_min_m: -8.4, y_max_m: -0.1}}"),
      "scenario.landmarks.empty_region", "lies outside the world");
  expect_rejected(
      with("grid_rows: 8}", "grid_rows: 8, empty_region: {x_min_m: -11, x_max_m: 11, y_min_m: -11, y_max_m: 11}}"),
      "scenario.landmarks", "the empty region holds all 72 landmarks of the layout: shrink empty_region");
  expect_rejected(with("grid_rows: 8}", "grid_rows: 8, empty_region: {x_min_m: 0, x_max_m: 1, y_min_m: 0, "
                                        "y_max_m: 1, radius_m: 2}}"),
                  "scenario.landmarks.empty_region.radius_m", "unknown key");
  expect_rejected(with("grid_rows: 8}", "grid_rows: 8, empty_region: [0, 1, 0, 1]}"),
                  "scenario.landmarks.empty_region", "wrong type: expected a map of keys");
}

// config/movers.yaml: paper.yaml's scenario with its 36 movers of three kinds.
TEST(SimScenario, MoversConfigLoads) {
  const ScenarioOptions o = load_scenario(std::string(ELASLAM_SOURCE_DIR) + "/config/movers.yaml");
  EXPECT_EQ(o.movers.kinds, (std::vector<MotionKind>{MotionKind::kOscillating, MotionKind::kConstantVelocity,
                                                      MotionKind::kStopAndGo}));
  EXPECT_EQ(o.stop_and_go_move_frames(), 30);
  EXPECT_EQ(o.stop_and_go_stop_frames(), 30);
  EXPECT_NE(describe(o).find("  movers: 12 oscillating, 12 constant_velocity, 12 stop_and_go"), std::string::npos)
      << describe(o);
}

// scenario.movers: absent, the paper's oscillating movers; listed, the kinds in
// order; stop_and_go's stretches default to 3 s each and may be given one by one.
TEST(SimScenario, MoverKeysAndDefaults) {
  const ScenarioOptions plain = load_scenario_text(kBase);
  EXPECT_EQ(plain.movers.kinds, std::vector<MotionKind>{MotionKind::kOscillating});
  EXPECT_EQ(plain.movers.stop_and_go.move_s, 3.0);
  EXPECT_EQ(plain.movers.stop_and_go.stop_s, 3.0);
  EXPECT_EQ(plain.stop_and_go_move_frames(), 30);
  const ScenarioOptions mixed = load_scenario_text(
      with("  reversal_period_frames: 20\n",
           "  reversal_period_frames: 20\n  movers:\n    kinds: [stop_and_go, oscillating, constant_velocity, "
           "stop_and_go]\n    stop_and_go: {stop_s: 1.25}\n"));
  EXPECT_EQ(mixed.movers.kinds, (std::vector<MotionKind>{MotionKind::kStopAndGo, MotionKind::kOscillating,
                                                          MotionKind::kConstantVelocity, MotionKind::kStopAndGo}));
  EXPECT_EQ(mixed.movers.stop_and_go.move_s, 3.0);
  EXPECT_EQ(mixed.movers.stop_and_go.stop_s, 1.25);
  EXPECT_EQ(mixed.stop_and_go_stop_frames(), 13);  // round(12.5)
}

TEST(SimScenario, MoverBadKeysAreNamed) {
  auto movers = [](const std::string& yaml) {
    return with("  reversal_period_frames: 20\n", "  reversal_period_frames: 20\n  movers: " + yaml + "\n");
  };
  expect_rejected(movers("{kinds: [oscillating, teleport]}"), "scenario.movers.kinds[1]",
                  "invalid value 'teleport', expected one of: oscillating, constant_velocity, stop_and_go");
  expect_rejected(movers("{kinds: [static]}"), "scenario.movers.kinds[0]", "invalid value 'static'");
  expect_rejected(movers("{kinds: []}"), "scenario.movers.kinds", "wrong length: got 0 items, expected 1 to 64");
  expect_rejected(movers("{kinds: oscillating}"), "scenario.movers.kinds",
                  "wrong type: expected a list of strings, got 'oscillating'");
  expect_rejected(movers("{kinds: [[oscillating]]}"), "scenario.movers.kinds[0]", "wrong type: expected a string");
  expect_rejected(movers("{stop_and_go: {move_s: 1.0}}"), "scenario.movers.kinds", "missing (required key)");
  expect_rejected(movers("{kinds: [oscillating], speed_mps: 1.0}"), "scenario.movers.speed_mps", "unknown key");
  expect_rejected(movers("[oscillating]"), "scenario.movers", "wrong type: expected a map of keys");
  for (const char* bad : {"0", "-1", "0.0001"})
    expect_rejected(movers(std::string("{kinds: [stop_and_go], stop_and_go: {move_s: ") + bad + "}}"),
                    "scenario.movers.stop_and_go.move_s", "out of range: got " + std::string(bad));
  for (const char* bad : {".nan", "-.inf", "1e999"})
    expect_rejected(movers(std::string("{kinds: [stop_and_go], stop_and_go: {stop_s: ") + bad + "}}"),
                    "scenario.movers.stop_and_go.stop_s", "not a finite number");
  expect_rejected(movers("{kinds: [stop_and_go], stop_and_go: {move_s: 1, pause_s: 1}}"),
                  "scenario.movers.stop_and_go.pause_s", "unknown key");
  // A stretch must last a frame at least (0.04 s is 0.4 frames at 10 Hz)...
  expect_rejected(movers("{kinds: [stop_and_go], stop_and_go: {stop_s: 0.04}}"), "scenario.movers.stop_and_go.stop_s",
                  "0.04 s is less than one frame at 10 Hz: make it at least 1 / rate_hz = 0.1 s");
  // ...when a mover uses it: a file may keep the stretches while no mover stops.
  EXPECT_NO_THROW(load_scenario_text(movers("{kinds: [constant_velocity], stop_and_go: {stop_s: 0.04}}")));
}

// Options built in code (or overridden after loading) meet the same checks.
TEST(SimScenario, MoverChecksOfCodeBuiltOptions) {
  auto problems_at = [](const ScenarioOptions& o, const std::string& key) {
    std::string all;
    for (const Problem& p : check_scenario(o))
      if (p.key == key) all += p.what + ";";
    return all;
  };
  ScenarioOptions o = load_scenario_text(kBase);
  ASSERT_TRUE(check_scenario(o).empty());
  o.movers.kinds.clear();
  EXPECT_NE(problems_at(o, "movers.kinds").find("must list 1 to 64 kinds"), std::string::npos);
  o.movers.kinds = {MotionKind::kConstantVelocity, MotionKind::kStatic};
  EXPECT_NE(problems_at(o, "movers.kinds[1]").find("static is not a mover kind"), std::string::npos);
  o.movers.kinds = {MotionKind::kStopAndGo};
  o.movers.stop_and_go.move_s = std::nan("");
  EXPECT_NE(problems_at(o, "movers.stop_and_go.move_s").find("must be in (0, 1e+06] s, got nan"), std::string::npos);
  o.movers.stop_and_go.move_s = 2.0;
  EXPECT_TRUE(check_scenario(o).empty());
  o.rate_hz = 0.2;  // a rate override can make a stretch shorter than a frame: 2 s is 0.4 frames
  EXPECT_NE(problems_at(o, "movers.stop_and_go.move_s").find("less than one frame at 0.2 Hz"), std::string::npos);
}

TEST(SimScenario, MoversAreEchoedWhenGivenAndDescribed) {
  auto effective = [](const std::string& text) {
    config::Document doc = config::Document::from_string(text, "test.yaml");
    ScenarioOptions o;
    doc.allow_sections();
    doc.section("scenario", [&](config::Reader& r) { parse(r, &o); });
    doc.finish();
    return YAML::Load(doc.effective_yaml());
  };
  // Absent, the effective config says nothing of movers (results of the default
  // scenario record the same configuration as before the kinds existed).
  EXPECT_FALSE(effective(kBase)["scenario"]["movers"].IsDefined());
  const std::string mixed_text = with(
      "  reversal_period_frames: 20\n",
      "  reversal_period_frames: 20\n  movers: {kinds: [oscillating, constant_velocity, stop_and_go]}\n");
  const YAML::Node eff = effective(mixed_text)["scenario"]["movers"];
  ASSERT_TRUE(eff["kinds"].IsSequence());
  EXPECT_EQ(eff["kinds"].size(), 3u);
  EXPECT_EQ(eff["kinds"][2].as<std::string>(), "stop_and_go");
  // The start-up summary names the kinds with their counts (20 % of 72: 14 movers).
  EXPECT_NE(describe(load_scenario_text(kBase)).find("  movers: 14 oscillating\n"), std::string::npos)
      << describe(load_scenario_text(kBase));
  const std::string d = describe(load_scenario_text(mixed_text));
  EXPECT_NE(d.find("  movers: 5 oscillating, 5 constant_velocity, 4 stop_and_go (kinds [oscillating, "
                   "constant_velocity, stop_and_go] in turn over the moving ids)\n"),
            std::string::npos)
      << d;
  EXPECT_NE(d.find("    stop_and_go: moving 3 s (30 frames), standing still 3 s (30 frames)"), std::string::npos)
      << d;
}

}  // namespace
}  // namespace elaslam::sim

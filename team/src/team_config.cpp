// SPDX-License-Identifier: Apache-2.0
#include "elaslam/team/team_config.hpp"

#include <cmath>

namespace elaslam {

std::string check_team(const TeamConfig& c) {
  const double D2 = c.scenario.sensor.max_range_m();
  if (std::fabs(c.robot.sensor_range - D2) > 1e-6 * (1.0 + D2))
    return "robot.ela.sensor_range_m (" + std::to_string(c.robot.sensor_range) +
           ") must equal scenario.sensor.fov_diameter_m / 2 (" + std::to_string(D2) +
           "): the robots must know their own field of view";
  if (c.scenario.sensor.max_observations > c.robot.max_observations)
    return "scenario.sensor.max_observations (" + std::to_string(c.scenario.sensor.max_observations) +
           ") exceeds robot.filter.max_observations (" + std::to_string(c.robot.max_observations) +
           "): the robots would refuse the fullest frames";
  if (c.scenario.landmarks.count > c.robot.ekf.max_landmark_id)
    return "scenario.landmarks.count exceeds robot.filter.max_landmark_id";
  if (c.scenario.landmarks.count > c.main.max_landmark_id) return "scenario.landmarks.count exceeds main.max_landmark_id";
  if (c.main.max_landmark_id < c.robot.ekf.max_landmark_id)
    return "main.max_landmark_id (" + std::to_string(c.main.max_landmark_id) + ") is smaller than robot.filter.max_landmark_id (" +
           std::to_string(c.robot.ekf.max_landmark_id) + "): main_robot would refuse every event about the ids between";
  for (const auto& r : c.scenario.robots)
    if (!c.robot.limits.in_team(r.id) || !c.main.limits.in_team(r.id))
      return "scenario robot " + std::to_string(r.id) + " is not in robot.limits.team (" + team_text(c.robot.limits.team_mask) +
             ") and main.limits.team (" + team_text(c.main.limits.team_mask) + ")";
  return "";
}

void read_robot_and_main(config::Document& doc, RobotOptions* robot, GlobalMapOptions* main) {
  doc.section("robot", [&](config::Reader& r) { parse(r, robot); });
  doc.section("main", [&](config::Reader& r) { parse(r, main); });
  doc.allow_sections();
  doc.finish();
}

TeamConfig load_team_config(const std::string& path) {
  config::Document doc = config::Document::from_file(path);
  TeamConfig c;
  doc.section("scenario", [&](config::Reader& r) { sim::parse(r, &c.scenario); });
  read_robot_and_main(doc, &c.robot, &c.main);
  const std::string problem = check_team(c);
  if (!problem.empty()) throw config::ConfigError(path, {problem});
  c.effective_yaml = doc.effective_yaml();
  c.source = path;
  return c;
}

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
#include "elaslam/simulator/messages.hpp"

#include <vector>

#include <yaml-cpp/yaml.h>

#include "elaslam/common/cli.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/common/run_info.hpp"

namespace elaslam::sim {

void to_message(const SensorFrame& f, std::int64_t utime, elaslam::sensor_frame_t* out) {
  elaslam::sensor_frame_t& m = *out;
  m.utime = utime;
  m.frame = f.frame;
  m.robot_id = static_cast<std::int16_t>(f.robot_id);
  m.odom_x = f.odometer.x;
  m.odom_y = f.odometer.y;
  m.odom_theta = f.odometer.theta;
  m.odom_var_trans_per_m = f.odometry_noise.var_trans_per_m;
  m.odom_var_rot_per_rad = f.odometry_noise.var_rot_per_rad;
  m.odom_var_rot_per_m = f.odometry_noise.var_rot_per_m;
  contract::set_count(&m.obs, &m.num_obs, f.num_obs);  // <= scenario.sensor.max_observations (Sensor::observe)
  for (int i = 0; i < f.num_obs; ++i) {
    const Observation& z = f.obs[static_cast<std::size_t>(i)];
    range_bearing_t& o = m.obs[static_cast<std::size_t>(i)];
    o.landmark_id = z.landmark_id;
    o.range = z.range_m;
    o.bearing = z.bearing_rad;
  }
}

elaslam::sensor_frame_t to_message(const SensorFrame& f, std::int64_t utime) {
  elaslam::sensor_frame_t m{};
  to_message(f, utime, &m);
  return m;
}

elaslam::ground_truth_t to_message(const World& w, std::int64_t utime) {
  elaslam::ground_truth_t m{};
  to_message(w, utime, &m);
  return m;
}

void to_message(const World& w, std::int64_t utime, elaslam::ground_truth_t* m) {
  m->utime = utime;
  m->frame = w.frame();
  // The counts fit: check_scenario bounds robots by kMaxRobots and landmarks by
  // kMaxWorldLandmarks.
  contract::set_count(&m->robot_ids, &m->num_robots, w.num_robots());
  contract::set_count(&m->robots, &m->num_robots, w.num_robots());
  for (int r = 0; r < w.num_robots(); ++r) {
    const Pose2& T = w.robot_pose(r);
    const auto k = static_cast<std::size_t>(r);
    m->robot_ids[k] = static_cast<std::int16_t>(w.options().robots[k].id);
    m->robots[k].x = T.x;
    m->robots[k].y = T.y;
    m->robots[k].theta = T.theta;
  }
  contract::set_count(&m->landmarks, &m->num_landmarks, w.num_landmarks());
  const auto& p = w.landmark_positions();
  for (int i = 0; i < w.num_landmarks(); ++i) {
    auto& l = m->landmarks[static_cast<std::size_t>(i)];
    l.id = i;
    l.x = p[static_cast<std::size_t>(i)].x();
    l.y = p[static_cast<std::size_t>(i)].y();
    l.moving = w.is_moving(i);
  }
}

}  // namespace elaslam::sim

namespace elaslam::sim {

elaslam::run_info_t to_run_info(const ScenarioOptions& o, const std::string& scenario, const std::string& effective_yaml,
                                const std::string& mode, std::int64_t utime) {
  std::vector<int> ids;
  for (const auto& r : o.robots) ids.push_back(r.id);  // <= kMaxRobots: check_scenario
  elaslam::run_info_t m = run_info_start("simulator", ids);
  m.utime = utime;
  m.scenario = scenario;
  m.mode = mode;
  m.seed = o.seed;
  m.dynamism_percent = o.dynamism_percent;
  m.landmark_speed_mps = o.landmark_speed_mps;
  m.rate_hz = o.rate_hz;
  m.frames = o.frames;
  m.config_yaml = config::edit_yaml(effective_yaml, [&o](YAML::Node& root) {  // the overrides, recorded
    YAML::Node sc = root["scenario"];
    sc["frames"] = o.frames;
    sc["rate_hz"] = o.rate_hz;
    sc["seed"] = o.seed;
    sc["dynamism_percent"] = o.dynamism_percent;
    sc["landmark_speed_mps"] = o.landmark_speed_mps;
  });
  return m;
}

}  // namespace elaslam::sim

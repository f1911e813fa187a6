#include "elaslam/simulator/messages.hpp"

namespace elaslam::sim {

elaslam::sensor_frame_t to_message(const SensorFrame& f, std::int64_t utime) {
  elaslam::sensor_frame_t m{};
  m.utime = utime;
  m.frame = f.frame;
  m.robot_id = static_cast<std::int16_t>(f.robot_id);
  m.odom_x = f.odometer.x;
  m.odom_y = f.odometer.y;
  m.odom_theta = f.odometer.theta;
  m.odom_var_trans_per_m = f.odometry_noise.var_trans_per_m;
  m.odom_var_rot_per_rad = f.odometry_noise.var_rot_per_rad;
  m.odom_var_rot_per_m = f.odometry_noise.var_rot_per_m;
  m.num_obs = static_cast<std::int16_t>(f.num_obs);  // <= 64 by construction (Sensor::observe)
  for (int i = 0; i < f.num_obs; ++i) {
    const Observation& z = f.obs[static_cast<std::size_t>(i)];
    m.obs[i].landmark_id = z.landmark_id;
    m.obs[i].range = z.range_m;
    m.obs[i].bearing = z.bearing_rad;
  }
  return m;
}

elaslam::ground_truth_t to_message(const World& w, std::int64_t utime) {
  elaslam::ground_truth_t m{};
  m.utime = utime;
  m.frame = w.frame();
  // Capacities (8 robots, 256 landmarks) are enforced by the scenario's ranges.
  m.num_robots = static_cast<std::int16_t>(w.num_robots());
  for (int r = 0; r < w.num_robots(); ++r) {
    const Pose2& T = w.robot_pose(r);
    m.robot_ids[r] = static_cast<std::int16_t>(w.options().robots[static_cast<std::size_t>(r)].id);
    m.robots[r].x = T.x;
    m.robots[r].y = T.y;
    m.robots[r].theta = T.theta;
  }
  m.num_landmarks = static_cast<std::int16_t>(w.num_landmarks());
  const auto& p = w.landmark_positions();
  for (int i = 0; i < w.num_landmarks(); ++i) {
    m.landmarks[i].id = i;
    m.landmarks[i].x = p[static_cast<std::size_t>(i)].x();
    m.landmarks[i].y = p[static_cast<std::size_t>(i)].y();
    m.landmarks[i].moving = w.is_moving(i);
  }
  return m;
}

}  // namespace elaslam::sim

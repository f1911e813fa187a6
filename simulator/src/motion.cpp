#include "elaslam/simulator/motion.hpp"

#include <algorithm>
#include <cmath>

namespace elaslam::sim {

Pose2 path_pose(const RobotPathOptions& path, double t_s) {
  const double arc_m = std::min(path.speed_mps * std::max(t_s, 0.0), kPi * path.radius_m);
  const double sign = path.ccw ? 1.0 : -1.0;
  const double phi = deg2rad(path.start_angle_deg) + sign * arc_m / path.radius_m;  // polar angle [rad]
  Pose2 T_WB;
  T_WB.x = path.center_x_m + path.radius_m * std::cos(phi);
  T_WB.y = path.center_y_m + path.radius_m * std::sin(phi);
  T_WB.theta = wrap_angle(phi + sign * 0.5 * kPi);  // tangent, direction of travel
  return T_WB;
}

Eigen::Vector2d direction_vector(int index) {
  switch (index) {
    case 0: return {1.0, 0.0};
    case 1: return {-1.0, 0.0};
    case 2: return {0.0, 1.0};
    default: return {0.0, -1.0};
  }
}

namespace {
// Mirror coordinate v back into [lo, hi]; flips *d when it did. At most a few
// passes: check_scenario keeps the step below the world size.
bool reflect(double* v, double* d, double lo, double hi) {
  bool reflected = false;
  for (int i = 0; i < 4 && (*v < lo || *v > hi); ++i) {
    *v = (*v > hi) ? 2.0 * hi - *v : 2.0 * lo - *v;
    *d = -*d;
    reflected = true;
  }
  *v = std::clamp(*v, lo, hi);
  return reflected;
}
}  // namespace

bool advance_landmark(Eigen::Vector2d* p_LinW, Eigen::Vector2d* dir, double step_m, const WorldBounds& world) {
  *p_LinW += step_m * *dir;
  const bool rx = reflect(&p_LinW->x(), &dir->x(), world.x_min_m, world.x_max_m);
  const bool ry = reflect(&p_LinW->y(), &dir->y(), world.y_min_m, world.y_max_m);
  return rx || ry;
}

Eigen::Vector3d increment_variances(const Pose2& u, const OdometryOptions& o) {
  const double d = std::hypot(u.x, u.y);
  const double v_t = o.var_trans_per_m * d;
  const double v_r = o.var_rot_per_rad * std::abs(u.theta) + o.var_rot_per_m * d;
  return {v_t, v_t, v_r};
}

Pose2 noisy_increment(const Pose2& u, const OdometryOptions& o, Rng* rng) {
  const Eigen::Vector3d var = increment_variances(u, o);
  // Draw all three first: the stream advances by the same amount every frame.
  const double n_x = rng->normal(), n_y = rng->normal(), n_t = rng->normal();
  Pose2 noisy;
  noisy.x = u.x + std::sqrt(var.x()) * n_x;
  noisy.y = u.y + std::sqrt(var.y()) * n_y;
  noisy.theta = u.theta + std::sqrt(var.z()) * n_t;
  return noisy;
}

}  // namespace elaslam::sim

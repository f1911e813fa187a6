// SPDX-License-Identifier: Apache-2.0
#include "elaslam/simulator/motion.hpp"

#include <algorithm>
#include <cmath>

namespace elaslam::sim {

namespace {
// The semicircle alone: the pose at arc length arc_m [m] from the start point.
Pose2 on_semicircle(const RobotPathOptions& path, double arc_m) {
  const double sign = path.ccw ? 1.0 : -1.0;
  const double phi = deg2rad(path.start_angle_deg) + sign * arc_m / path.radius_m;  // polar angle [rad]
  Pose2 T_WB;
  T_WB.x = path.center_x_m + path.radius_m * std::cos(phi);
  T_WB.y = path.center_y_m + path.radius_m * std::sin(phi);
  T_WB.theta = wrap_angle(phi + sign * 0.5 * kPi);  // tangent, direction of travel
  return T_WB;
}

double arc_at(const RobotPathOptions& path, double drive_s) {
  return std::min(path.speed_mps * drive_s, kPi * path.radius_m);
}
}  // namespace

double drive_time(const RobotPathOptions& path, double t_s) {
  const double t = std::max(t_s, 0.0);
  const SpinOptions& spin = path.spin;
  if (!(spin.duration_s > 0.0) || t <= spin.start_s) return t;
  return t >= spin.start_s + spin.duration_s ? t - spin.duration_s : spin.start_s;
}

Pose2 path_pose(const RobotPathOptions& path, double t_s) {
  const Pose2 T_WB = on_semicircle(path, arc_at(path, drive_time(path, t_s)));
  const SpinOptions& spin = path.spin;
  if (!(spin.duration_s > 0.0) || t_s <= spin.start_s) return T_WB;
  // P: where the robot turns in place; it has turned by `turned` so far.
  const Pose2 P = on_semicircle(path, arc_at(path, spin.start_s));
  const double turned = deg2rad(spin.turn_deg) * std::min((t_s - spin.start_s) / spin.duration_s, 1.0);
  if (t_s < spin.start_s + spin.duration_s) return {P.x, P.y, wrap_angle(P.theta + turned)};  // exactly in place
  // Afterwards: the rest of the semicircle, seen from P, rotated by the turn about P.
  return compose(P, compose(Pose2{0.0, 0.0, turned}, between(P, T_WB)));
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

// Mirror a landmark that stepped from `from` into the empty region back out through
// the side it came in by, flipping its direction's component normal to that side.
// Moves are axis-aligned, so one coordinate changed. A few passes with the world's
// border in between (a gap narrower than a step); then it stops on the side itself.
bool keep_out(const Eigen::Vector2d& from, Eigen::Vector2d* p, Eigen::Vector2d* dir, const EmptyRegion& e,
              const WorldBounds& world) {
  if (!e.contains(p->x(), p->y())) return false;
  const bool along_x = std::abs(dir->x()) >= std::abs(dir->y());
  double& v = along_x ? p->x() : p->y();
  double& d = along_x ? dir->x() : dir->y();
  const double lo = along_x ? e.x_min_m : e.y_min_m, hi = along_x ? e.x_max_m : e.y_max_m;
  const double w_lo = along_x ? world.x_min_m : world.y_min_m, w_hi = along_x ? world.x_max_m : world.y_max_m;
  const double came = along_x ? from.x() : from.y();
  const double side = came <= lo ? lo : came >= hi ? hi : (v - lo <= hi - v ? lo : hi);
  for (int i = 0; i < 4 && e.contains(p->x(), p->y()); ++i) {
    v = 2.0 * side - v;
    d = -d;
    reflect(&v, &d, w_lo, w_hi);
  }
  if (e.contains(p->x(), p->y())) v = side;
  return true;
}
}  // namespace

bool advance_landmark(Eigen::Vector2d* p_LinW, Eigen::Vector2d* dir, double step_m, const WorldBounds& world,
                      const EmptyRegion& empty) {
  const Eigen::Vector2d from = *p_LinW;
  *p_LinW += step_m * *dir;
  const bool rx = reflect(&p_LinW->x(), &dir->x(), world.x_min_m, world.x_max_m);
  const bool ry = reflect(&p_LinW->y(), &dir->y(), world.y_min_m, world.y_max_m);
  const bool re = keep_out(from, p_LinW, dir, empty, world);
  return rx || ry || re;
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

Pose2 reported_increment(const Pose2& u_true, const OdometerError& e, double dt_s) {
  return {u_true.x / e.speed_scale, u_true.y / e.speed_scale,
          (u_true.theta - e.turn_bias_rad_s * dt_s) / e.turn_scale};
}

Pose2 true_increment(const Pose2& u_reported, const OdometerError& e, double dt_s) {
  return {e.speed_scale * u_reported.x, e.speed_scale * u_reported.y,
          e.turn_scale * u_reported.theta + e.turn_bias_rad_s * dt_s};
}

}  // namespace elaslam::sim

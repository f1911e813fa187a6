// SPDX-License-Identifier: Apache-2.0
// Motion and observation models (paper eqs 3, 6, 7, 13, 15) and the odometer's
// calibration. Pure functions; the Jacobians are analytic and checked
// against central differences in tests/robot_node/test_models.cpp.
#include "elaslam/robot_node/models.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/LU>

namespace elaslam {

double mahalanobis2(const Eigen::Vector2d& r, const Eigen::Matrix2d& C) {
  const double det = C(0, 0) * C(1, 1) - C(0, 1) * C(1, 0);
  if (!(det > 0.0) || !(C(0, 0) > 0.0)) return std::numeric_limits<double>::infinity();
  const Eigen::Matrix2d inv = (Eigen::Matrix2d() << C(1, 1), -C(0, 1), -C(1, 0), C(0, 0)).finished() / det;
  return r.dot(inv * r);
}

namespace {
// Variance floor [m^2 or rad^2]: keeps U positive definite for a robot standing
// still (zero increment), far below any real odometry noise.
constexpr double kMinOdometryVariance = 1e-12;
// Below this range [m] the bearing of a landmark is undefined (it sits on the
// robot centre) and the 1/r, 1/r^2 Jacobian terms blow up.
constexpr double kMinObservableRange = 1e-12;
}  // namespace

Pose2 motion(const Pose2& pose, const Pose2& increment, Eigen::Matrix3d* F_x,
             Eigen::Matrix3d* F_u) {
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  if (F_x != nullptr) {
    // d(R (+) u)/dR: the increment's translation, rotated into W, swings with theta.
    *F_x << 1.0, 0.0, -s * increment.x - c * increment.y,  //
        0.0, 1.0, c * increment.x - s * increment.y,       //
        0.0, 0.0, 1.0;
  }
  if (F_u != nullptr) {
    // d(R (+) u)/du: the increment is expressed in B, so it enters rotated by theta.
    *F_u << c, -s, 0.0,  //
        s, c, 0.0,       //
        0.0, 0.0, 1.0;
  }
  return compose(pose, increment);  // eq 3 (compose wraps the new heading)
}

Pose2 calibrated_increment(const Pose2& reported, const OdometryCalibration& c, double dt, Eigen::Matrix3d* J_c,
                           Eigen::Matrix3d* J_r) {
  if (J_c != nullptr) {
    // Columns s_w, s_v, b: the scales multiply their own components, the bias
    // integrates over the step.
    *J_c << 0.0, reported.x, 0.0,  //
        0.0, reported.y, 0.0,      //
        reported.theta, 0.0, dt;
  }
  if (J_r != nullptr) *J_r = Eigen::Vector3d(c.speed_scale, c.speed_scale, c.turn_scale).asDiagonal();
  // Not wrapped: compose() wraps the heading it produces.
  return {c.speed_scale * reported.x, c.speed_scale * reported.y, c.turn_scale * reported.theta + c.turn_bias * dt};
}

Eigen::Matrix3d odometry_covariance(const Pose2& increment, const OdometryNoise& noise) {
  const double distance = std::hypot(increment.x, increment.y);  // [m]
  const double var_trans = std::max(noise.var_trans_per_m * distance, kMinOdometryVariance);
  const double var_rot =
      std::max(noise.var_rot_per_rad * std::abs(increment.theta) + noise.var_rot_per_m * distance,
               kMinOdometryVariance);
  return Eigen::Vector3d(var_trans, var_trans, var_rot).asDiagonal();
}

Eigen::Matrix3d gap_odometry_covariance(const Pose2& increment, int steps, const OdometryNoise& noise) {
  const int k = std::min(steps, kMaxGapSteps);
  if (k <= 1) return odometry_covariance(increment, noise);
  // k equal steps u (turn th / k each) compose to sum_{i<k} R(i th / k) t_u: solve
  // M t_u = t for the step's translation.
  const double turn = increment.theta / k;
  Eigen::Matrix2d M = Eigen::Matrix2d::Zero();
  for (int i = 0; i < k; ++i) M += rotation(i * turn);
  const Eigen::FullPivLU<Eigen::Matrix2d> lu(M);
  if (!lu.isInvertible()) return odometry_covariance(increment, noise);
  const Eigen::Vector2d t = lu.solve(Eigen::Vector2d(increment.x, increment.y));
  const Pose2 step{t.x(), t.y(), turn};
  const Eigen::Matrix3d U = odometry_covariance(step, noise);
  Eigen::Matrix3d P = Eigen::Matrix3d::Zero(), F_x, F_u;
  Pose2 at;  // the path so far, in the increment's coordinates
  for (int i = 0; i < k; ++i) {
    at = motion(at, step, &F_x, &F_u);
    P = F_x * P * F_x.transpose() + F_u * U * F_u.transpose();
  }
  return 0.5 * (P + P.transpose());
}

Eigen::Matrix3d dead_reckoning_cov(const Eigen::Matrix3d& P0, int steps, double step_m, double turn_rad,
                                   const OdometryNoise& noise) {
  // The noise of each increment counts its turn; the Jacobians are those of the
  // straight path (heading 0 throughout).
  const Eigen::Matrix3d U = odometry_covariance({step_m, 0.0, turn_rad}, noise);
  Eigen::Matrix3d F_x, F_u;
  motion({0.0, 0.0, 0.0}, {step_m, 0.0, 0.0}, &F_x, &F_u);
  const Eigen::Matrix3d Q = F_u * U * F_u.transpose();
  // P_k = F^k P0 F^kT + sum_{i<k} F^i Q F^iT, in closed form (O(1) for any k): on the
  // straight path F = I + N with N nilpotent (only N(y, th) = step_m), so
  // F^i = I + i N and F^i X F^iT = X + i (N X + X N^T) + i^2 N X N^T.
  const double k = std::max(0, std::min(steps, kMaxDeadReckoningSteps));
  const Eigen::Matrix3d N = F_x - Eigen::Matrix3d::Identity();
  const double s1 = k * (k - 1.0) / 2.0, s2 = (k - 1.0) * k * (2.0 * k - 1.0) / 6.0;  // sum of i, i^2 for i < k
  const Eigen::Matrix3d P = P0 + k * (N * P0 + P0 * N.transpose()) + k * k * (N * P0 * N.transpose()) + k * Q +
                            s1 * (N * Q + Q * N.transpose()) + s2 * (N * Q * N.transpose());
  // Largest eigenvalue of the symmetric 2x2 position block.
  const double a = P(0, 0), c = P(1, 1), b = 0.5 * (P(0, 1) + P(1, 0));
  const double lambda = 0.5 * (a + c) + std::sqrt(0.25 * (a - c) * (a - c) + b * b);
  return Eigen::Vector3d(lambda, lambda, P(2, 2)).asDiagonal();
}

RangeBearing observe(const Pose2& pose, const Eigen::Vector2d& p_LinW,
                     Eigen::Matrix<double, 2, 3>* H_x, Eigen::Matrix2d* H_l) {
  const double dx = p_LinW.x() - pose.x, dy = p_LinW.y() - pose.y;  // [m], in W
  const double q = dx * dx + dy * dy;
  const double r = std::sqrt(q);
  RangeBearing z;
  // The bearing is returned in [-pi, pi) as RangeBearing promises; the filter
  // wraps the innovation again, where it matters.
  z.bearing = wrap_angle(std::atan2(dy, dx) - pose.theta);
  if (r < kMinObservableRange) {
    // Singular point: bearing undefined, derivatives unbounded. Report range 0 and
    // zero Jacobians so that a caller never sees NaN; the filter then applies no
    // correction through this observation.
    z.range = 0.0;
    if (H_x != nullptr) H_x->setZero();
    if (H_l != nullptr) H_l->setZero();
    return z;
  }
  z.range = r;
  // eq 13, the landmark part: d(r, b)/d(l).
  Eigen::Matrix2d J_l;
  J_l << dx / r, dy / r,  //
      -dy / q, dx / q;
  if (H_l != nullptr) *H_l = J_l;
  if (H_x != nullptr) {
    // Moving the robot by dt moves the landmark by -dt in relative terms; turning
    // the robot by dtheta moves the bearing by -dtheta.
    H_x->leftCols<2>() = -J_l;
    H_x->col(2) << 0.0, -1.0;
  }
  return z;
}

Eigen::Vector2d inverse_observe(const Pose2& pose, const RangeBearing& z,
                                Eigen::Matrix<double, 2, 3>* G_x, Eigen::Matrix2d* G_z) {
  const double a = pose.theta + z.bearing;  // direction of the landmark in W [rad]
  const double c = std::cos(a), s = std::sin(a);
  if (G_x != nullptr) {
    *G_x << 1.0, 0.0, -z.range * s,  //
        0.0, 1.0, z.range * c;
  }
  if (G_z != nullptr) {
    *G_z << c, -z.range * s,  //
        s, z.range * c;
  }
  return {pose.x + z.range * c, pose.y + z.range * s};  // eq 15
}

Eigen::Vector2d observation_to_local(const RangeBearing& z, Eigen::Matrix2d* J_z) {
  const double c = std::cos(z.bearing), s = std::sin(z.bearing);
  if (J_z != nullptr) {
    *J_z << c, -z.range * s,  //
        s, z.range * c;
  }
  return {z.range * c, z.range * s};  // p_LinB [m]
}

}  // namespace elaslam

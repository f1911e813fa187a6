// SPDX-License-Identifier: Apache-2.0
// The one rigid motion of the plane that best carries a robot's landmark estimates
// onto the team's (docs/adr/0029-gauge-test.md). A robot that drove
// through a stretch without landmarks on a biased odometer maps everything it sees
// afterwards from a rotated, shifted pose: its map and pose are a rigid copy of the
// truth, consistent in themselves, and no observation of its own can show it (a
// rigid motion of the whole state leaves every range and bearing unchanged: the
// gauge of SLAM). The team's map, in the world's gauge, can. Robot::apply_team_map
// uses the fit to tell that case ("most shared landmarks disagree before the motion,
// most agree after it") and to move the robot back (EkfSlam::apply_rigid_motion).
//
// The fit: T = (phi, t) minimising sum_i r_i^T C_i^-1 r_i, r_i = R(phi) a_i + t - b_i,
// C_i = R(phi) A_i R(phi)^T + B_i, with a_i, A_i the robot's estimate of landmark i
// and b_i, B_i the team's (cross-correlations between landmarks ignored). Started
// from the closed-form weighted Procrustes solution (scalar weights 2 / tr(A_i +
// B_i): Horn's / Umeyama's centroid and cross-covariance), then Gauss-Newton with
// the full 2x2 weights. The covariance of (phi, t) is the inverse of the normal
// matrix at the solution. No allocation: the caller owns the pairs.
#pragma once

#include <Eigen/Core>

namespace elaslam {

/// One landmark held by both: the robot's estimate (a, A) and the team's (b, B) [m, m^2].
struct PointPair {
  Eigen::Vector2d a = Eigen::Vector2d::Zero();
  Eigen::Matrix2d A = Eigen::Matrix2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  Eigen::Matrix2d B = Eigen::Matrix2d::Zero();
};

/// p -> R(rotation) p + translation.
struct RigidMotion {
  double rotation = 0.0;                                  // [rad], in [-pi, pi)
  Eigen::Vector2d translation = Eigen::Vector2d::Zero();  // [m]
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();          // of (rotation, tx, ty)
  double cost = 0.0;                                      // sum of the pairs' d2 after the motion
};

/// The motion for `n` pairs (n >= 2, else false). False too when the pairs do not
/// fix a rotation (every pair at one point) or a weight is not positive definite.
bool fit_rigid_motion(const PointPair* pairs, int n, RigidMotion* out);

/// The pair's d2 after the motion: r^T (R A R^T + B)^-1 r; +inf when singular.
double aligned_d2(const PointPair& p, const RigidMotion& T);

}  // namespace elaslam

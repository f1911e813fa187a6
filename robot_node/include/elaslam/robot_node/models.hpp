// SPDX-License-Identifier: Apache-2.0
// Motion and observation models of the planar EKF-SLAM, as pure functions that
// return a value and, only when asked, fixed-size Jacobians (GTSAM style).
// Frames: W world, B robot body. Paper eqs 3 and 6 (motion), 7 and 13 (observation),
// 15 (inverse observation).
#pragma once

#include <Eigen/Core>

#include "elaslam/common/geometry.hpp"

namespace elaslam {

/// A range-bearing measurement of a point landmark from the robot centre.
struct RangeBearing {
  double range = 0.0;    // [m]
  double bearing = 0.0;  // [rad], robot frame, in [-pi, pi)
};

/// Odometry noise model (docs/design.md section 2, sensor_frame_t): variances grow with
/// the distance travelled and the angle turned.
struct OdometryNoise {
  double var_trans_per_m = 0.0;   // [m^2/m]   along and across the motion
  double var_rot_per_rad = 0.0;   // [rad^2/rad]
  double var_rot_per_m = 0.0;     // [rad^2/m]
};

/// The odometer's systematic error: the true increment of a step of dt
/// seconds whose odometer reports (dx_r, dy_r, dtheta_r), in B at the step start, is
///   dx = s_v dx_r,  dy = s_v dy_r,  dtheta = s_w dtheta_r + b dt.
/// The simulator produces the error with the same convention. Identity: 1, 1, 0.
struct OdometryCalibration {
  double turn_scale = 1.0;   // s_w: true turn / reported turn
  double speed_scale = 1.0;  // s_v: true distance / reported distance
  double turn_bias = 0.0;    // b [rad/s]: turn rate the odometer does not report
};

/// The true increment u(c) of a reported one over dt [s] (OdometryCalibration).
/// J_c = du/dc (3x3, rows x, y, theta of u; columns s_w, s_v, b) and
/// J_r = du/du_r = diag(s_v, s_v, s_w), when asked.
Pose2 calibrated_increment(const Pose2& reported, const OdometryCalibration& c, double dt,
                           Eigen::Matrix3d* J_c = nullptr, Eigen::Matrix3d* J_r = nullptr);

/// d2 = r^T C^-1 r for a 2x2 symmetric C; +inf when C is not positive definite.
double mahalanobis2(const Eigen::Vector2d& r, const Eigen::Matrix2d& C);

/// Motion f(R, u) (eq 3): the pose R_WB composed with the odometry increment u
/// (expressed in B at the start of the step). F_x = df/dR, F_u = df/du (eq 6).
Pose2 motion(const Pose2& pose, const Pose2& increment, Eigen::Matrix3d* F_x = nullptr,
             Eigen::Matrix3d* F_u = nullptr);

/// Covariance U of an odometry increment (in the increment's own coordinates).
/// A small floor keeps U positive definite for a standing robot.
Eigen::Matrix3d odometry_covariance(const Pose2& increment, const OdometryNoise& noise);

/// Covariance of an odometer increment that spans `steps` frames (frames were
/// missed: a restart, a radio outage): the increment taken as `steps` equal steps of
/// a constant-curvature arc, each with its own noise (odometry_covariance), compounded
/// in the increment's coordinates (eq 5 per step). A heading error early in the gap
/// swings the rest of the path, and the arc is longer than its chord: one noise for
/// the whole chord understates both. steps <= 1 (or an arc with no such split)
/// gives odometry_covariance(increment). steps is capped at kMaxGapSteps.
/// Allocates nothing.
constexpr int kMaxGapSteps = 1000;
Eigen::Matrix3d gap_odometry_covariance(const Pose2& increment, int steps, const OdometryNoise& noise);

/// The pose covariance of dead reckoning from a start known to within P0, after
/// `steps` odometer increments of step_m [m] and turn_rad [rad] each: eq 5 applied
/// `steps` times on a straight path (the lever arm of a heading error is largest
/// there), the x, y block then made isotropic with its largest eigenvalue (the
/// direction of travel is unknown) and the cross terms dropped. The prior of a
/// robot whose first frame is not frame 0 (docs/adr/0023-late-start-prior.md).
/// steps is capped at kMaxDeadReckoningSteps. Allocates nothing.
constexpr int kMaxDeadReckoningSteps = 100000;
Eigen::Matrix3d dead_reckoning_cov(const Eigen::Matrix3d& P0, int steps, double step_m, double turn_rad,
                                   const OdometryNoise& noise);

/// Observation h(R, l) (eq 7): range and bearing of landmark p_LinW seen from R_WB.
/// H_x = dh/dR (2x3), H_l = dh/dl (2x2). Undefined (Jacobians set to zero, range 0)
/// when the landmark is at the robot centre.
RangeBearing observe(const Pose2& pose, const Eigen::Vector2d& p_LinW,
                     Eigen::Matrix<double, 2, 3>* H_x = nullptr, Eigen::Matrix2d* H_l = nullptr);

/// Inverse observation g(R, y) (eq 15): the world position of the landmark seen at
/// y from R_WB. G_x = dg/dR (2x3), G_z = dg/dy (2x2).
Eigen::Vector2d inverse_observe(const Pose2& pose, const RangeBearing& z,
                                Eigen::Matrix<double, 2, 3>* G_x = nullptr,
                                Eigen::Matrix2d* G_z = nullptr);

/// Local (robot-frame) position of an observation and dp/dz.
Eigen::Vector2d observation_to_local(const RangeBearing& z, Eigen::Matrix2d* J_z = nullptr);

}  // namespace elaslam

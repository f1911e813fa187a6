// SPDX-License-Identifier: Apache-2.0
// Ground-truth motion of robots and landmarks, and the odometer's noise.
// Frames: W world, B robot body.
#pragma once

#include <Eigen/Core>

#include "elaslam/common/geometry.hpp"
#include "elaslam/simulator/random.hpp"
#include "elaslam/simulator/scenario.hpp"

namespace elaslam::sim {

/// True pose T_WB of a robot at time t_s [s] after the start: on its circle at
/// arc length min(speed * t, pi * radius) from the start point (it stops at the
/// end of the semicircle), heading along the tangent in the direction of travel.
/// With a spin (path.spin.duration_s > 0) the robot stands still from spin.start_s
/// for spin.duration_s, turning by spin.turn_deg at a constant rate, and the rest
/// of its path is the rest of the semicircle rotated by turn_deg about the point
/// where it turned (it drives on with the same speed and curvature); time spent
/// turning is not spent driving.
Pose2 path_pose(const RobotPathOptions& path, double t_s);

/// Time [s] a robot has driven (not turned in place) by time t_s [s].
double drive_time(const RobotPathOptions& path, double t_s);

/// The four directions of a moving landmark (paper section 4: front, back,
/// right, left), as unit vectors in W. index 0: +x, 1: -x, 2: +y, 3: -y.
Eigen::Vector2d direction_vector(int index);

/// Move a landmark by step_m [m] along dir (unit vector in W, along an axis). At a
/// world border the landmark is reflected: the overshoot is mirrored back inside
/// and the direction component normal to that border flips, so it keeps moving at
/// the same speed and stays inside. An enabled empty region reflects it the same
/// way at the side it came through, so it stays out. Returns true when a reflection
/// happened.
bool advance_landmark(Eigen::Vector2d* p_LinW, Eigen::Vector2d* dir, double step_m, const WorldBounds& world,
                      const EmptyRegion& empty = EmptyRegion{});

/// The odometer's report of a true increment u (in B at the step's start) over
/// dt_s [s], the inverse of OdometerError's convention:
/// (dx, dy) / speed_scale and (dtheta - turn_bias_rad_s * dt) / turn_scale.
Pose2 reported_increment(const Pose2& u_true, const OdometerError& e, double dt_s);

/// The true increment of a reported one, OdometerError's convention itself:
/// (speed_scale dx_r, speed_scale dy_r, turn_scale dtheta_r + turn_bias_rad_s dt).
Pose2 true_increment(const Pose2& u_reported, const OdometerError& e, double dt_s);

/// Variances of an odometry increment u (sensor_frame_t's model): with d = |(u.x, u.y)|,
/// var_along = var_across = var_trans_per_m * d, var_theta = var_rot_per_rad * |u.theta|
/// + var_rot_per_m * d.
Eigen::Vector3d increment_variances(const Pose2& u, const OdometryOptions& o);

/// u + n with n ~ N(0, diag(increment_variances(u))), drawn from rng (3 normals, always,
/// so that the stream position does not depend on the motion).
Pose2 noisy_increment(const Pose2& u, const OdometryOptions& o, Rng* rng);

}  // namespace elaslam::sim

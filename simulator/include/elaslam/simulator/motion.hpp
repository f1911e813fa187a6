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
Pose2 path_pose(const RobotPathOptions& path, double t_s);

/// The four directions of a moving landmark (paper section 4: front, back,
/// right, left), as unit vectors in W. index 0: +x, 1: -x, 2: +y, 3: -y.
Eigen::Vector2d direction_vector(int index);

/// Move a landmark by step_m [m] along dir (unit vector in W). At a world border
/// the landmark is reflected: the overshoot is mirrored back inside and the
/// direction component normal to that border flips, so it keeps moving at the
/// same speed and stays inside. Returns true when a reflection happened.
bool advance_landmark(Eigen::Vector2d* p_LinW, Eigen::Vector2d* dir, double step_m, const WorldBounds& world);

/// Variances of an odometry increment u (sensor_frame_t's model): with d = |(u.x, u.y)|,
/// var_along = var_across = var_trans_per_m * d, var_theta = var_rot_per_rad * |u.theta|
/// + var_rot_per_m * d.
Eigen::Vector3d increment_variances(const Pose2& u, const OdometryOptions& o);

/// u + n with n ~ N(0, diag(increment_variances(u))), drawn from rng (3 normals, always,
/// so that the stream position does not depend on the motion).
Pose2 noisy_increment(const Pose2& u, const OdometryOptions& o, Rng* rng);

}  // namespace elaslam::sim

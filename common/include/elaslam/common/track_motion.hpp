// SPDX-License-Identifier: Apache-2.0
// The constant-velocity motion of a track's state (p_x, p_y, v_x, v_y) in W, shared
// by the robots' track filter (robot_node/mover_track: its constant-velocity
// model) and main's prediction of the robots' tracks to a common time
// (main_robot/track_fusion: predict_track).
#pragma once

#include <Eigen/Core>

namespace elaslam {

/// The constant-velocity model's white acceleration by default [m / s^1.5]
/// (robot.tracking.cv_accel_sigma): a gentle change of speed, 0.2 m/s within a
/// second (docs/tracking.md).
constexpr double kDefaultCvAccelSigma = 0.2;

/// The transition over dt [s] of a mover of constant velocity driven by white
/// acceleration of standard deviation accel_sigma: x' = F x, noise Q, both per
/// axis, F = [[I, dt I], [0, I]], Q = q [[dt^3/3 I, dt^2/2 I], [dt^2/2 I, dt I]],
/// q = accel_sigma^2.
inline void constant_velocity_step(double dt, double accel_sigma, Eigen::Matrix4d* F, Eigen::Matrix4d* Q) {
  const double q = accel_sigma * accel_sigma, dt2 = dt * dt, dt3 = dt2 * dt;
  F->setIdentity();
  Q->setZero();
  for (int k = 0; k < 2; ++k) {
    (*F)(k, k + 2) = dt;
    (*Q)(k, k) = q * dt3 / 3;
    (*Q)(k, k + 2) = (*Q)(k + 2, k) = q * dt2 / 2;
    (*Q)(k + 2, k + 2) = q * dt;
  }
}

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// SE(2) helpers and angle wrapping. Frames: W (world), B (robot body), O (odometry).
#pragma once

#include <cmath>

#include <Eigen/Core>

namespace elaslam {

constexpr double kPi = 3.14159265358979323846;

/// Wrap an angle to [-pi, pi).
inline double wrap_angle(double a) {
  double w = std::fmod(a + kPi, 2.0 * kPi);
  if (w < 0.0) w += 2.0 * kPi;
  return w - kPi;
}

inline double deg2rad(double d) { return d * kPi / 180.0; }
inline double rad2deg(double r) { return r * 180.0 / kPi; }

/// A planar pose: position [m] and heading [rad] of a frame B in a frame A (T_AB).
struct Pose2 {
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;

  Eigen::Vector2d translation() const { return {x, y}; }
};

inline Eigen::Matrix2d rotation(double theta) {
  const double c = std::cos(theta), s = std::sin(theta);
  Eigen::Matrix2d R;
  R << c, -s, s, c;
  return R;
}

/// a (+) b: pose b expressed in a's frame, composed onto a.
inline Pose2 compose(const Pose2& a, const Pose2& b) {
  const double c = std::cos(a.theta), s = std::sin(a.theta);
  return {a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y, wrap_angle(a.theta + b.theta)};
}

/// (-)a: the inverse transform.
inline Pose2 inverse(const Pose2& a) {
  const double c = std::cos(a.theta), s = std::sin(a.theta);
  return {-c * a.x - s * a.y, s * a.x - c * a.y, wrap_angle(-a.theta)};
}

/// a (-) b = inverse(b) (+) a: the increment that takes b to a, in b's frame.
inline Pose2 between(const Pose2& b, const Pose2& a) { return compose(inverse(b), a); }

/// Point p given in frame B, returned in frame A, for the pose T_AB.
inline Eigen::Vector2d transform_from(const Pose2& T_AB, const Eigen::Vector2d& p_B) {
  return rotation(T_AB.theta) * p_B + T_AB.translation();
}

/// Point p given in frame A, returned in frame B, for the pose T_AB.
inline Eigen::Vector2d transform_to(const Pose2& T_AB, const Eigen::Vector2d& p_A) {
  return rotation(T_AB.theta).transpose() * (p_A - T_AB.translation());
}

}  // namespace elaslam

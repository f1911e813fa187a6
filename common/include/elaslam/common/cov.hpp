// SPDX-License-Identifier: Apache-2.0
// Covariances as the messages carry them (double cov[N][N], row-major: cov[r][c] is
// C(r, c)) to and from Eigen: 2x2 for a landmark's position (landmark_estimate_t,
// landmark_event_t, global_landmark_t), 3x3 for a pose (pose_estimate_t). Exact
// copies, no symmetrisation: the receivers' checks (limits.hpp, check_cov2) see what
// was sent. A track's 4x4 covariance travels as its upper triangle in floats
// (track_t, global_track_t: float cov[10]), symmetric by construction.
#pragma once

#include <cstddef>

#include <Eigen/Core>

namespace elaslam {

/// The message's covariance as an Eigen matrix.
template <std::size_t N>
Eigen::Matrix<double, static_cast<int>(N), static_cast<int>(N)> read_cov(const double (&c)[N][N]) {
  Eigen::Matrix<double, static_cast<int>(N), static_cast<int>(N)> C;
  for (std::size_t r = 0; r < N; ++r)
    for (std::size_t q = 0; q < N; ++q) C(static_cast<int>(r), static_cast<int>(q)) = c[r][q];
  return C;
}

/// Store `C` in the message's covariance.
template <std::size_t N>
void write_cov(double (&c)[N][N], const Eigen::Matrix<double, static_cast<int>(N), static_cast<int>(N)>& C) {
  for (std::size_t r = 0; r < N; ++r)
    for (std::size_t q = 0; q < N; ++q) c[r][q] = C(static_cast<int>(r), static_cast<int>(q));
}

/// A symmetric 4x4 covariance's upper triangle, row by row (xx, xy, xvx, xvy, yy,
/// yvx, yvy, vxvx, vxvy, vyvy), rounded to float: track_t.cov, global_track_t.cov.
inline void write_cov_upper(float (&c)[10], const Eigen::Matrix4d& C) {
  int k = 0;
  for (int r = 0; r < 4; ++r)
    for (int q = r; q < 4; ++q) c[k++] = static_cast<float>(C(r, q));
}

/// The symmetric 4x4 matrix of an upper triangle written by write_cov_upper.
inline Eigen::Matrix4d read_cov_upper(const float (&c)[10]) {
  Eigen::Matrix4d C;
  int k = 0;
  for (int r = 0; r < 4; ++r)
    for (int q = r; q < 4; ++q) C(r, q) = C(q, r) = static_cast<double>(c[k++]);
  return C;
}

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// Covariances as the messages carry them (double cov[N][N], row-major: cov[r][c] is
// C(r, c)) to and from Eigen: 2x2 for a landmark's position (landmark_estimate_t,
// landmark_event_t, global_landmark_t), 3x3 for a pose (pose_estimate_t). Exact
// copies, no symmetrisation: the receivers' checks (limits.hpp, check_cov2) see what
// was sent.
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

}  // namespace elaslam

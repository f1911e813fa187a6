// SPDX-License-Identifier: Apache-2.0
// Central-difference Jacobian checker for the models' analytic Jacobians
// (GTSAM's EXPECT_CORRECT_FACTOR_JACOBIANS in spirit). Header-only, test use.
#pragma once

#include <cmath>
#include <sstream>
#include <string>

#include <Eigen/Core>

#include "elaslam/common/geometry.hpp"

namespace elaslam::test {

template <int M, int N>
struct JacobianCheck {
  bool ok = false;
  double max_error = 0.0;                // max |analytic - numeric| / (1 + |numeric|)
  Eigen::Matrix<double, M, N> numeric;   // the central-difference estimate
  std::string message;                   // what differed, for the assertion output
};

/// Checks `analytic` = df/dx at `x` by central differences with step `step`.
/// Outputs flagged in `angle_outputs` (bit k for output k) are angles: their
/// differences are wrapped to [-pi, pi), so a value that crosses +-pi between the
/// two evaluations does not show up as a 2 pi jump.
/// `f` maps Eigen::Matrix<double, N, 1> to Eigen::Matrix<double, M, 1>.
template <class F, int M, int N>
JacobianCheck<M, N> check_jacobian(const F& f, const Eigen::Matrix<double, N, 1>& x,
                                   const Eigen::Matrix<double, M, N>& analytic,
                                   unsigned angle_outputs = 0u, double step = 1e-6,
                                   double tolerance = 1e-6) {
  JacobianCheck<M, N> result;
  for (int j = 0; j < N; ++j) {
    Eigen::Matrix<double, N, 1> xp = x, xm = x;
    xp(j) += step;
    xm(j) -= step;
    const Eigen::Matrix<double, M, 1> fp = f(xp), fm = f(xm);
    for (int i = 0; i < M; ++i) {
      double d = fp(i) - fm(i);
      if ((angle_outputs >> i) & 1u) d = wrap_angle(d);
      result.numeric(i, j) = d / (2.0 * step);
    }
  }
  const auto err = ((analytic - result.numeric).array().abs() /
                    (1.0 + result.numeric.array().abs()))
                       .eval();
  result.max_error = err.maxCoeff();
  // A NaN anywhere must fail the check, hence the negated comparison.
  result.ok = !(result.max_error > tolerance) && analytic.allFinite() &&
              result.numeric.allFinite();
  if (!result.ok) {
    std::ostringstream os;
    os << "Jacobian mismatch (max relative error " << result.max_error << " > " << tolerance
       << ")\nanalytic:\n" << analytic << "\nnumeric:\n" << result.numeric << "\nat x = "
       << x.transpose();
    result.message = os.str();
  }
  return result;
}

}  // namespace elaslam::test

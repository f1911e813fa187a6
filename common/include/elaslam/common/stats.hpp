// SPDX-License-Identifier: Apache-2.0
// Chi-square quantiles for gates. Computed once at start-up, never per frame.
#pragma once

namespace elaslam {

/// Regularised lower incomplete gamma P(a, x).
double gamma_p(double a, double x);

/// CDF of the chi-square distribution with `dof` degrees of freedom.
double chi2_cdf(double x, int dof);

/// Quantile of the chi-square distribution: the x with chi2_cdf(x, dof) == p.
/// dof >= 1, 0 < p < 1. Exact to ~1e-10 (bisection on the CDF).
double chi2_quantile(double p, int dof);

}  // namespace elaslam

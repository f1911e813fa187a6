#include <gtest/gtest.h>

#include <cmath>

#include "elaslam/common/stats.hpp"

namespace elaslam {
namespace {

// Reference values from standard chi-square tables.
TEST(Stats, Chi2QuantileMatchesTables) {
  EXPECT_NEAR(chi2_quantile(0.99, 2), -2.0 * std::log(0.01), 1e-9);  // closed form for 2 dof
  EXPECT_NEAR(chi2_quantile(0.95, 1), 3.841459, 1e-5);
  EXPECT_NEAR(chi2_quantile(0.95, 2), 5.991465, 1e-5);
  EXPECT_NEAR(chi2_quantile(0.99, 3), 11.344867, 1e-5);
  EXPECT_NEAR(chi2_quantile(0.025, 100), 74.2219, 1e-3);
  EXPECT_NEAR(chi2_quantile(0.975, 100), 129.5612, 1e-3);
}

TEST(Stats, Chi2CdfInvertsQuantile) {
  for (int dof : {1, 2, 3, 5, 30})
    for (double p : {0.01, 0.5, 0.9, 0.999}) EXPECT_NEAR(chi2_cdf(chi2_quantile(p, dof), dof), p, 1e-9);
}

}  // namespace
}  // namespace elaslam

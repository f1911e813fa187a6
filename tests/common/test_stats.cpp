// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "elaslam/common/histogram.hpp"
#include "elaslam/common/quantile.hpp"
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

// The project's one quantile convention: the nearest rank, ceil(q n)-th smallest.
TEST(Quantile, NearestRank) {
  EXPECT_EQ(quantile_rank(0.5, 100), 49u);   // the 50th of 100
  EXPECT_EQ(quantile_rank(0.99, 100), 98u);  // the 99th: not the maximum (0.99 * 100 is a hair above 99)
  EXPECT_EQ(quantile_rank(1.0, 100), 99u);
  EXPECT_EQ(quantile_rank(0.5, 1), 0u);
  EXPECT_EQ(quantile_rank(0.99, 3), 2u);
  EXPECT_EQ(quantile_rank(0.5, 4), 1u);
  std::vector<int> v{5, 1, 4, 2, 3};
  EXPECT_EQ(quantile(v, 0.5), 3);
  EXPECT_EQ(quantile(v, 1.0), 5);
  EXPECT_EQ(quantile(v, 0.01), 1);
  EXPECT_EQ(quantile(std::vector<int>{}, 0.5), 0);
}

TEST(Quantile, HistogramAgreesWithTheSampleQuantile) {
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> us(0, 3000);
  for (int n : {1, 2, 7, 100, 1001}) {
    DurationHistogram h;
    std::vector<std::int64_t> v;
    for (int i = 0; i < n; ++i) {
      v.push_back(us(rng));
      h.add(v.back());
    }
    for (double q : {0.01, 0.5, 0.9, 0.99, 1.0}) EXPECT_EQ(h.quantile(q), quantile(v, q)) << n << " " << q;
  }
}

}  // namespace
}  // namespace elaslam

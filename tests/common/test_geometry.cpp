// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <random>

#include "elaslam/common/cov.hpp"
#include "elaslam/common/geometry.hpp"

namespace elaslam {
namespace {

TEST(Geometry, WrapAngleRange) {
  EXPECT_DOUBLE_EQ(wrap_angle(0.0), 0.0);
  EXPECT_DOUBLE_EQ(wrap_angle(kPi), -kPi);  // [-pi, pi)
  EXPECT_DOUBLE_EQ(wrap_angle(-kPi), -kPi);
  EXPECT_NEAR(wrap_angle(3 * kPi + 0.1), -kPi + 0.1, 1e-12);
  EXPECT_NEAR(wrap_angle(-7.0), -7.0 + 2 * kPi, 1e-12);
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(-100.0, 100.0);
  for (int i = 0; i < 1000; ++i) {
    const double a = u(rng), w = wrap_angle(a);
    ASSERT_GE(w, -kPi);
    ASSERT_LT(w, kPi);
    ASSERT_NEAR(std::remainder(a - w, 2 * kPi), 0.0, 1e-9);
  }
}

// A message's covariance is row-major: cov[r][c] is C(r, c), copied exactly (an
// asymmetric matrix stays asymmetric, so the receivers' checks see what was sent).
TEST(Geometry, MessageCovariancesAreRowMajorExactCopies) {
  const double m2[2][2] = {{0.25, 0.125}, {-0.5, 4.0}};
  const Eigen::Matrix2d C2 = read_cov(m2);
  EXPECT_EQ(C2(0, 0), 0.25);
  EXPECT_EQ(C2(0, 1), 0.125);
  EXPECT_EQ(C2(1, 0), -0.5);
  EXPECT_EQ(C2(1, 1), 4.0);
  double back2[2][2] = {};
  write_cov(back2, C2);
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 2; ++c) EXPECT_EQ(back2[r][c], m2[r][c]) << r << c;

  Eigen::Matrix3d C3;
  C3 << 1, 2, 3, 4, 5, 6, 7, 8, 9.5;
  double m3[3][3] = {};
  write_cov(m3, C3);
  EXPECT_EQ(m3[0][2], 3.0);
  EXPECT_EQ(m3[2][0], 7.0);
  EXPECT_EQ(m3[2][2], 9.5);
  EXPECT_EQ(read_cov(m3), C3);
  const Eigen::Matrix2d position = read_cov(m3).topLeftCorner<2, 2>();
  EXPECT_EQ(position(1, 0), 4.0);
}

TEST(Geometry, ComposeInverseBetween) {
  const Pose2 a{1.0, -2.0, 0.7}, b{0.3, 0.4, -1.2};
  const Pose2 ab = compose(a, b);
  const Pose2 back = between(a, ab);
  EXPECT_NEAR(back.x, b.x, 1e-12);
  EXPECT_NEAR(back.y, b.y, 1e-12);
  EXPECT_NEAR(back.theta, b.theta, 1e-12);
  const Pose2 id = compose(a, inverse(a));
  EXPECT_NEAR(id.x, 0.0, 1e-12);
  EXPECT_NEAR(id.y, 0.0, 1e-12);
  EXPECT_NEAR(id.theta, 0.0, 1e-12);
  // Hand-computed: a at (1,-2) heading 0.7 rad moves 1 m forward.
  const Pose2 fwd = compose(a, Pose2{1.0, 0.0, 0.0});
  EXPECT_NEAR(fwd.x, 1.0 + std::cos(0.7), 1e-12);
  EXPECT_NEAR(fwd.y, -2.0 + std::sin(0.7), 1e-12);
}

TEST(Geometry, TransformPointRoundTrip) {
  const Pose2 T{2.0, 3.0, kPi / 2};
  const Eigen::Vector2d p_B(1.0, 0.0);
  const Eigen::Vector2d p_A = transform_from(T, p_B);
  EXPECT_NEAR(p_A.x(), 2.0, 1e-12);
  EXPECT_NEAR(p_A.y(), 4.0, 1e-12);
  EXPECT_TRUE(transform_to(T, p_A).isApprox(p_B, 1e-12));
}

}  // namespace
}  // namespace elaslam

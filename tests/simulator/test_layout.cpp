// SPDX-License-Identifier: Apache-2.0
// Landmark layouts: count, inside the world, spacing, determinism.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "elaslam/simulator/layout.hpp"
#include "sim_test_util.hpp"

namespace elaslam::sim {
namespace {

void expect_inside(const ScenarioOptions& o, const std::vector<Eigen::Vector2d>& p) {
  for (const auto& q : p) {
    EXPECT_TRUE(q.x() >= o.world.x_min_m && q.x() <= o.world.x_max_m && q.y() >= o.world.y_min_m &&
                q.y() <= o.world.y_max_m)
        << q.transpose();
  }
}

double min_spacing(const std::vector<Eigen::Vector2d>& p) {
  double m = 1e300;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (std::size_t j = i + 1; j < p.size(); ++j) m = std::min(m, (p[i] - p[j]).norm());
  return m;
}

TEST(SimLayout, GridCoversTheWorldEvenly) {
  const ScenarioOptions o = test::paper();
  std::vector<Eigen::Vector2d> p;
  std::string why;
  ASSERT_TRUE(generate_layout(o, &p, &why)) << why;
  ASSERT_EQ(p.size(), 72u);
  expect_inside(o, p);
  // 9 x 8 cells of 20/9 m x 2.5 m: neighbours 2.22 m apart, corner landmark half a cell in.
  EXPECT_NEAR(min_spacing(p), 20.0 / 9.0, 1e-12);
  EXPECT_NEAR(p[0].x(), -10.0 + 10.0 / 9.0, 1e-12);
  EXPECT_NEAR(p[0].y(), -8.75, 1e-12);
  EXPECT_NEAR(p[71].y(), 8.75, 1e-12);
}

TEST(SimLayout, CloisterRingsAreSquares) {
  ScenarioOptions o = test::paper();
  o.landmarks.layout = Layout::kCloister;
  o.landmarks.cloister_rings = 2;
  o.landmarks.cloister_inner_half_width_m = 5.0;
  o.landmarks.cloister_outer_half_width_m = 8.0;
  std::vector<Eigen::Vector2d> p;
  std::string why;
  ASSERT_TRUE(generate_layout(o, &p, &why)) << why;
  ASSERT_EQ(p.size(), 72u);
  expect_inside(o, p);
  for (const auto& q : p) {
    const double h = std::max(std::abs(q.x()), std::abs(q.y()));  // Chebyshev radius = ring half-width
    EXPECT_TRUE(std::abs(h - 5.0) < 1e-9 || std::abs(h - 8.0) < 1e-9) << q.transpose();
  }
  o.landmarks.cloister_outer_half_width_m = 11.0;
  EXPECT_FALSE(generate_layout(o, &p, &why));
  EXPECT_NE(why.find("half the world"), std::string::npos) << why;
}

TEST(SimLayout, RandomIsSeededAndSpaced) {
  ScenarioOptions o = test::paper();
  o.landmarks.layout = Layout::kRandom;
  o.landmarks.min_spacing_m = 1.2;
  std::vector<Eigen::Vector2d> a, b, c;
  std::string why;
  ASSERT_TRUE(generate_layout(o, &a, &why)) << why;
  ASSERT_TRUE(generate_layout(o, &b, &why)) << why;
  o.seed += 1;
  ASSERT_TRUE(generate_layout(o, &c, &why)) << why;
  ASSERT_EQ(a.size(), 72u);
  expect_inside(o, a);
  EXPECT_GE(min_spacing(a), 1.2);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
}

TEST(SimLayout, EmptyRegionLeavesItsLandmarksOutAndKeepsTheRest) {
  // GIVEN every layout with and without config/odometry_bias.yaml's empty region
  for (Layout layout : {Layout::kGrid, Layout::kCloister, Layout::kRandom}) {
    ScenarioOptions o = test::paper();
    o.landmarks.layout = layout;
    std::vector<Eigen::Vector2d> all, kept;
    std::string why;
    ASSERT_TRUE(generate_layout(o, &all, &why)) << why;
    o.landmarks.empty_region = {true, 0.1, 8.4, -8.4, -0.1};
    ASSERT_TRUE(generate_layout(o, &kept, &why)) << why;
    // THEN the landmarks outside it are the same, in the same order (ids consecutive)
    std::vector<Eigen::Vector2d> outside;
    for (const auto& q : all)
      if (!o.landmarks.empty_region.contains(q.x(), q.y())) outside.push_back(q);
    EXPECT_EQ(kept, outside) << layout_name(layout);
    EXPECT_LT(kept.size(), all.size()) << layout_name(layout);
  }
  // The grid: columns x = 2.22, 4.44, 6.67 and rows y = -1.25, -3.75, -6.25 fall inside.
  ScenarioOptions o = test::paper();
  o.landmarks.empty_region = {true, 0.1, 8.4, -8.4, -0.1};
  std::vector<Eigen::Vector2d> p;
  std::string why;
  ASSERT_TRUE(generate_layout(o, &p, &why)) << why;
  EXPECT_EQ(p.size(), 63u);
  // A region that holds every landmark cannot be built, and says why.
  o.landmarks.empty_region = {true, -20.0, 20.0, -20.0, 20.0};
  EXPECT_FALSE(generate_layout(o, &p, &why));
  EXPECT_NE(why.find("holds all 72 landmarks"), std::string::npos) << why;
}

}  // namespace
}  // namespace elaslam::sim

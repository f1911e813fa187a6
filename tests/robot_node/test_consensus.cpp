// ConsensusSolver (mode consensus): the largest mutually consistent set of the
// landmarks in view, exactly, and the prior that breaks ties against co-moving groups.
#include "elaslam/robot_node/consensus.hpp"

#include <gtest/gtest.h>

#include "elaslam/common/stats.hpp"
#include "elaslam/robot_node/ela_gate.hpp"
#include "scene.hpp"

namespace elaslam {
namespace {

using test::view_of;

const double kThreshold = chi2_quantile(0.99, 2);

TEST(Consensus, SixtyPercentMovingInDifferentDirectionsKeepsExactlyTheStaticOnes) {
  // GIVEN 10 mapped landmarks in view, 6 of which then move 0.6 m, each its own way
  const Pose2 pose{0.0, 0.0, 0.2};
  auto lms = test::ring(10, 4.0);
  const EkfSlam ekf = test::mapped_filter(pose, lms);
  const std::vector<int> moving = {0, 2, 3, 5, 7, 8};
  for (std::size_t k = 0; k < moving.size(); ++k) {
    const double a = 2.0 * kPi * static_cast<double>(k) / 6.0;
    lms[static_cast<std::size_t>(moving[k])] += 0.6 * Eigen::Vector2d(std::cos(a), std::sin(a));
  }
  std::mt19937_64 rng(11);
  const auto view = view_of(ekf, pose, lms, &rng);
  // WHEN the consensus is solved
  ConsensusSolver solver(0.99);
  solver.reset(10);
  for (int i = 0; i < 10; ++i) {
    solver.set_prior_d2(i, ekf.check(i, view[static_cast<std::size_t>(i)].z).d2);
    for (int j = i + 1; j < 10; ++j)
      if (pair_d2(ekf, view[static_cast<std::size_t>(i)], view[static_cast<std::size_t>(j)]) <= kThreshold)
        solver.add_edge(i, j);
  }
  const std::uint64_t chosen = solver.solve();
  // THEN exactly the four static landmarks are kept
  EXPECT_EQ(chosen, (1u << 1) | (1u << 4) | (1u << 6) | (1u << 9));
  EXPECT_TRUE(solver.chosen_agrees_with_prior());
}

TEST(Consensus, CoMovingGroupLargerThanStaticSetLosesOnThePrior) {
  // GIVEN 7 landmarks: 4 moved together by 0.8 m (they stay mutually consistent)
  // and 3 static: the co-moving group is the larger clique
  const Pose2 pose{0.0, 0.0, 0.0};
  auto lms = test::ring(7, 4.0);
  const EkfSlam ekf = test::mapped_filter(pose, lms);
  for (int i : {0, 1, 2, 3}) lms[static_cast<std::size_t>(i)] += Eigen::Vector2d(0.8, 0.0);
  const auto view = view_of(ekf, pose, lms, nullptr);
  ConsensusSolver solver(0.99);
  solver.reset(7);
  for (int i = 0; i < 7; ++i) {
    solver.set_prior_d2(i, ekf.check(i, view[static_cast<std::size_t>(i)].z).d2);
    for (int j = i + 1; j < 7; ++j)
      if (pair_d2(ekf, view[static_cast<std::size_t>(i)], view[static_cast<std::size_t>(j)]) <= kThreshold)
        solver.add_edge(i, j);
  }
  // THEN the static set, which agrees with the predicted pose, wins
  EXPECT_EQ(solver.solve(), (1u << 4) | (1u << 5) | (1u << 6));
  EXPECT_GE(solver.cliques_visited(), 2);
}

TEST(Consensus, MaximumCliqueIsExact) {
  // A graph whose greedy choice (highest degree first) is wrong: the exact answer
  // is the 4-clique {0,1,2,3}; vertex 4 has the highest degree.
  ConsensusSolver s(0.99);
  s.reset(9);
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) s.add_edge(a, b);
  for (int v : {0, 5, 6, 7, 8}) s.add_edge(4, v);
  s.add_edge(5, 6);
  EXPECT_EQ(s.solve(), 0b1111u);
}

}  // namespace
}  // namespace elaslam

// The ELA gate (eq 16) and the pairwise relative test on constructed scenes.
#include <gtest/gtest.h>

#include "elaslam/common/stats.hpp"
#include "elaslam/robot_node/consensus.hpp"
#include "elaslam/robot_node/ela_gate.hpp"
#include "scene.hpp"

namespace elaslam {
namespace {

std::vector<InView> view_of(const EkfSlam& ekf, const Pose2& truth, const std::vector<Eigen::Vector2d>& lms,
                            std::mt19937_64* rng) {
  const FrameInput in = test::frame_from(0, truth, truth, lms, test::all_ids(lms.size()), rng);
  std::vector<InView> v;
  for (int k = 0; k < in.num_obs; ++k) {
    InView x;
    x.id = in.obs[static_cast<std::size_t>(k)].landmark_id;
    x.z = in.obs[static_cast<std::size_t>(k)].z;
    set_local(&x, ekf.measurement_cov());
    v.push_back(x);
  }
  return v;
}

const double kThreshold = chi2_quantile(0.99, 2);

TEST(ElaGate, LandmarkDisplacedBySeveralSigmaIsFlaggedOthersAreNot) {
  // GIVEN a map of 8 landmarks 4 m away (position sigma ~5 cm), observed noise-free
  const Pose2 pose{0.0, 0.0, 0.3};
  auto lms = test::ring(8, 4.0);
  const EkfSlam ekf = test::mapped_filter(pose, lms);
  // WHEN landmark 2 has moved by 0.5 m (about 7 sigma of the relative vectors)
  lms[2] += Eigen::Vector2d(0.5, 0.0);
  const auto view = view_of(ekf, pose, lms, nullptr);
  // THEN its ELA test fails and every other landmark's passes
  for (int i = 0; i < 8; ++i) {
    const double d2 = ela_multi_d2(ekf, view.data(), 8, i);
    if (i == 2)
      EXPECT_GT(d2, 4 * kThreshold) << i;
    else
      EXPECT_LT(d2, kThreshold) << i;
  }
}

// Draw a true world from the filter's own distribution (mean + chol(P) n), then
// noisy observations: the gates should fire at about their nominal rate.
TEST(ElaGate, StaticLandmarksFlaggedAtAboutTheGateRate) {
  const Pose2 pose{1.0, -0.5, -0.4};
  const auto lms = test::ring(6, 3.5);
  EkfSlam ekf = test::mapped_filter(pose, lms);
  // Some odometry so that the robot's own uncertainty matters too.
  ekf.predict({0.5, 0.0, 0.05}, Eigen::Vector3d(4e-4, 4e-4, 1e-4).asDiagonal());
  const Eigen::MatrixXd P = ekf.covariance();
  const Eigen::VectorXd mean = ekf.mean();
  const Eigen::MatrixXd L = Eigen::LLT<Eigen::MatrixXd>(P).matrixL();
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n01;
  int single_flags = 0, multi_flags = 0, tests = 0;
  const int draws = 4000;
  for (int d = 0; d < draws; ++d) {
    Eigen::VectorXd n(mean.size());
    for (Eigen::Index i = 0; i < n.size(); ++i) n[i] = n01(rng);
    const Eigen::VectorXd x = mean + L * n;
    const Pose2 truth{x[0], x[1], x[2]};
    std::vector<Eigen::Vector2d> true_lms;
    for (int i = 0; i < 6; ++i) true_lms.push_back(x.segment<2>(StateLayout::landmark_offset(ekf.slot_of(i))));
    const auto view = view_of(ekf, truth, true_lms, &rng);
    for (int i = 0; i < 6; ++i, ++tests) {
      single_flags += ekf.check(view[static_cast<std::size_t>(i)].id, view[static_cast<std::size_t>(i)].z).d2 > kThreshold;
      multi_flags += ela_multi_d2(ekf, view.data(), 6, i) > kThreshold;
    }
  }
  const double single_rate = static_cast<double>(single_flags) / tests;
  const double multi_rate = static_cast<double>(multi_flags) / tests;
  // Both tests are exact for a linear-Gaussian world: 1 % +- 4 binomial sigma. For
  // eq 16 this holds because the residual's covariance is computed from its parts
  // (ela_gate.cpp); with the naive product-of-Gaussians covariance the rate was 5 %.
  const double tol = 4.0 * std::sqrt(0.01 * 0.99 / tests);
  EXPECT_NEAR(single_rate, 0.01, tol);
  EXPECT_NEAR(multi_rate, 0.01, tol);
  RecordProperty("single_rate", std::to_string(single_rate));
  RecordProperty("multi_rate", std::to_string(multi_rate));
}

TEST(ElaGate, RobotPositionErrorCancelsInTheMultiLandmarkElaOnly) {
  // GIVEN a map built at the true pose
  const Pose2 truth{0.0, 0.0, 0.0};
  const auto lms = test::ring(7, 4.0);
  EkfSlam ekf = test::mapped_filter(truth, lms);
  // WHEN the filter believes (confidently) it moved 1 m while it did not
  ekf.predict({1.0, 0.0, 0.0}, Eigen::Matrix3d::Identity() * 1e-8);
  std::mt19937_64 rng(3);
  const auto view = view_of(ekf, truth, lms, &rng);
  // THEN every single-landmark test fails, and no multi-landmark ELA test does
  for (int i = 0; i < 7; ++i) {
    EXPECT_GT(ekf.check(view[static_cast<std::size_t>(i)].id, view[static_cast<std::size_t>(i)].z).d2, kThreshold);
    EXPECT_LT(ela_multi_d2(ekf, view.data(), 7, i), kThreshold);
  }
}

TEST(ElaGate, PairTestIsSymmetricAndDetectsRelativeMotion) {
  const Pose2 pose{0.5, 0.5, 1.0};
  auto lms = test::ring(4, 3.0);
  const EkfSlam ekf = test::mapped_filter(pose, lms);
  auto view = view_of(ekf, pose, lms, nullptr);
  EXPECT_NEAR(pair_d2(ekf, view[0], view[1]), pair_d2(ekf, view[1], view[0]), 1e-9);
  EXPECT_LT(pair_d2(ekf, view[0], view[1]), 1e-6);
  lms[1] += Eigen::Vector2d(0.0, 0.4);
  view = view_of(ekf, pose, lms, nullptr);
  EXPECT_GT(pair_d2(ekf, view[0], view[1]), kThreshold);
  EXPECT_LT(pair_d2(ekf, view[0], view[2]), 1e-6);
}

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

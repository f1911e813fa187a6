// SPDX-License-Identifier: Apache-2.0
// ConsensusSolver (mode consensus): the largest mutually consistent set of the
// landmarks in view, exactly, and the prior that breaks ties against co-moving groups.
#include "elaslam/robot_node/consensus.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/Cholesky>

#include "elaslam/common/stats.hpp"
#include "elaslam/robot_node/ela_gate.hpp"
#include "scene.hpp"

namespace elaslam {
namespace {

using test::view_of;

const double kThreshold = chi2_quantile(0.99, 2);

// The consensus problem of a view: each landmark's prior innovation d2, and an edge
// between every two whose pair test passes at 0.99.
void add_view(ConsensusSolver* solver, const EkfSlam& ekf, const std::vector<InView>& view) {
  const int n = static_cast<int>(view.size());
  solver->reset(n);
  for (int i = 0; i < n; ++i) {
    solver->set_prior_d2(i, ekf.check(i, view[static_cast<std::size_t>(i)].z).d2);
    for (int j = i + 1; j < n; ++j)
      if (pair_d2(ekf, view[static_cast<std::size_t>(i)], view[static_cast<std::size_t>(j)]) <= kThreshold)
        solver->add_edge(i, j);
  }
}

// The joint prior test of a clique: the innovations of one frame share
// the pose's error, so the clique's d2 uses their joint covariance H P H^T + W. On a
// robot whose pose uncertainty dominates (0.1 m), the sum of the single d2s fired
// 7.4 % of the time against chi2(0.99, 12); the joint d2 fires at the nominal 1 %.
// Also checked against a dense reference to 1e-9.
TEST(Consensus, TheJointPriorTestIsExactAndFiresAtTheNominalRate) {
  const Pose2 pose{1.0, -0.5, -0.4};
  const auto lms = test::ring(6, 3.5);
  EkfSlam ekf(test::filter_options());
  ekf.reset(pose, Eigen::Vector3d(1e-4, 1e-4, 1e-4).asDiagonal());
  for (int i = 0; i < 6; ++i) ekf.add_landmark(i, observe(pose, lms[static_cast<std::size_t>(i)]));
  ekf.predict({0.3, 0.0, 0.05}, Eigen::Vector3d(1e-2, 1e-2, 2.5e-3).asDiagonal());
  const Eigen::MatrixXd P = ekf.covariance();
  // Dense reference: H (12 x dim) stacked from each landmark's Jacobians.
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(12, P.rows());
  for (int i = 0; i < 6; ++i) {
    Eigen::Matrix<double, 2, 3> Hx;
    Eigen::Matrix2d Hl;
    observe(ekf.pose(), ekf.landmark(i), &Hx, &Hl);
    H.block<2, 3>(2 * i, 0) = Hx;
    H.block<2, 2>(2 * i, StateLayout::landmark_offset(ekf.slot_of(i))) = Hl;
  }
  Eigen::MatrixXd S = H * P * H.transpose();
  for (int i = 0; i < 6; ++i) S.block<2, 2>(2 * i, 2 * i) += ekf.measurement_cov();
  const Eigen::LLT<Eigen::MatrixXd> S_llt(S);
  const test::WorldSampler sampler(ekf, 6);
  std::mt19937_64 rng(11);
  ElaGate gate(test::robot_options(Mode::kConsensus));
  LMap lmap(64);
  const double thr = chi2_quantile(0.99, 12);
  int joint_fires = 0, sum_fires = 0;
  const int draws = 6000;
  Pose2 truth;
  std::vector<Eigen::Vector2d> true_lms;
  for (int d = 0; d < draws; ++d) {
    sampler.draw(&rng, &truth, &true_lms);
    const auto view = view_of(ekf, truth, true_lms, &rng);  // noisy observations
    gate.clear();
    Eigen::VectorXd nu(12);
    double sum = 0.0;
    for (int i = 0; i < 6; ++i) {
      const RangeBearing& z = view[static_cast<std::size_t>(i)].z;
      gate.add_to_view(i, z);
      const UpdateReport r = ekf.check(i, z);
      nu.segment<2>(2 * i) = r.innovation;
      sum += r.d2;
    }
    gate.judge_view(ekf, &lmap);
    const double joint = gate.consensus().clique_d2(0b111111);
    if (d < 20) {
      const double want = nu.dot(S_llt.solve(nu));
      EXPECT_NEAR(joint, want, 1e-9 * std::max(1.0, want));
    }
    joint_fires += joint > thr;
    sum_fires += sum > thr;
  }
  const double joint_rate = static_cast<double>(joint_fires) / draws;
  const double sum_rate = static_cast<double>(sum_fires) / draws;
  EXPECT_NEAR(joint_rate, 0.01, 4.0 * std::sqrt(0.01 * 0.99 / draws));
  EXPECT_GT(sum_rate, 0.03);  // what the joint covariance is for
  RecordProperty("joint_rate", std::to_string(joint_rate));
  RecordProperty("sum_rate", std::to_string(sum_rate));
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
  add_view(&solver, ekf, view);
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
  add_view(&solver, ekf, view);
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

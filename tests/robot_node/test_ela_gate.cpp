// SPDX-License-Identifier: Apache-2.0
// The ELA gate: eq 16 and the pairwise relative test on constructed scenes, and
// ElaGate's verdicts and records (one per landmark, naming the test that decided).
#include "elaslam/robot_node/ela_gate.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/LU>

#include "elaslam/common/stats.hpp"
#include "scene.hpp"

namespace elaslam {
namespace {

using test::view_of;

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
  const test::WorldSampler sampler(ekf, 6);
  std::mt19937_64 rng(5);
  int single_flags = 0, multi_flags = 0, tests = 0;
  const int draws = 4000;
  Pose2 truth;
  std::vector<Eigen::Vector2d> true_lms;
  for (int d = 0; d < draws; ++d) {
    sampler.draw(&rng, &truth, &true_lms);
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

// The same with a map built under realistic heading uncertainty (3 deg at mapping
// time, then some driving): the landmarks' errors are then strongly correlated with
// the heading's (a map built with a heading error is rotated by it), and eq 16's and
// the pair test's covariances must carry that correlation. Without it the
// multi-landmark test fires at 0.5-0.7 %, not 1 %: slow movers caught later.
TEST(ElaGate, StaticLandmarksFlaggedAtTheGateRateUnderHeadingUncertainty) {
  const Pose2 pose{1.0, -0.5, -0.4};
  const auto lms = test::ring(6, 3.5);
  EkfSlam ekf(test::filter_options());
  const double sigma_th = deg2rad(3.0);
  ekf.reset(pose, Eigen::Vector3d(1e-4, 1e-4, sigma_th * sigma_th).asDiagonal());
  for (int i = 0; i < 6; ++i) ekf.add_landmark(i, observe(pose, lms[static_cast<std::size_t>(i)]));
  ekf.predict({0.3, 0.0, 0.05}, Eigen::Vector3d(4e-4, 4e-4, 1e-4).asDiagonal());
  const Eigen::MatrixXd P = ekf.covariance();
  // The correlation this test is about: heading with a landmark's tangential error.
  const Eigen::Matrix<double, 3, 2> Prl = ekf.pose_landmark_cov(0);
  const double corr = Prl.row(2).norm() / std::sqrt(P(2, 2) * ekf.landmark_cov(0).trace());
  EXPECT_GT(corr, 0.5);
  const test::WorldSampler sampler(ekf, 6);
  std::mt19937_64 rng(11);
  int multi_flags = 0, pair_flags = 0, tests = 0, pairs = 0;
  Pose2 truth;
  std::vector<Eigen::Vector2d> true_lms;
  for (int d = 0; d < 6000; ++d) {
    sampler.draw(&rng, &truth, &true_lms);
    const auto view = view_of(ekf, truth, true_lms, &rng);
    for (int i = 0; i < 6; ++i, ++tests) multi_flags += ela_multi_d2(ekf, view.data(), 6, i) > kThreshold;
    for (int i = 0; i < 6; i += 2, ++pairs)  // disjoint pairs: independent within a draw
      pair_flags += pair_d2(ekf, view[static_cast<std::size_t>(i)], view[static_cast<std::size_t>(i + 1)]) > kThreshold;
  }
  const double multi_rate = static_cast<double>(multi_flags) / tests;
  const double pair_rate = static_cast<double>(pair_flags) / pairs;
  // 1 % +- 4 binomial sigma (the draws are linear-Gaussian up to the heading's
  // nonlinearity, small at 3 deg).
  EXPECT_NEAR(multi_rate, 0.01, 4.0 * std::sqrt(0.01 * 0.99 / tests));
  EXPECT_NEAR(pair_rate, 0.01, 4.0 * std::sqrt(0.01 * 0.99 / pairs));
  RecordProperty("multi_rate", std::to_string(multi_rate));
  RecordProperty("pair_rate", std::to_string(pair_rate));
}

// Eq 16's d2 against a dense reference: the residual r = m_i - sum_j W_j p_j, with
// p_j = m_j + R^T (l_i - l_j) and W_j = (sum_k b_k)^-1 b_j (b_j from
// neighbour_weight: (M_j + R^T P_jj R)^-1), is linear in the state's errors,
// r = n_i - sum_j W_j n_j + H e with H = [-g at th, -R^T at l_i, W_j R^T at l_j], so
// cov(r) = M_i + sum_j W_j M_j W_j^T + H P H^T with the whole of P.
TEST(ElaGate, Eq16CovarianceIsTheDenseLinearisedOne) {
  const Pose2 pose{0.3, 0.2, 0.7};
  auto lms = test::ring(5, 3.0);
  EkfSlam ekf(test::filter_options());
  ekf.reset(pose, Eigen::Vector3d(1e-3, 2e-3, 3e-3).asDiagonal());
  for (int i = 0; i < 5; ++i) ekf.add_landmark(i, observe(pose, lms[static_cast<std::size_t>(i)]));
  ekf.predict({0.4, 0.1, -0.1}, Eigen::Vector3d(1e-3, 1e-3, 5e-4).asDiagonal());
  lms[3] += Eigen::Vector2d(0.2, -0.1);  // some residual to measure
  std::mt19937_64 rng(2);
  const auto view = view_of(ekf, ekf.pose(), lms, &rng);
  const Eigen::MatrixXd P = ekf.covariance();
  const double th = ekf.pose().theta;
  const Eigen::Matrix2d Rt = rotation(th).transpose();
  for (int i = 0; i < 5; ++i) {
    Eigen::Matrix2d Lambda = Eigen::Matrix2d::Zero();
    Eigen::Vector2d eta = Eigen::Vector2d::Zero();
    std::vector<Eigen::Matrix2d> info(5);
    for (int j = 0; j < 5; ++j) {
      if (j == i) continue;
      const InView& vj = view[static_cast<std::size_t>(j)];
      const Eigen::Matrix2d Pjj = P.block<2, 2>(StateLayout::landmark_offset(ekf.slot_of(j)),
                                                StateLayout::landmark_offset(ekf.slot_of(j)));
      info[static_cast<std::size_t>(j)] = (vj.M + Rt * Pjj * Rt.transpose()).inverse();
      Lambda += info[static_cast<std::size_t>(j)];
      eta += info[static_cast<std::size_t>(j)] * (vj.m + Rt * (ekf.landmark(i) - ekf.landmark(j)));
    }
    const Eigen::Matrix2d F = Lambda.inverse();
    const Eigen::Vector2d r = view[static_cast<std::size_t>(i)].m - F * eta;
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(2, P.rows());
    Eigen::Matrix2d noise = view[static_cast<std::size_t>(i)].M;
    const Eigen::Index oi = StateLayout::landmark_offset(ekf.slot_of(i));
    H.block<2, 2>(0, oi) = -Rt;
    for (int j = 0; j < 5; ++j) {
      if (j == i) continue;
      const Eigen::Matrix2d W = F * info[static_cast<std::size_t>(j)];
      noise += W * view[static_cast<std::size_t>(j)].M * W.transpose();
      const Eigen::Index oj = StateLayout::landmark_offset(ekf.slot_of(j));
      H.block<2, 2>(0, oj) += W * Rt;
      const Eigen::Vector2d d = ekf.landmark(i) - ekf.landmark(j);
      const Eigen::Vector2d J(-std::sin(th) * d.x() + std::cos(th) * d.y(), -std::cos(th) * d.x() - std::sin(th) * d.y());
      H.col(StateLayout::kTheta) -= W * J;
    }
    const Eigen::Matrix2d C = noise + H * P * H.transpose();
    const double want = r.dot(C.inverse() * r);
    EXPECT_NEAR(ela_multi_d2(ekf, view.data(), 5, i), want, 1e-9 * std::max(1.0, want)) << i;
  }
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

// ---- ElaGate: one verdict and one record per landmark in view -----------------------

// Every record names the test that decided and carries that test's own numbers.
void expect_consistent(const GateRecord& g) {
  EXPECT_EQ(g.inside, g.d2 <= g.threshold) << to_string(g.kind) << " " << g.landmark_id;
}

void judge(ElaGate* gate, LMap* lmap, const EkfSlam& ekf, const Pose2& truth,
           const std::vector<Eigen::Vector2d>& lms, const std::vector<int>& ids) {
  gate->clear();
  for (int id : ids) gate->add_to_view(id, observe(truth, lms[static_cast<std::size_t>(id)]));
  gate->judge_view(ekf, lmap);
}

// n landmarks on a ring of radius r, mapped from `pose` by a filter, and a gate of
// `o` with its own LMap; a test moves some of lms, then judges the landmarks `ids`
// seen from `pose`.
struct RingFrame {
  RingFrame(const Pose2& pose, int n, double r, const RobotOptions& o)
      : pose(pose), lms(test::ring(n, r)), ekf(test::mapped_filter(pose, lms)), gate(o) {}
  void judge_view(const std::vector<int>& ids) { judge(&gate, &lmap, ekf, pose, lms, ids); }
  const Pose2 pose;
  std::vector<Eigen::Vector2d> lms;
  const EkfSlam ekf;
  ElaGate gate;
  LMap lmap{64};
};

// ElaGate computes eq 16 for the whole view at once and sets landmarks aside by
// subtracting their terms (O(n^2) each, not a new O(n^3) pass): the same d2 and
// verdicts as ela_multi_d2 pass by pass, on views with several movers.
TEST(ElaGateFrame, TheIncrementalEq16IsEq16PassByPass) {
  for (int seed = 1; seed <= 6; ++seed) {
    std::mt19937_64 rng(static_cast<std::uint64_t>(seed));
    const Pose2 pose{0.2, -0.1, 0.4};
    auto lms = test::ring(12, 4.0);
    EkfSlam ekf(test::filter_options());
    ekf.reset(pose, Eigen::Vector3d(1e-4, 1e-4, 1e-3).asDiagonal());
    for (int i = 0; i < 12; ++i) ekf.add_landmark(i, observe(pose, lms[static_cast<std::size_t>(i)]));
    ekf.predict({0.2, 0.0, 0.02}, Eigen::Vector3d(1e-3, 1e-3, 1e-4).asDiagonal());
    std::uniform_real_distribution<double> u(-0.6, 0.6);
    for (int k = 0; k < seed % 4 + 1; ++k) lms[static_cast<std::size_t>(3 * k + seed % 3)] += Eigen::Vector2d(u(rng), u(rng));
    const Pose2 truth = ekf.pose();
    ElaGate gate(test::robot_options(Mode::kEla));
    LMap lmap(64);
    judge(&gate, &lmap, ekf, truth, lms, test::all_ids(12));
    // The reference: ela_multi_d2 for every active landmark, the worst set aside.
    std::vector<InView> view;
    for (int k = 0; k < 12; ++k) view.push_back(gate.in_view(k));
    std::vector<std::uint8_t> mask(12, 1);
    std::vector<double> d2(12, 0.0);
    int active = 12;
    while (active >= 2) {
      int worst = -1;
      for (int i = 0; i < 12; ++i)
        if (mask[static_cast<std::size_t>(i)]) d2[static_cast<std::size_t>(i)] = ela_multi_d2(ekf, view.data(), 12, i, mask.data());
      for (int i = 0; i < 12; ++i)
        if (mask[static_cast<std::size_t>(i)] && d2[static_cast<std::size_t>(i)] > kThreshold &&
            (worst < 0 || d2[static_cast<std::size_t>(i)] > d2[static_cast<std::size_t>(worst)]))
          worst = i;
      if (worst < 0) break;
      mask[static_cast<std::size_t>(worst)] = 0;
      --active;
    }
    int outside = 0;
    for (int k = 0; k < 12; ++k) {
      const GateRecord& g = gate.records()[static_cast<std::size_t>(k)];
      ASSERT_EQ(g.kind, GateKind::kMulti) << seed;
      EXPECT_NEAR(g.d2, d2[static_cast<std::size_t>(k)], 1e-9 * std::max(1.0, d2[static_cast<std::size_t>(k)])) << seed << " " << k;
      EXPECT_EQ(gate.verdict(k).inside, mask[static_cast<std::size_t>(k)] != 0) << seed << " " << k;
      outside += !gate.verdict(k).inside;
    }
    EXPECT_GE(outside, 1) << seed;  // the movers were set aside: the passes were exercised
  }
}

TEST(ElaGateFrame, OneVerdictAndOneRecordPerLandmarkInViewEq16) {
  RingFrame f({0.0, 0.0, 0.3}, 8, 4.0, test::robot_options(Mode::kEla));
  f.lms[2] += Eigen::Vector2d(0.5, 0.0);
  f.judge_view(test::all_ids(8));
  const ElaGate& gate = f.gate;
  ASSERT_EQ(gate.view_size(), 8);
  ASSERT_EQ(gate.records().size(), 8u);
  for (int k = 0; k < 8; ++k) {
    const GateRecord& g = gate.records()[static_cast<std::size_t>(k)];
    EXPECT_EQ(g.landmark_id, k);
    EXPECT_EQ(g.kind, GateKind::kMulti);
    EXPECT_EQ(gate.verdict(k).inside, k != 2) << k;
    EXPECT_EQ(gate.verdict(k).inside, g.inside);
    EXPECT_FALSE(gate.verdict(k).alone);
    expect_consistent(g);
  }
}

// With two landmarks in view eq 16 cannot tell which one moved (the
// residuals are r and -r with one covariance); the prior innovation breaks the tie,
// whichever comes first in the view. Before, the first was set aside: a static
// landmark flagged, and the mover then failed its lone test too.
TEST(ElaGateFrame, TwoInViewTheMoverIsSetAsideWhicheverComesFirst) {
  const Pose2 pose{0.0, 0.0, 0.2};
  for (int mover : {0, 1}) {
    RingFrame f(pose, 2, 3.0, test::robot_options(Mode::kEla));
    f.lms[static_cast<std::size_t>(mover)] += Eigen::Vector2d(0.5, -0.3);
    f.judge_view({0, 1});
    const ElaGate& gate = f.gate;
    ASSERT_EQ(gate.records().size(), 2u);
    EXPECT_FALSE(gate.verdict(mover).inside) << "mover " << mover;
    EXPECT_TRUE(gate.verdict(1 - mover).inside) << "mover " << mover;
    for (const GateRecord& g : gate.records()) expect_consistent(g);
  }
}

TEST(ElaGateFrame, ALoneLandmarkIsJudgedByItsPriorInnovation) {
  for (Mode mode : {Mode::kEla, Mode::kConsensus}) {
    RingFrame f({0.0, 0.0, 0.0}, 4, 3.0, test::robot_options(mode));
    f.lms[1] += Eigen::Vector2d(0.0, 0.6);
    f.judge_view({1});
    const ElaGate& gate = f.gate;
    ASSERT_EQ(gate.records().size(), 1u);
    EXPECT_EQ(gate.records()[0].kind, GateKind::kInnovation);
    EXPECT_FALSE(gate.verdict(0).inside);
    EXPECT_TRUE(gate.verdict(0).alone);
    EXPECT_DOUBLE_EQ(gate.records()[0].d2, f.ekf.check(1, observe(f.pose, f.lms[1])).d2);
    expect_consistent(gate.records()[0]);
  }
}

TEST(ElaGateFrame, ConsensusRecordsTheCliqueAndTheReTest) {
  RingFrame f({0.0, 0.0, 0.2}, 8, 4.0, test::robot_options(Mode::kConsensus));
  f.lms[5] += Eigen::Vector2d(0.0, 0.7);
  f.judge_view(test::all_ids(8));
  const ElaGate& gate = f.gate;
  const EkfSlam& ekf = f.ekf;
  ASSERT_EQ(gate.records().size(), 8u);
  for (int k = 0; k < 8; ++k) {
    const GateRecord& g = gate.records()[static_cast<std::size_t>(k)];
    EXPECT_EQ(g.kind, GateKind::kConsensus);
    EXPECT_EQ(g.inside, k != 5) << k;
    if (k == 5) {
      EXPECT_GT(g.d2, g.threshold);  // re-tested against the clique by eq 16
      // ... the same number as the reference, eq 16 restricted to the clique
      std::vector<InView> view;
      for (int i = 0; i < 8; ++i) view.push_back(gate.in_view(i));
      std::vector<std::uint8_t> clique(8, 1);
      clique[5] = 0;
      const double want = ela_multi_d2(ekf, view.data(), 8, 5, clique.data());
      EXPECT_NEAR(g.d2, want, 1e-9 * want);
    }
    expect_consistent(g);
  }
}

TEST(ElaGateFrame, ADriftRejectionRecordsTheDriftTestWithItsOwnNumbers) {
  // GIVEN landmark 3's drift sum already far out (a slow mover), landmark 4's near 0
  RobotOptions o = test::robot_options(Mode::kEla);
  o.drift_memory = 0.9;
  RingFrame f({0.0, 0.0, 0.0}, 6, 3.0, o);
  const ElaGate& gate = f.gate;
  LMap& lmap = f.lmap;
  lmap.add_drift(3, 0.9, Eigen::Vector2d(20.0, 0.0));
  // WHEN every landmark passes eq 16
  f.judge_view(test::all_ids(6));
  // THEN landmark 3 is rejected by the drift test, and its record says so
  const GateRecord& g = gate.records()[3];
  EXPECT_FALSE(gate.verdict(3).inside);
  EXPECT_EQ(g.kind, GateKind::kDrift);
  EXPECT_DOUBLE_EQ(g.d2, lmap[3].drift.squaredNorm() * (1.0 - 0.9 * 0.9));
  EXPECT_DOUBLE_EQ(g.threshold, chi2_quantile(o.drift_gate_probability, 2));
  for (int k = 0; k < 6; ++k) {
    expect_consistent(gate.records()[static_cast<std::size_t>(k)]);
    if (k == 3) continue;
    EXPECT_EQ(gate.records()[static_cast<std::size_t>(k)].kind, GateKind::kMulti);
    EXPECT_TRUE(gate.verdict(k).inside);
  }
  // s <- lambda s + w, w ~ 0 here (noise-free sightings from the mapping pose)
  EXPECT_NEAR(lmap[3].drift.x(), 18.0, 1e-6);
}

TEST(ElaGateFrame, CandidateVerdictsAndTheirRecords) {
  RobotOptions o = test::robot_options(Mode::kEla);
  o.candidate_drift_test = true;
  ElaGate gate(o);
  LMap lmap(64);
  gate.clear();
  UpdateReport ok;
  ok.d2 = 1.0;
  ok.whitened = Eigen::Vector2d(1.0, 0.0);
  EXPECT_TRUE(gate.judge_candidate(7, ok, &lmap));  // |sum|^2 / n = 1
  UpdateReport far = ok;
  far.d2 = 50.0;
  EXPECT_FALSE(gate.judge_candidate(7, far, &lmap));
  UpdateReport failed;
  failed.status = EkfStatus::kSingular;
  EXPECT_FALSE(gate.judge_candidate(7, failed, &lmap));
  // Consistent sightings that all lean the same way: the sum's test decides.
  UpdateReport leaning = ok;
  leaning.d2 = 8.0;
  leaning.whitened = Eigen::Vector2d(2.8, 0.0);
  EXPECT_TRUE(gate.judge_candidate(8, leaning, &lmap));   // |2.8|^2 / 1 = 7.8
  EXPECT_FALSE(gate.judge_candidate(8, leaning, &lmap));  // |5.6|^2 / 2 = 15.7
  const auto& r = gate.records();
  ASSERT_EQ(r.size(), 5u);
  EXPECT_EQ(r[0].kind, GateKind::kCandidate);
  EXPECT_EQ(r[1].kind, GateKind::kCandidate);
  EXPECT_EQ(r[2].kind, GateKind::kCandidate);
  EXPECT_EQ(r[2].d2, std::numeric_limits<double>::infinity());  // no innovation: outside
  EXPECT_EQ(r[3].kind, GateKind::kCandidate);
  EXPECT_EQ(r[4].kind, GateKind::kCandidateDrift);
  EXPECT_NEAR(r[4].d2, 5.6 * 5.6 / 2, 1e-12);
  for (const GateRecord& g : r) expect_consistent(g);
}

// Several movers gone far the same way (after frames missed: a restart, a radio
// outage) pull the static landmarks' ELAs: setting aside the worst first then set
// the statics aside one by one and kept the movers, which agree with each other.
// 400 scenes of 5-7 landmarks at 1-5 m, a minority displaced together by up to
// 0.6 m per axis, the heading uncertain (a gap's prediction): before, 17 scenes
// had most of their static landmarks judged outside (all of them in 13); now none.
TEST(ElaGateFrame, SeveralMoversGoneTheSameWayDoNotOutvoteTheStatics) {
  int inverted = 0, movers_caught = 0, statics_out = 0, statics = 0;
  for (int seed = 1; seed <= 400; ++seed) {
    std::mt19937_64 rng(static_cast<std::uint64_t>(seed));
    std::uniform_real_distribution<double> u(-1.0, 1.0), range(1.0, 5.0);
    const Pose2 pose{0.0, 0.0, 0.3};
    const int n = 5 + seed % 3, m = (n - 1) / 2;  // landmarks 0..m-1 move
    std::vector<Eigen::Vector2d> lms;
    for (int i = 0; i < n; ++i) {
      const double a = 1.2 * u(rng), d = range(rng);
      lms.emplace_back(d * std::cos(a), d * std::sin(a));
    }
    EkfSlam ekf = test::mapped_filter(pose, lms);
    ekf.predict({0.0, 0.0, 0.0}, Eigen::Vector3d(4e-3, 4e-3, 4e-4).asDiagonal());
    const Eigen::Vector2d shift(0.6 * u(rng), 0.6 * u(rng));
    for (int k = 0; k < m; ++k) lms[static_cast<std::size_t>(k)] += shift;
    ElaGate gate(test::robot_options(Mode::kEla));
    LMap lmap(64);
    judge(&gate, &lmap, ekf, pose, lms, test::all_ids(n));
    int out = 0, caught = 0;
    for (int k = 0; k < n; ++k) {
      if (k < m) {
        caught += !gate.verdict(k).inside;
      } else {
        out += !gate.verdict(k).inside;
        ++statics;
      }
      expect_consistent(gate.records()[static_cast<std::size_t>(k)]);
    }
    if (2 * out > n - m) {
      ++inverted;
      ADD_FAILURE() << "seed " << seed << ": " << out << " of " << n - m << " static landmarks outside";
    }
    movers_caught += caught == m;
    statics_out += out;
  }
  std::printf("scenes with most statics outside: %d; all movers caught: %d of 400; statics outside: %d of %d\n",
              inverted, movers_caught, statics_out, statics);
  EXPECT_EQ(inverted, 0);
  EXPECT_GE(movers_caught, 200);           // the scenes test something: most movers are caught
  EXPECT_LE(statics_out, statics / 20);    // and the statics stay in
}

}  // namespace
}  // namespace elaslam

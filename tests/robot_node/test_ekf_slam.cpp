// SPDX-License-Identifier: Apache-2.0
// EkfSlam: known answers from a dense textbook EKF, statistical consistency on a
// simulated loop, exact marginalisation, and refusal of bad inputs and faults.
#include "elaslam/robot_node/ekf_slam.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <gtest/gtest.h>

#include "ekf_test_world.hpp"
#include "elaslam/common/stats.hpp"

namespace elaslam {
namespace {

using test::DenseEkf;
using test::kOdoNoise;
using test::OpCounts;
using test::RandomWorld;
using test::max_difference;
using test::random_operation;
using test::small_options;
using Vec2 = Eigen::Vector2d;
using Layout = StateLayout;

// ---- known answer ------------------------------------------------------------------------

// The odometer's calibration estimated: a prior and a random walk on
// every state, so that every term of the vehicle block's prediction counts.
EkfOptions calibrated(EkfOptions o) {
  o.calibration.prior = {0.95, 1.02, 0.01};
  o.calibration.turn_scale_sigma = 0.05;
  o.calibration.speed_scale_sigma = 0.05;
  o.calibration.turn_bias_sigma = 0.02;
  o.calibration.turn_scale_walk = 0.01;
  o.calibration.speed_scale_walk = 0.01;
  o.calibration.turn_bias_walk = 0.002;
  return o;
}

// Parameters: (Joseph form, calibration estimated).
class EkfKnownAnswer : public ::testing::TestWithParam<std::tuple<bool, bool>> {};

TEST_P(EkfKnownAnswer, MatchesDenseTextbookEkf) {
  // GIVEN EkfSlam and a dense textbook EKF with the same options and prior
  const auto [joseph, with_calibration] = GetParam();
  const EkfOptions o = with_calibration ? calibrated(small_options(joseph)) : small_options(joseph);
  EkfSlam ekf(o);
  DenseEkf ref(o);
  RandomWorld w(0xE1F5EED + (joseph ? 1 : 0) + (with_calibration ? 2 : 0));
  const Eigen::Matrix3d P0 = Eigen::Vector3d(1e-4, 1e-4, 1e-5).asDiagonal();
  ekf.reset(w.truth, P0);
  ref.reset(w.truth, P0);
  // WHEN both run the same 400 random predicts, updates, adds and removes
  OpCounts total;
  double worst = 0.0;
  for (int k = 0; k < 400; ++k) {
    const OpCounts c = random_operation(w, ekf, &ref, o.capacity);
    total.predicts += c.predicts;
    total.updates += c.updates;
    total.adds += c.adds;
    total.removes += c.removes;
    const double d = max_difference(ekf, ref);
    worst = std::max(worst, d);
    // THEN mean and covariance agree to 1e-9 after every step
    ASSERT_LT(d, 1e-9) << "after operation " << k << ", " << ekf.num_landmarks() << " landmarks";
  }
  EXPECT_GE(total.predicts, 80);
  EXPECT_GE(total.updates, 80);
  EXPECT_GE(total.adds, 40);
  EXPECT_GE(total.removes, 15);
  RecordProperty("max_difference", ::testing::PrintToString(worst));
}

INSTANTIATE_TEST_SUITE_P(BothCovarianceForms, EkfKnownAnswer, ::testing::Combine(::testing::Bool(), ::testing::Bool()),
                         [](const ::testing::TestParamInfo<std::tuple<bool, bool>>& i) {
                           return std::string(std::get<0>(i.param) ? "Joseph" : "Standard") +
                                  (std::get<1>(i.param) ? "Calibrated" : "");
                         });

// ---- batched covariance steps -------------------------------------------------------------

// Runs of consecutive updates (1 to 40, so beyond kMaxBatch too, with gated and
// refused ones inside) are held as pending steps and applied in one pass when the
// filter is next read. Compared only at the end of each run, so the runs really
// are batched: the result must be the dense EKF's after the same sequential
// updates, and a twin filter read after every update (so never batching) must
// agree to rounding.
class EkfBatch : public ::testing::TestWithParam<bool> {};

TEST_P(EkfBatch, BatchedUpdatesEqualSequentialOnes) {
  // The Joseph form with the calibration estimated, the standard form without.
  EkfOptions o = GetParam() ? calibrated(small_options(true)) : small_options(false);
  o.capacity = 40;
  EkfSlam ekf(o), twin(o);
  DenseEkf ref(o);
  RandomWorld w(0xBA7C4 + (GetParam() ? 1 : 0));
  const Eigen::Matrix3d P0 = Eigen::Vector3d(1e-4, 1e-4, 1e-5).asDiagonal();
  ekf.reset(w.truth, P0);
  twin.reset(w.truth, P0);
  ref.reset(w.truth, P0);
  for (int id = 0; id < 30; ++id) {
    const RangeBearing z = w.sense(id, o);
    ASSERT_EQ(ekf.add_landmark(id, z), EkfStatus::kOk);
    ASSERT_EQ(twin.add_landmark(id, z), EkfStatus::kOk);
    ref.add(id, z);
  }
  int batched = 0, longest = 0, gated = 0, position = 0;
  double worst_ref = 0.0, worst_twin = 0.0;
  for (int run = 0; run < 60; ++run) {
    const Pose2 u = w.move();
    const Eigen::Matrix3d U = odometry_covariance(u, kOdoNoise);
    ASSERT_EQ(ekf.predict(u, U, test::kStepSeconds), EkfStatus::kOk);
    ASSERT_EQ(twin.predict(u, U, test::kStepSeconds), EkfStatus::kOk);
    ref.predict(u, U, test::kStepSeconds);
    const int k = 1 + w.pick(40);
    for (int i = 0; i < k; ++i) {
      const int id = ekf.id_at(w.pick(ekf.num_landmarks()));
      if (i % 9 == 4) {  // a gross outlier, refused by the gate: no step, nothing changes
        const RangeBearing far{w.sense(id, o).range + 20.0, 0.0};
        ASSERT_EQ(ekf.update(id, far, true).status, EkfStatus::kGated);
        ASSERT_EQ(twin.update(id, far, true).status, EkfStatus::kGated);
        ++gated;
        continue;
      }
      if (i % 11 == 6) {  // a position measurement joins the batch too
        const Eigen::Matrix2d R = 0.01 * Eigen::Matrix2d::Identity();
        const Vec2 zp = w.landmarks[static_cast<std::size_t>(id)] + Vec2(0.02, -0.01);
        ASSERT_EQ(ekf.update_position(id, zp, R).status, EkfStatus::kOk);
        ASSERT_EQ(twin.update_position(id, zp, R).status, EkfStatus::kOk);
        ref.update_position(id, zp, R);
        (void)twin.pose_cov();
        ++position;
        continue;
      }
      const RangeBearing z = w.sense(id, o);
      const UpdateReport a = ekf.update(id, z), b = twin.update(id, z);
      ASSERT_EQ(a.status, EkfStatus::kOk);
      ASSERT_EQ(b.status, EkfStatus::kOk);
      // The innovation of a batched update is that of the sequential one.
      ASSERT_NEAR(a.d2, b.d2, 1e-9 * (1.0 + b.d2)) << "run " << run << ", update " << i;
      ref.update(id, z);
      (void)twin.pose_cov();  // a read: the twin applies each step at once
    }
    batched += k;
    longest = std::max(longest, k);
    worst_ref = std::max(worst_ref, max_difference(ekf, ref));
    worst_twin = std::max(worst_twin, (ekf.covariance() - twin.covariance()).cwiseAbs().maxCoeff() +
                                          (ekf.mean() - twin.mean()).cwiseAbs().maxCoeff());
    ASSERT_LT(worst_ref, 1e-9) << "after run " << run << " of " << k << " updates";
    ASSERT_LT(worst_twin, 1e-12) << "after run " << run << " of " << k << " updates";
  }
  EXPECT_GT(longest, EkfSlam::kMaxBatch);  // some runs needed two passes
  EXPECT_GT(gated, 20);
  EXPECT_GT(position, 20);
  RecordProperty("max_difference_to_dense", ::testing::PrintToString(worst_ref));
  RecordProperty("max_difference_to_sequential", ::testing::PrintToString(worst_twin));
}

// A refused update inside a batch (its variance would go negative) changes
// nothing, and the pending steps before it still apply. The state: landmark 2
// independent of everything (and poorly known: its update changes little),
// landmark 1 "correlated" with the robot's x beyond what a covariance allows (P
// indefinite, its diagonal positive), so that observing it drives a variance
// below zero.
TEST_P(EkfBatch, RefusedUpdateInsideABatchLeavesThePendingSteps) {
  EkfOptions o;
  o.joseph = GetParam();
  o.range_sigma = 1e-3;
  EkfSlam ekf(o), twin(o);
  Eigen::VectorXd x(Layout::dim(2));
  x << 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 1.0, 0.0, 2.0, 1.0;  // pose, calibration (frozen: 1, 1, 0), landmarks 1, 2
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(Layout::dim(2), Layout::dim(2));
  P.diagonal() << 1e-4, 1e-4, 1e-5, 0.0, 0.0, 0.0, 1e-2, 1e-2, 1.0, 1.0;
  const Eigen::Index l1 = Layout::landmark_offset(0);
  P(l1, Layout::kX) = P(Layout::kX, l1) = 2e-3;  // correlation 2
  for (EkfSlam* f : {&ekf, &twin}) ASSERT_EQ(f->restore(x, P, {1, 2}), EkfStatus::kOk);
  // The twin takes only the accepted update; the filter takes it and then the
  // refused one, in the same batch.
  const RangeBearing z2 = observe(ekf.pose(), ekf.landmark(2));
  ASSERT_EQ(twin.update(2, z2).status, EkfStatus::kOk);
  ASSERT_EQ(ekf.update(2, z2).status, EkfStatus::kOk);
  const UpdateReport r = ekf.update(1, {1.0, 0.0});
  EXPECT_EQ(r.status, EkfStatus::kCovarianceFault) << to_string(r.status);
  EXPECT_EQ(ekf.mean(), twin.mean());
  EXPECT_EQ(ekf.covariance(), twin.covariance());
}

INSTANTIATE_TEST_SUITE_P(BothCovarianceForms, EkfBatch, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& i) {
                           return i.param ? std::string("Joseph") : std::string("Standard");
                         });

// A filter and its dense reference, both covariance forms, after each of 300 random
// operations that leave at least two landmarks: `check(w, ekf, ref, k)` applies
// the update under test to both and compares them. Returns how many were checked.
int after_random_operations(std::uint64_t seed,
                            const std::function<void(RandomWorld&, EkfSlam&, DenseEkf&, int)>& check) {
  int checked = 0;
  for (const bool joseph : {true, false}) {
    // The Joseph form with the calibration estimated, the standard form without.
    const EkfOptions o = joseph ? calibrated(small_options(true)) : small_options(false);
    EkfSlam ekf(o);
    DenseEkf ref(o);
    RandomWorld w(seed + (joseph ? 1 : 0));
    const Eigen::Matrix3d P0 = Eigen::Vector3d(1e-4, 1e-4, 1e-5).asDiagonal();
    ekf.reset(w.truth, P0);
    ref.reset(w.truth, P0);
    for (int k = 0; k < 300; ++k) {
      random_operation(w, ekf, &ref, o.capacity);
      if (ekf.num_landmarks() < 2) continue;
      check(w, ekf, ref, k);
      ++checked;
    }
  }
  return checked;
}

// The landmark-only (consider) update used for candidates: it must equal the dense
// Schmidt-Kalman update, leave the robot's mean and covariance and every other
// landmark's marginal exactly as they were, and shrink the landmark's covariance.
TEST(EkfSlam, LandmarkOnlyUpdateMatchesTheDenseSchmidtUpdate) {
  const int checked = after_random_operations(0x5C4D1D7, [](RandomWorld& w, EkfSlam& ekf, DenseEkf& ref, int k) {
    // WHEN one landmark is corrected alone
    const int id = ekf.id_at(w.pick(ekf.num_landmarks()));
    const int other = ekf.id_at((ekf.slot_of(id) + 1) % ekf.num_landmarks());
    const RangeBearing z = w.sense(id, ekf.options());
    const Eigen::Vector3d x_before = ekf.mean().head<3>();
    const Eigen::Matrix3d pose_cov = ekf.pose_cov();
    const Vec2 other_mean = ekf.landmark(other);
    const Eigen::Matrix2d other_cov = ekf.landmark_cov(other);
    const Eigen::Matrix2d lm_cov = ekf.landmark_cov(id);
    ASSERT_EQ(ekf.update_landmark_only(id, z).status, EkfStatus::kOk);
    ref.update_landmark_only(id, z);
    // THEN it matches the dense reference, and only the landmark has changed
    ASSERT_LT(max_difference(ekf, ref), 1e-9) << "operation " << k;
    EXPECT_EQ(ekf.mean().head<3>(), x_before);
    EXPECT_EQ(ekf.pose_cov(), pose_cov);
    EXPECT_EQ(ekf.landmark(other), other_mean);
    EXPECT_EQ(ekf.landmark_cov(other), other_cov);
    EXPECT_LT(ekf.landmark_cov(id).trace(), lm_cov.trace());
  });
  EXPECT_GE(checked, 200);
}

// The team map's measurement of a landmark's position (update_position): the dense
// textbook update with H = [0 .. I .. 0], both covariance forms; check_position
// gives the same d2 without changing anything.
TEST(EkfSlam, PositionUpdateMatchesTheDenseUpdate) {
  const int checked = after_random_operations(0x7EA3, [](RandomWorld& w, EkfSlam& ekf, DenseEkf& ref, int k) {
    const int id = ekf.id_at(w.pick(ekf.num_landmarks()));
    Eigen::Matrix2d R;
    R << 0.02, 0.005, 0.005, 0.01;
    const Vec2 z = ekf.landmark(id) + Vec2(0.05, -0.03);
    const Eigen::VectorXd x_before = ekf.mean();
    const double trace_before = ekf.landmark_cov(id).trace();
    const UpdateReport check = ekf.check_position(id, z, R);
    ASSERT_EQ(check.status, EkfStatus::kOk);
    EXPECT_EQ(ekf.mean(), x_before);
    const UpdateReport r = ekf.update_position(id, z, R);
    ASSERT_EQ(r.status, EkfStatus::kOk);
    EXPECT_DOUBLE_EQ(r.d2, check.d2);
    ref.update_position(id, z, R);
    ASSERT_LT(max_difference(ekf, ref), 1e-9) << "operation " << k;
    EXPECT_LT(ekf.landmark_cov(id).trace(), trace_before);
  });
  EXPECT_GE(checked, 200);
}

// assign (FilterHistory's rebuild): a copy of another filter, whatever the two held
// before (more landmarks or fewer); both then go on identically. Capacity or id
// range that differ are refused.
TEST(EkfSlam, AssignMakesAnExactCopy) {
  const EkfOptions o = calibrated(small_options(false));  // the calibration states are copied too
  for (const bool grow : {true, false}) {
    SCOPED_TRACE(grow ? "into a filter with fewer landmarks" : "into one with more");
    EkfSlam big(o), small(o);
    RandomWorld wb(0xB16), ws(0x5A11);
    big.reset(wb.truth, 1e-4 * Eigen::Matrix3d::Identity());
    small.reset(ws.truth, 1e-4 * Eigen::Matrix3d::Identity());
    for (int k = 0; k < 120; ++k) random_operation(wb, big, nullptr, o.capacity);
    for (int k = 0; k < 8; ++k) random_operation(ws, small, nullptr, o.capacity);
    ASSERT_GT(big.num_landmarks(), small.num_landmarks() + 3);
    EkfSlam& a = grow ? big : small;  // the source
    EkfSlam& b = grow ? small : big;  // the copy
    ASSERT_EQ(b.assign(a), EkfStatus::kOk);
    EXPECT_EQ(b.mean(), a.mean());
    EXPECT_EQ(b.covariance(), a.covariance());
    for (int id = 0; id < o.max_landmark_id; ++id) EXPECT_EQ(b.slot_of(id), a.slot_of(id)) << "id " << id;
    // The same operations on both from here: the same filter to the last digit.
    RandomWorld w1(0xC0FFEE), w2(0xC0FFEE);
    for (int k = 0; k < 100; ++k) {
      random_operation(w1, a, nullptr, o.capacity);
      random_operation(w2, b, nullptr, o.capacity);
    }
    EXPECT_EQ(b.mean(), a.mean());
    EXPECT_EQ(b.covariance(), a.covariance());
  }
  EkfOptions other = o;
  other.capacity += 1;
  EkfSlam c(other), d(o);
  EXPECT_EQ(c.assign(d), EkfStatus::kBadInput);
}

// A filter at the origin holding landmark 3 only: for the refusal tests.
EkfSlam filter_with_landmark_3() {
  EkfSlam ekf(small_options(true));
  ekf.reset({0.0, 0.0, 0.0}, Eigen::Matrix3d::Identity() * 1e-4);
  EXPECT_EQ(ekf.add_landmark(3, {2.0, 0.1}), EkfStatus::kOk);
  return ekf;
}

TEST(EkfSlam, PositionUpdateRefusesUnknownAndBadInput) {
  EkfSlam ekf = filter_with_landmark_3();
  ASSERT_TRUE(ekf.has_landmark(3));
  const Eigen::VectorXd x = ekf.mean();
  const Eigen::Matrix2d R = 0.01 * Eigen::Matrix2d::Identity();
  const Vec2 z(2.0, 0.2);
  EXPECT_EQ(ekf.update_position(4, z, R).status, EkfStatus::kUnknownLandmark);
  EXPECT_EQ(ekf.update_position(3, Vec2(std::nan(""), 0.0), R).status, EkfStatus::kBadInput);
  EXPECT_EQ(ekf.update_position(3, z, -R).status, EkfStatus::kBadInput);
  Eigen::Matrix2d asym = R;
  asym(0, 1) = 0.005;
  EXPECT_EQ(ekf.update_position(3, z, asym).status, EkfStatus::kBadInput);
  Eigen::Matrix2d indefinite;
  indefinite << 0.01, 0.02, 0.02, 0.01;
  EXPECT_EQ(ekf.update_position(3, z, indefinite).status, EkfStatus::kBadInput);
  EXPECT_EQ(ekf.update_position(-1, z, R).status, EkfStatus::kBadInput);
  EXPECT_EQ(ekf.mean(), x);
  // d2 against the textbook (P_ll + R)^-1.
  const Vec2 nu = z - ekf.landmark(3);
  const double d2 = nu.dot((ekf.landmark_cov(3) + R).inverse() * nu);
  EXPECT_NEAR(ekf.check_position(3, z, R).d2, d2, 1e-9 * d2);
}

// move_landmark (a followed mover's own prediction): the landmark's mean moves by
// delta and its block gains Q; nothing else changes, its cross-covariances
// included. Against the dense reference with the same step applied by hand.
TEST(EkfSlam, MoveLandmarkShiftsOneLandmarkAndWidensItsBlockAlone) {
  const int checked = after_random_operations(0x30F3, [](RandomWorld& w, EkfSlam& ekf, DenseEkf& ref, int k) {
    const int id = ekf.id_at(w.pick(ekf.num_landmarks()));
    Eigen::Matrix2d Q;
    Q << 4e-4, 1e-4, 1e-4, 2e-4;
    const Vec2 delta(0.03, -0.01);
    const Eigen::MatrixXd P_before = ekf.covariance();
    const Eigen::VectorXd x_before = ekf.mean();
    ASSERT_EQ(ekf.move_landmark(id, delta, Q), EkfStatus::kOk);
    const int off = StateLayout::landmark_offset(ekf.slot_of(id));
    Eigen::VectorXd x = x_before;
    x.segment<2>(off) += delta;
    Eigen::MatrixXd P = P_before;
    P.block<2, 2>(off, off) += Q;
    EXPECT_LT((ekf.mean() - x).cwiseAbs().maxCoeff(), 1e-15) << "operation " << k;
    EXPECT_LT((ekf.covariance() - P).cwiseAbs().maxCoeff(), 1e-15) << "operation " << k;
    ref.move_landmark(id, delta, Q);
    ASSERT_LT(max_difference(ekf, ref), 1e-9) << "operation " << k;
  });
  EXPECT_GE(checked, 200);
  EkfSlam ekf = filter_with_landmark_3();
  const Eigen::VectorXd x = ekf.mean();
  const Eigen::MatrixXd P = ekf.covariance();
  const Eigen::Matrix2d Q = 1e-4 * Eigen::Matrix2d::Identity();
  EXPECT_EQ(ekf.move_landmark(4, Vec2(0.1, 0.0), Q), EkfStatus::kUnknownLandmark);
  EXPECT_EQ(ekf.move_landmark(3, Vec2(std::nan(""), 0.0), Q), EkfStatus::kBadInput);
  EXPECT_EQ(ekf.move_landmark(3, Vec2(0.1, 0.0), -Q), EkfStatus::kBadInput);
  Eigen::Matrix2d indefinite;
  indefinite << 1e-4, 2e-4, 2e-4, 1e-4;
  EXPECT_EQ(ekf.move_landmark(3, Vec2(0.1, 0.0), indefinite), EkfStatus::kBadInput);
  EXPECT_EQ(ekf.mean(), x);
  EXPECT_EQ(ekf.covariance(), P);
}

TEST(EkfSlam, LandmarkOnlyUpdateRefusesUnknownAndBadInput) {
  EkfSlam ekf = filter_with_landmark_3();
  ASSERT_TRUE(ekf.has_landmark(3));
  const Eigen::VectorXd x = ekf.mean();
  EXPECT_EQ(ekf.update_landmark_only(4, {2.0, 0.1}).status, EkfStatus::kUnknownLandmark);
  EXPECT_EQ(ekf.update_landmark_only(3, {-1.0, 0.1}).status, EkfStatus::kBadInput);
  EXPECT_EQ(ekf.update_landmark_only(3, {2.0, std::nan("")}).status, EkfStatus::kBadInput);
  EXPECT_EQ(ekf.mean(), x);
}

// EkfSlam keeps the lower triangle of P current and completes the upper one when
// covariance() is called; the block accessors read the lower triangle only. They
// must agree with the completed view, which must be a covariance.
TEST(EkfSlam, BlockAccessorsAgreeWithTheCovarianceView) {
  for (const bool joseph : {true, false}) {
    // The Joseph form with the calibration estimated, the standard form without.
    EkfSlam ekf(joseph ? calibrated(small_options(true)) : small_options(false));
    RandomWorld w(77);
    ekf.reset(w.truth, Eigen::Vector3d(1e-4, 1e-4, 1e-5).asDiagonal());
    for (int k = 0; k < 300; ++k) random_operation(w, ekf, nullptr, 20);
    ASSERT_GT(ekf.num_landmarks(), 5);
    // Read everything through the accessors before the view completes P.
    const Eigen::Matrix3d pose_cov = ekf.pose_cov();
    const double mean_diag = ekf.mean_diag();
    std::vector<Eigen::Matrix<double, 3, 2>> pose_cross;
    std::vector<Eigen::Matrix2d> cross;  // all pairs, in slot order
    for (int i = 0; i < ekf.num_landmarks(); ++i) {
      pose_cross.push_back(ekf.pose_landmark_cov(ekf.id_at(i)));
      for (int j = 0; j < ekf.num_landmarks(); ++j)
        cross.push_back(ekf.landmark_cross_cov(ekf.id_at(i), ekf.id_at(j)));
    }
    const Eigen::MatrixXd P = ekf.covariance();
    EXPECT_TRUE(P == P.transpose()) << "joseph = " << joseph;
    // Positive definite; frozen calibration states have no variance: without them.
    std::vector<Eigen::Index> kept;  // every state but C, in order
    for (Eigen::Index i = 0; i < P.rows(); ++i)
      if (i < Layout::kCalibration || i >= Layout::kVehicleDim) kept.push_back(i);
    const Eigen::MatrixXd P_RM = P(kept, kept);
    EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(joseph ? P : P_RM).info(), Eigen::Success);
    if (!joseph) {
      EXPECT_TRUE(P.middleRows<3>(Layout::kCalibration).isZero(0.0));
    }
    EXPECT_TRUE((pose_cov == P.topLeftCorner<3, 3>()));
    EXPECT_TRUE((ekf.calibration_cov() == P.block<3, 3>(Layout::kCalibration, Layout::kCalibration)));
    EXPECT_EQ(mean_diag, P_RM.diagonal().mean());  // eq 19: the pose and the landmarks
    std::size_t k = 0;
    for (int i = 0; i < ekf.num_landmarks(); ++i) {
      const Eigen::Index oi = Layout::landmark_offset(i);
      EXPECT_TRUE((pose_cross[static_cast<std::size_t>(i)] == P.block<3, 2>(0, oi))) << "slot " << i;
      EXPECT_TRUE((ekf.landmark_cov(ekf.id_at(i)) == P.block<2, 2>(oi, oi))) << "slot " << i;
      for (int j = 0; j < ekf.num_landmarks(); ++j, ++k) {
        EXPECT_TRUE((cross[k] == P.block<2, 2>(oi, Layout::landmark_offset(j))))
            << "slots " << i << ", " << j;
      }
    }
  }
}

// ---- consistency -------------------------------------------------------------------------

// A robot driving one loop of a 10 m radius circle among 20 static landmarks,
// range-limited sensor, known data association. Returns the robot NEES averaged
// over runs at every step, and the final landmark error averaged over runs.
struct MonteCarlo {
  std::vector<double> anees;     // per step, mean over runs of e^T P_RR^-1 e
  double landmark_error = 0.0;   // [m], mean over runs and landmarks at the end
  int faults = 0;                // any non-kOk status
};

MonteCarlo run_loop_monte_carlo(int runs, double told_sigma_scale) {
  constexpr int kSteps = 220;          // 0.3 m steps: a little over one loop
  constexpr double kRadius = 10.0;     // [m]
  constexpr double kStep = 0.3;        // [m]
  constexpr double kSensorRange = 6.0; // [m]
  const OdometryNoise true_odo{4e-4, 1e-4, 2e-5};
  const double true_range_sigma = 0.02, true_bearing_sigma = 0.004;
  const double s2 = told_sigma_scale * told_sigma_scale;
  const OdometryNoise told_odo{true_odo.var_trans_per_m * s2, true_odo.var_rot_per_rad * s2,
                               true_odo.var_rot_per_m * s2};

  // Landmarks spread evenly around the loop, alternately 2-4 m inside and outside
  // the path, so that a few are always in view and none is on the path.
  std::mt19937_64 map_rng(2021);
  std::uniform_real_distribution<double> jitter(-0.1, 0.1), offset(2.0, 4.0);
  std::vector<Vec2> landmarks;
  for (int i = 0; i < 20; ++i) {
    const double a = 2.0 * kPi * i / 20.0 + jitter(map_rng);
    const double r = kRadius + (i % 2 == 0 ? -1.0 : 1.0) * offset(map_rng);
    landmarks.push_back({r * std::cos(a), r * std::sin(a)});
  }
  const double dtheta = kStep / kRadius;
  const Pose2 u_true{kRadius * std::sin(dtheta), kRadius * (1.0 - std::cos(dtheta)), dtheta};

  MonteCarlo mc;
  mc.anees.assign(kSteps, 0.0);
  for (int run = 0; run < runs; ++run) {
    std::mt19937_64 rng(1000 + static_cast<std::uint64_t>(run));
    const auto gauss = [&](double var) {
      return std::normal_distribution<double>(0.0, std::sqrt(var))(rng);
    };
    EkfOptions o;
    o.capacity = 32;
    o.max_landmark_id = 32;
    o.range_sigma = true_range_sigma * told_sigma_scale;
    o.bearing_sigma = true_bearing_sigma * told_sigma_scale;
    EkfSlam ekf(o);
    Pose2 truth{kRadius, 0.0, kPi / 2};
    ekf.reset(truth, Eigen::Matrix3d::Zero());  // the map frame is the start pose
    for (int k = 0; k < kSteps; ++k) {
      const Eigen::Matrix3d U_true = odometry_covariance(u_true, true_odo);
      const Pose2 u{u_true.x + gauss(U_true(0, 0)), u_true.y + gauss(U_true(1, 1)),
                    u_true.theta + gauss(U_true(2, 2))};
      truth = compose(truth, u_true);
      mc.faults += ekf.predict(u, odometry_covariance(u, told_odo)) != EkfStatus::kOk;
      for (int id = 0; id < static_cast<int>(landmarks.size()); ++id) {
        const RangeBearing h = observe(truth, landmarks[static_cast<std::size_t>(id)]);
        if (h.range > kSensorRange) continue;
        const RangeBearing y{h.range + gauss(true_range_sigma * true_range_sigma),
                             wrap_angle(h.bearing + gauss(true_bearing_sigma * true_bearing_sigma))};
        const EkfStatus s = ekf.has_landmark(id) ? ekf.update(id, y).status : ekf.add_landmark(id, y);
        mc.faults += s != EkfStatus::kOk;
      }
      const Pose2 est = ekf.pose();
      const Eigen::Vector3d e(est.x - truth.x, est.y - truth.y, wrap_angle(est.theta - truth.theta));
      mc.anees[static_cast<std::size_t>(k)] += e.dot(ekf.pose_cov().ldlt().solve(e)) / runs;
    }
    double err = 0.0;
    for (int id = 0; id < ekf.capacity(); ++id) {
      if (ekf.has_landmark(id)) err += (ekf.landmark(id) - landmarks[static_cast<std::size_t>(id)]).norm();
    }
    mc.landmark_error += err / ekf.num_landmarks() / runs;
  }
  return mc;
}

struct NeesBand {
  double lo, hi;
  double time_average;
  double fraction_inside;
};

NeesBand nees_band(const MonteCarlo& mc, int runs) {
  // The sum over runs of the robot NEES is chi-square with 3 * runs dof when the
  // filter is consistent; the run average lies in this band 95% of the time.
  NeesBand b{chi2_quantile(0.025, 3 * runs) / runs, chi2_quantile(0.975, 3 * runs) / runs, 0.0, 0.0};
  for (const double a : mc.anees) {
    b.time_average += a / static_cast<double>(mc.anees.size());
    b.fraction_inside += (a >= b.lo && a <= b.hi) ? 1.0 / static_cast<double>(mc.anees.size()) : 0.0;
  }
  return b;
}

TEST(EkfSlamConsistency, RobotNeesInsideChiSquareBandOnALoop) {
  constexpr int kRuns = 50;
  const MonteCarlo mc = run_loop_monte_carlo(kRuns, 1.0);
  const NeesBand b = nees_band(mc, kRuns);
  EXPECT_EQ(mc.faults, 0);
  // The time average smooths the per-step noise, so checking it against the
  // per-step 95% band is conservative for a consistent filter; an overconfident
  // filter (below) misses it by a wide margin.
  EXPECT_GT(b.time_average, b.lo);
  EXPECT_LT(b.time_average, b.hi);
  // The steps are correlated in time, so the fraction inside the per-step band
  // scatters widely around 95% (0.76 to 1.0 over ten seeds): ask for most.
  EXPECT_GT(b.fraction_inside, 0.6) << "band [" << b.lo << ", " << b.hi << "]";
  EXPECT_LT(mc.landmark_error, 0.1);
  RecordProperty("anees_time_average", std::to_string(b.time_average));
  RecordProperty("fraction_inside", std::to_string(b.fraction_inside));
  RecordProperty("landmark_error_m", std::to_string(mc.landmark_error));
}

TEST(EkfSlamConsistency, OverconfidentFilterFailsTheNeesTest) {
  // The filter is told the noise is 10x smaller (std dev) than simulated.
  constexpr int kRuns = 50;
  const NeesBand b = nees_band(run_loop_monte_carlo(kRuns, 0.1), kRuns);
  EXPECT_GT(b.time_average, b.hi);
  EXPECT_LT(b.fraction_inside, 0.1);
  RecordProperty("anees_time_average", std::to_string(b.time_average));
}

// ---- marginalisation ----------------------------------------------------------------------

// Everything EkfSlam knows about the robot and the landmarks other than `gone`.
struct Marginals {
  Eigen::Vector3d pose;
  Eigen::Matrix3d pose_cov;
  std::vector<int> ids;
  std::vector<Vec2> means;
  std::vector<Eigen::Matrix<double, 3, 2>> pose_cross;
  std::vector<std::vector<Eigen::Matrix2d>> cross;  // [i][j] = P_{id_i id_j}
};

Marginals marginals(const EkfSlam& ekf, int gone) {
  Marginals m;
  m.pose << ekf.pose().x, ekf.pose().y, ekf.pose().theta;
  m.pose_cov = ekf.pose_cov();
  for (int s = 0; s < ekf.num_landmarks(); ++s)
    if (ekf.id_at(s) != gone) m.ids.push_back(ekf.id_at(s));
  std::sort(m.ids.begin(), m.ids.end());
  for (const int i : m.ids) {
    m.means.push_back(ekf.landmark(i));
    m.pose_cross.push_back(ekf.pose_landmark_cov(i));
    m.cross.emplace_back();
    for (const int j : m.ids) m.cross.back().push_back(ekf.landmark_cross_cov(i, j));
  }
  return m;
}

void expect_same(const Marginals& a, const Marginals& b) {
  EXPECT_TRUE(a.pose == b.pose);
  EXPECT_TRUE(a.pose_cov == b.pose_cov);
  ASSERT_EQ(a.ids, b.ids);
  for (std::size_t i = 0; i < a.ids.size(); ++i) {
    EXPECT_TRUE(a.means[i] == b.means[i]) << "id " << a.ids[i];
    EXPECT_TRUE(a.pose_cross[i] == b.pose_cross[i]) << "id " << a.ids[i];
    for (std::size_t j = 0; j < a.ids.size(); ++j)
      EXPECT_TRUE(a.cross[i][j] == b.cross[i][j]) << "ids " << a.ids[i] << ", " << a.ids[j];
  }
}

TEST(EkfSlam, RemovingALandmarkLeavesEveryOtherMarginalUnchanged) {
  // Hole at the first slot, in the middle, and at the last slot (no move).
  for (const int which : {0, 4, -1}) {
    EkfSlam ekf(small_options(true));
    RandomWorld w(99);
    ekf.reset(w.truth, Eigen::Vector3d(1e-4, 1e-4, 1e-5).asDiagonal());
    for (int id = 0; id < 10; ++id) ASSERT_EQ(ekf.add_landmark(id, w.sense(id, ekf.options())), EkfStatus::kOk);
    for (int k = 0; k < 50; ++k) random_operation(w, ekf, nullptr, 20);
    ASSERT_GE(ekf.num_landmarks(), 6);
    const int slot = which < 0 ? ekf.num_landmarks() - 1 : which;
    const int gone = ekf.id_at(slot);
    const Marginals before = marginals(ekf, gone);
    const int n_before = ekf.num_landmarks();

    ASSERT_EQ(ekf.remove_landmark(gone), EkfStatus::kOk);

    EXPECT_FALSE(ekf.has_landmark(gone));
    EXPECT_EQ(ekf.num_landmarks(), n_before - 1);
    EXPECT_EQ(ekf.state_dim(), Layout::dim(n_before - 1));
    expect_same(before, marginals(ekf, gone));
    // The id tables agree with each other.
    for (int s = 0; s < ekf.num_landmarks(); ++s) EXPECT_EQ(ekf.slot_of(ekf.id_at(s)), s);
    EXPECT_TRUE(ekf.landmark(gone).hasNaN());
    // The freed slot is reusable.
    EXPECT_EQ(ekf.add_landmark(gone, w.sense(gone, ekf.options())), EkfStatus::kOk);
  }
}

// ---- refusals -------------------------------------------------------------------------------

// The whole observable state, to compare before/after a refused call.
struct Snapshot {
  explicit Snapshot(const EkfSlam& e) : x(e.mean()), P(e.covariance()), n(e.num_landmarks()) {
    for (int s = 0; s < n; ++s) ids.push_back(e.id_at(s));
  }
  bool operator==(const Snapshot& o) const {
    return x.size() == o.x.size() && x == o.x && P == o.P && n == o.n && ids == o.ids;
  }
  Eigen::VectorXd x;
  Eigen::MatrixXd P;
  int n;
  std::vector<int> ids;
};

class EkfRefusal : public ::testing::Test {
 protected:
  EkfRefusal() : ekf_(options()) {
    ekf_.reset({1.0, 2.0, 0.3}, Eigen::Vector3d(1e-3, 1e-3, 1e-4).asDiagonal());
    EXPECT_EQ(ekf_.add_landmark(3, {4.0, 0.2}), EkfStatus::kOk);
    EXPECT_EQ(ekf_.add_landmark(7, {6.0, -1.0}), EkfStatus::kOk);
    EXPECT_EQ(ekf_.predict({0.5, 0.0, 0.05}, odometry_covariance({0.5, 0.0, 0.05}, kOdoNoise)),
              EkfStatus::kOk);
    EXPECT_EQ(ekf_.update(3, {3.6, 0.15}).status, EkfStatus::kOk);
  }
  static EkfOptions options() {
    EkfOptions o;
    o.capacity = 3;
    o.max_landmark_id = 10;
    return o;
  }
  // A correct observation of `id` from the current estimate.
  RangeBearing predicted(int id) const { return observe(ekf_.pose(), ekf_.landmark(id)); }
  EkfSlam ekf_;
};

TEST_F(EkfRefusal, BadObservationsLeaveTheFilterUnchanged) {
  const Snapshot before(ekf_);
  const double nan = std::nan("");
  const struct {
    int id;
    RangeBearing z;
    EkfStatus expected;
  } cases[] = {
      {3, {nan, 0.1}, EkfStatus::kBadInput},
      {3, {4.0, nan}, EkfStatus::kBadInput},
      {3, {HUGE_VAL, 0.1}, EkfStatus::kBadInput},
      {3, {-1.0, 0.1}, EkfStatus::kBadInput},
      {3, {0.0, 0.1}, EkfStatus::kBadInput},
      {-1, {4.0, 0.1}, EkfStatus::kBadInput},
      {10, {4.0, 0.1}, EkfStatus::kBadInput},  // == max_landmark_id
      {5, {4.0, 0.1}, EkfStatus::kUnknownLandmark},
  };
  for (const auto& c : cases) {
    const UpdateReport r = ekf_.update(c.id, c.z, true);
    EXPECT_EQ(r.status, c.expected) << "id " << c.id << ": " << to_string(r.status);
    EXPECT_EQ(r.d2, 0.0);
    EXPECT_EQ(ekf_.check(c.id, c.z).status, c.expected);
    EXPECT_TRUE(Snapshot(ekf_) == before);
  }
}

TEST_F(EkfRefusal, BadAddsAndRemovesLeaveTheFilterUnchanged) {
  const Snapshot before(ekf_);
  EXPECT_EQ(ekf_.add_landmark(3, {2.0, 0.0}), EkfStatus::kAlreadyMapped);
  EXPECT_EQ(ekf_.add_landmark(4, {std::nan(""), 0.0}), EkfStatus::kBadInput);
  EXPECT_EQ(ekf_.add_landmark(4, {-2.0, 0.0}), EkfStatus::kBadInput);
  EXPECT_EQ(ekf_.add_landmark(10, {2.0, 0.0}), EkfStatus::kBadInput);
  EXPECT_EQ(ekf_.add_landmark(-3, {2.0, 0.0}), EkfStatus::kBadInput);
  EXPECT_EQ(ekf_.remove_landmark(4), EkfStatus::kUnknownLandmark);
  EXPECT_EQ(ekf_.remove_landmark(11), EkfStatus::kBadInput);
  EXPECT_TRUE(Snapshot(ekf_) == before);
  // Full: capacity 3.
  ASSERT_EQ(ekf_.add_landmark(4, {2.0, 0.5}), EkfStatus::kOk);
  const Snapshot full(ekf_);
  EXPECT_EQ(ekf_.add_landmark(5, {2.0, 0.0}), EkfStatus::kFull);
  EXPECT_TRUE(Snapshot(ekf_) == full);
}

TEST_F(EkfRefusal, BadOdometryLeavesTheFilterUnchanged) {
  const Snapshot before(ekf_);
  const Eigen::Matrix3d U = odometry_covariance({0.5, 0.0, 0.0}, kOdoNoise);
  Eigen::Matrix3d nan_U = U, asym_U = U, neg_U = U;
  nan_U(1, 2) = std::nan("");
  asym_U(0, 1) = 1e-3;
  neg_U(2, 2) = -1e-6;
  EXPECT_EQ(ekf_.predict({std::nan(""), 0.0, 0.0}, U), EkfStatus::kBadInput);
  EXPECT_EQ(ekf_.predict({0.5, 0.0, HUGE_VAL}, U), EkfStatus::kBadInput);
  EXPECT_EQ(ekf_.predict({0.5, 0.0, 0.0}, nan_U), EkfStatus::kBadInput);
  EXPECT_EQ(ekf_.predict({0.5, 0.0, 0.0}, Eigen::Matrix3d::Constant(HUGE_VAL)), EkfStatus::kBadInput);
  EXPECT_EQ(ekf_.predict({0.5, 0.0, 0.0}, asym_U), EkfStatus::kBadInput);
  EXPECT_EQ(ekf_.predict({0.5, 0.0, 0.0}, neg_U), EkfStatus::kBadInput);
  EXPECT_EQ(ekf_.predict({0.5, 0.0, 0.0}, U, -0.1), EkfStatus::kBadInput);  // dt [s]
  EXPECT_EQ(ekf_.predict({0.5, 0.0, 0.0}, U, std::nan("")), EkfStatus::kBadInput);
  EXPECT_EQ(ekf_.predict({0.5, 0.0, 0.0}, U, HUGE_VAL), EkfStatus::kBadInput);
  EXPECT_TRUE(Snapshot(ekf_) == before);
}

// An indefinite odometry covariance (non-negative diagonal, so it passes the input
// checks) at a 45 degree heading gives the robot a negative variance: refused.
TEST(EkfFault, PredictRefusesANegativeVariance) {
  EkfSlam ekf(EkfOptions{});
  ekf.reset({0.0, 0.0, kPi / 4}, Eigen::Matrix3d::Identity() * 1e-6);
  ASSERT_EQ(ekf.add_landmark(1, {3.0, 0.0}), EkfStatus::kOk);
  const Snapshot before(ekf);
  Eigen::Matrix3d U;
  U << 1.0, 5.0, 0.0, 5.0, 1.0, 0.0, 0.0, 0.0, 1.0;  // eigenvalues 6, -4, 1
  EXPECT_EQ(ekf.predict({0.1, 0.0, 0.0}, U), EkfStatus::kCovarianceFault);
  EXPECT_TRUE(Snapshot(ekf) == before);
}

// The robot gets an indefinite covariance that is independent of a well-known
// landmark; observing the landmark would then drive the heading variance negative
// (the Schur complement of an indefinite matrix). Both forms refuse it.
TEST(EkfFault, UpdateRefusesANegativeVariance) {
  for (const bool joseph : {true, false}) {
    EkfOptions o;
    o.joseph = joseph;
    EkfSlam ekf(o);
    ekf.reset({0.0, 0.0, 0.0}, Eigen::Matrix3d::Identity() * 1e-8);
    ASSERT_EQ(ekf.add_landmark(1, {1.0, 0.0}), EkfStatus::kOk);
    Eigen::Matrix3d U;
    U << 1.0, 0.0, 0.9, 0.0, 1.0, 0.9, 0.9, 0.9, 1.0;  // indefinite, diagonal > 0
    ASSERT_EQ(ekf.predict({0.0, 0.0, 0.0}, U), EkfStatus::kOk);  // heading 0: F_u = I
    const Snapshot before(ekf);
    const UpdateReport r = ekf.update(1, observe(ekf.pose(), ekf.landmark(1)));
    EXPECT_EQ(r.status, EkfStatus::kCovarianceFault) << "joseph " << joseph << ": " << to_string(r.status);
    EXPECT_TRUE(Snapshot(ekf) == before);
  }
}

TEST(EkfFault, SingularInnovationCovarianceIsRefused) {
  // Robot x-y covariance 5 with variances 1: H P H^T + W is indefinite.
  EkfSlam ekf(EkfOptions{});
  ekf.reset({0.0, 0.0, 0.0}, Eigen::Matrix3d::Identity() * 1e-8);
  ASSERT_EQ(ekf.add_landmark(1, {1.0, 0.0}), EkfStatus::kOk);
  Eigen::Matrix3d U;
  U << 1.0, 5.0, 0.0, 5.0, 1.0, 0.0, 0.0, 0.0, 1.0;
  ASSERT_EQ(ekf.predict({0.0, 0.0, 0.0}, U), EkfStatus::kOk);
  const Snapshot before(ekf);
  const RangeBearing y = observe(ekf.pose(), ekf.landmark(1));
  EXPECT_EQ(ekf.check(1, y).status, EkfStatus::kSingular);
  EXPECT_EQ(ekf.update(1, y).status, EkfStatus::kSingular);
  EXPECT_TRUE(Snapshot(ekf) == before);
}

// ---- gate ------------------------------------------------------------------------------------

TEST_F(EkfRefusal, GateRefusesAFarObservationAndAcceptsANearOne) {
  const Snapshot before(ekf_);
  RangeBearing far = predicted(7);
  far.range += 3.0;  // 30 sigma
  const UpdateReport check_far = ekf_.check(7, far);
  const UpdateReport gated = ekf_.update(7, far, true);
  EXPECT_EQ(gated.status, EkfStatus::kGated);
  EXPECT_GT(gated.d2, gated.threshold);
  EXPECT_EQ(gated.threshold, ekf_.gate_threshold());
  EXPECT_NEAR(gated.threshold, chi2_quantile(0.99, 2), 1e-9);  // 9.21
  EXPECT_NEAR(gated.innovation(0), 3.0, 1e-12);
  EXPECT_TRUE(Snapshot(ekf_) == before);
  // check() gives the same numbers and changes nothing.
  EXPECT_EQ(check_far.status, EkfStatus::kOk);
  EXPECT_EQ(check_far.d2, gated.d2);
  EXPECT_EQ(check_far.threshold, ekf_.gate_threshold());

  RangeBearing near = predicted(7);
  near.range += 0.05;  // half a sigma
  const UpdateReport ok = ekf_.update(7, near, true);
  EXPECT_EQ(ok.status, EkfStatus::kOk);
  EXPECT_LT(ok.d2, ok.threshold);
  EXPECT_FALSE(Snapshot(ekf_) == before);
  // Without the gate the far observation is applied, and threshold reports 0.
  const UpdateReport ungated = ekf_.update(7, far, false);
  EXPECT_EQ(ungated.status, EkfStatus::kOk);
  EXPECT_EQ(ungated.threshold, 0.0);
}

TEST_F(EkfRefusal, BearingInnovationIsWrapped) {
  // Landmark 7 seen at a bearing just across the +-pi seam from the prediction.
  EkfSlam ekf(options());
  ekf.reset({0.0, 0.0, 0.0}, Eigen::Matrix3d::Identity() * 1e-4);
  ASSERT_EQ(ekf.add_landmark(7, {5.0, kPi - 0.001}), EkfStatus::kOk);
  const UpdateReport r = ekf.check(7, {5.0, -kPi + 0.001});
  EXPECT_NEAR(r.innovation(1), 0.002, 1e-9);
  EXPECT_LT(r.d2, 1.0);
}

// ---- accessors and misc --------------------------------------------------------------------

TEST(EkfSlam, AccessorsAndLayout) {
  EkfOptions o;
  o.capacity = 4;
  o.max_landmark_id = 8;
  o.range_sigma = 0.2;
  o.bearing_sigma = 0.05;
  EkfSlam ekf(o);
  EXPECT_EQ(ekf.capacity(), 4);
  EXPECT_EQ(ekf.num_landmarks(), 0);
  EXPECT_EQ(ekf.state_dim(), 6);  // the pose and the (frozen) calibration states
  EXPECT_EQ(Layout::kVehicleDim, 6);
  EXPECT_EQ(Layout::landmark_offset(0), 6);
  EXPECT_EQ(Layout::landmark_offset(2), 10);
  EXPECT_NEAR(ekf.measurement_cov()(0, 0), 0.04, 1e-15);
  EXPECT_NEAR(ekf.measurement_cov()(1, 1), 0.0025, 1e-15);
  EXPECT_EQ(ekf.measurement_cov()(0, 1), 0.0);
  ekf.reset({1.0, 1.0, 7.0}, Eigen::Vector3d(0.1, 0.2, 0.3).asDiagonal());
  EXPECT_NEAR(ekf.pose().theta, wrap_angle(7.0), 1e-15);
  EXPECT_NEAR(ekf.mean_diag(), 0.2, 1e-15);  // eq 19
  ASSERT_EQ(ekf.add_landmark(6, {2.0, 0.0}), EkfStatus::kOk);
  EXPECT_EQ(ekf.slot_of(6), 0);
  EXPECT_EQ(ekf.id_at(0), 6);
  EXPECT_EQ(ekf.slot_of(5), -1);
  EXPECT_EQ(ekf.slot_of(100), -1);
  EXPECT_EQ(ekf.state_dim(), 8);
  EXPECT_NEAR(ekf.mean_diag(), ekf.covariance().trace() / 5.0, 1e-15);  // 5: pose and landmark, not C
  EXPECT_TRUE((ekf.landmark_cov(6) == ekf.covariance().block<2, 2>(6, 6)));
  EXPECT_TRUE((ekf.pose_landmark_cov(6) == ekf.covariance().block<3, 2>(0, 6)));
  // Frozen calibration: the configured constants, no variance.
  EXPECT_EQ(ekf.calibration().turn_scale, 1.0);
  EXPECT_EQ(ekf.calibration().speed_scale, 1.0);
  EXPECT_EQ(ekf.calibration().turn_bias, 0.0);
  EXPECT_TRUE(ekf.calibration_cov().isZero(0.0));
  EXPECT_FALSE(ekf.calibration_estimated());
  EXPECT_TRUE(ekf.landmark_cross_cov(6, 1).hasNaN());
  EXPECT_TRUE(ekf.pose_landmark_cov(2).hasNaN());
  // reset forgets the map and frees the ids.
  ekf.reset({}, Eigen::Matrix3d::Zero());
  EXPECT_EQ(ekf.num_landmarks(), 0);
  EXPECT_FALSE(ekf.has_landmark(6));
}

TEST(EkfSlam, InvalidOptionsAreRefusedAtConstruction) {
  EkfOptions o;
  o.capacity = -1;
  EXPECT_THROW(EkfSlam{o}, std::invalid_argument);
  o = EkfOptions{};
  o.range_sigma = 0.0;
  EXPECT_THROW(EkfSlam{o}, std::invalid_argument);
  o = EkfOptions{};
  o.gate_probability = 1.0;
  EXPECT_THROW(EkfSlam{o}, std::invalid_argument);
  EXPECT_NO_THROW(EkfSlam{EkfOptions{}});
}

TEST(EkfSlam, StatusNames) {
  EXPECT_STREQ(to_string(EkfStatus::kOk), "ok");
  EXPECT_STREQ(to_string(EkfStatus::kGated), "gated");
  EXPECT_STREQ(to_string(EkfStatus::kUnknownLandmark), "unknown_landmark");
  EXPECT_STREQ(to_string(EkfStatus::kAlreadyMapped), "already_mapped");
  EXPECT_STREQ(to_string(EkfStatus::kFull), "full");
  EXPECT_STREQ(to_string(EkfStatus::kBadInput), "bad_input");
  EXPECT_STREQ(to_string(EkfStatus::kSingular), "singular");
  EXPECT_STREQ(to_string(EkfStatus::kCovarianceFault), "covariance_fault");
}

}  // namespace
}  // namespace elaslam

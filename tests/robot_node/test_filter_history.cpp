// SPDX-License-Identifier: Apache-2.0
// FilterHistory: a candidate's landmark-only corrections made full ones after the
// fact give the filter that trusted it from the start (to rounding); without an
// upgrade the filter is left alone; a full ring commits early and stays exact.
#include "elaslam/robot_node/filter_history.hpp"

#include <vector>

#include <gtest/gtest.h>

#include "ekf_test_world.hpp"

namespace elaslam {
namespace {

using test::difference;
using test::RandomWorld;
using test::kOdoNoise;
using test::small_options;

// Three filters driven through the same frames: `current` (with the history) and
// `trusted` hold the candidate as the robot does and as a filter that trusted it
// from its first sighting does; mapped landmarks 0-3 are corrected in every frame.
struct Frames {
  explicit Frames(bool joseph, int window, int max_ops)
      : o(small_options(joseph)), current(o), trusted(o), history(o, window, max_ops), w(0x415 + (joseph ? 1 : 0)) {
    const Eigen::Matrix3d P0 = Eigen::Vector3d(1e-4, 1e-4, 1e-5).asDiagonal();
    current.reset(w.truth, P0);
    trusted.reset(w.truth, P0);
    for (int id = 0; id < 4; ++id) {
      const RangeBearing z = w.sense(id, o);
      current.add_landmark(id, z);
      trusted.add_landmark(id, z);
    }
    history.restart(current);
  }
  // One frame: a prediction, the mapped landmarks, then `candidate` seen: added
  // when new, else corrected alone (current) or fully (trusted, when `trust`).
  void frame(int k, int candidate, bool trust) {
    const Pose2 u = w.move();
    const Eigen::Matrix3d U = odometry_covariance(u, kOdoNoise);
    ASSERT_EQ(current.predict(u, U), EkfStatus::kOk);
    trusted.predict(u, U);
    history.record(FilterHistory::predict(k, u, U));
    for (int id = 0; id < 4; ++id) {
      const RangeBearing z = w.sense(id, o);
      ASSERT_EQ(current.update(id, z).status, EkfStatus::kOk);
      trusted.update(id, z);
      history.record(FilterHistory::update(k, id, z));
    }
    const RangeBearing z = w.sense(candidate, o);
    if (!current.has_landmark(candidate)) {
      current.add_landmark(candidate, z);
      trusted.add_landmark(candidate, z);
      history.record(FilterHistory::add(k, candidate, z));
    } else {
      ASSERT_EQ(current.update_landmark_only(candidate, z).status, EkfStatus::kOk);
      history.record(FilterHistory::update_landmark_only(k, candidate, z));
      if (trust) {
        trusted.update(candidate, z);
      } else {
        trusted.update_landmark_only(candidate, z);
      }
    }
  }
  EkfOptions o;
  EkfSlam current, trusted;
  FilterHistory history;
  RandomWorld w;
};

class FilterHistoryForms : public ::testing::TestWithParam<bool> {};

TEST_P(FilterHistoryForms, AConfirmedCandidateCorrectsAsIfTrustedFromItsFirstSighting) {
  // GIVEN a window of 3 frames (at a confirmation in frame k, frames k-3..k are
  // held); candidate 5 first seen in frame 10, then in frames 11-12
  Frames r(GetParam(), 3, 200);
  for (int k = 1; k < 10; ++k) {
    // candidate 6 seen in frames 1-8, never confirmed (landmark-only in both); 7 new in 9
    r.frame(k, k < 9 ? 6 : 7, false);
    r.history.end_frame(k, &r.current);
  }
  for (int k = 10; k < 13; ++k) {
    r.frame(k, 5, true);
    if (k < 12) r.history.end_frame(k, &r.current);
  }
  ASSERT_GT(difference(r.current, r.trusted), 1e-6);  // they differ before the upgrade
  // WHEN it is confirmed in frame 12
  EXPECT_EQ(r.history.upgrade(5), 2);
  EXPECT_EQ(r.history.upgrade(6), 0);  // its last sighting (frame 8) is older than the window
  EXPECT_EQ(r.history.end_frame(12, &r.current), 0);
  // THEN the filter is the one that trusted it from the start, candidate 6 included
  EXPECT_LT(difference(r.current, r.trusted), 1e-9);
  EXPECT_EQ(r.history.rebuilds(), 1);
  // and goes on as that one does
  for (int k = 13; k < 20; ++k) {
    r.frame(k, 6, false);
    r.history.end_frame(k, &r.current);
  }
  EXPECT_LT(difference(r.current, r.trusted), 1e-9);
}

TEST_P(FilterHistoryForms, WithoutAnUpgradeTheFilterIsLeftAlone) {
  Frames r(GetParam(), 3, 200);
  for (int k = 1; k < 15; ++k) {
    r.frame(k, 5, false);
    const Eigen::VectorXd x = r.current.mean();
    EXPECT_EQ(r.history.end_frame(k, &r.current), 0);
    EXPECT_EQ(r.current.mean(), x);
  }
  EXPECT_EQ(r.history.rebuilds(), 0);
  EXPECT_LT(difference(r.current, r.trusted), 1e-12);
  // The window holds the last 3 frames' operations: 6 per frame (predict, 4 + 1).
  EXPECT_EQ(r.history.held(), 3 * 6);
}

TEST_P(FilterHistoryForms, AFullRingCommitsTheOldestEarlyAndStaysExact) {
  // GIVEN a ring of 6 operations (a frame has 6): only the confirming frame's are
  // held, however long the window
  Frames r(GetParam(), 5, 6);
  r.frame(1, 5, false);  // first sighting: the add
  r.frame(2, 5, false);  // its landmark-only update leaves the ring early: stays so
  r.frame(3, 5, true);   // still held
  EXPECT_EQ(r.history.held(), 6);
  EXPECT_EQ(r.history.upgrade(5), 1);
  EXPECT_EQ(r.history.end_frame(3, &r.current), 0);
  EXPECT_LT(difference(r.current, r.trusted), 1e-9);
}

// A saved history restored into a smaller ring (a node with a shorter window): the
// oldest operations go into the lagged filter, and lagged + held still give the
// filter the history was saved from.
TEST_P(FilterHistoryForms, RestoredIntoASmallerRingTheOldestGoIntoTheLaggedFilter) {
  Frames r(GetParam(), 3, 200);
  for (int k = 1; k < 8; ++k) {
    r.frame(k, 5, false);
    r.history.end_frame(k, &r.current);
  }
  std::vector<FilterHistory::Op> ops;
  for (int k = 0; k < r.history.held(); ++k) ops.push_back(r.history.op(k));
  ASSERT_EQ(ops.size(), 18u);
  const EkfSlam& lagged = *r.history.lagged();
  std::vector<int> ids;
  for (int slot = 0; slot < lagged.num_landmarks(); ++slot) ids.push_back(lagged.id_at(slot));
  FilterHistory small(r.o, 1, 6);
  ASSERT_EQ(small.restore(lagged.mean(), lagged.covariance(), ids, ops), EkfStatus::kOk);
  EXPECT_EQ(small.held(), 6);
  EkfSlam replay(r.o);
  replay.assign(*small.lagged());
  for (int k = 0; k < small.held(); ++k) ASSERT_TRUE(FilterHistory::apply(small.op(k), &replay));
  EXPECT_LT(difference(replay, r.current), 1e-12);
}

INSTANTIATE_TEST_SUITE_P(BothCovarianceForms, FilterHistoryForms, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& i) {
                           return i.param ? std::string("Joseph") : std::string("Standard");
                         });

TEST(FilterHistory, OffRecordsNothingAndChangesNothing) {
  const EkfOptions o = small_options(false);
  FilterHistory h(o, 0, 100);
  EXPECT_FALSE(h.enabled());
  EkfSlam f(o);
  f.reset({0.0, 0.0, 0.0}, 1e-4 * Eigen::Matrix3d::Identity());
  h.restart(f);
  h.record(FilterHistory::add(0, 3, {2.0, 0.1}));
  EXPECT_EQ(h.held(), 0);
  EXPECT_EQ(h.upgrade(3), 0);
  EXPECT_EQ(h.end_frame(5, &f), 0);
  EXPECT_EQ(f.num_landmarks(), 0);
}

}  // namespace
}  // namespace elaslam

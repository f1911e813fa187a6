// SPDX-License-Identifier: Apache-2.0
// FilterPair: the aided filter sees every operation the own filter takes, so
// without team increments the two are the same filter, bit for bit; a team
// increment moves the aided filter alone and stays in its history; an operation the
// own filter refuses never reaches the aided one; a relocalisation moves each by its
// own motion; without the aided filter the estimate is the own filter.
#include "elaslam/robot_node/filter_pair.hpp"

#include <gtest/gtest.h>

#include "ekf_test_world.hpp"

namespace elaslam {
namespace {

using test::kOdoNoise;
using test::RandomWorld;
using test::small_options;

// Bit-identical: the same landmarks in the same slots, the same mean and covariance.
bool same(const EkfSlam& a, const EkfSlam& b) { return test::difference(a, b) == 0.0; }

// Frames of a random world through `pair`: predict, correct landmarks 0-3 (added at
// frame 0), landmark 4 refined alone from frame 2, removed at frame 6.
int drive(FilterPair* pair, RandomWorld* w, const EkfOptions& o, int frames) {
  int faults = 0;
  pair->reset(w->truth, Eigen::Vector3d(1e-4, 1e-4, 1e-5).asDiagonal());
  for (int id = 0; id < 4; ++id) EXPECT_EQ(pair->add(0, id, w->sense(id, o), &faults), EkfStatus::kOk);
  for (int k = 1; k <= frames; ++k) {
    const Pose2 u = w->move();
    EXPECT_EQ(pair->predict(k, u, odometry_covariance(u, kOdoNoise), 0.1, &faults), EkfStatus::kOk);
    for (int id = 0; id < 4; ++id) EXPECT_EQ(pair->update(k, id, w->sense(id, o), true, &faults).status, EkfStatus::kOk);
    if (k == 1) {
      EXPECT_EQ(pair->add(k, 4, w->sense(4, o), &faults), EkfStatus::kOk);
    }
    if (k >= 2 && k < 6) pair->update_landmark_only(k, 4, w->sense(4, o), &faults);
    if (k == 6) {
      EXPECT_EQ(pair->remove(k, 4), EkfStatus::kOk);
    }
    faults += pair->end_frame(k);
  }
  return faults;
}

// A pair of small_options(false) filters driven `frames` frames through the random
// world of `seed`; `faults` is what drive counted.
struct DrivenPair {
  DrivenPair(std::uint64_t seed, int frames, bool aided = true, int history_frames = 0, int history_ops = 64)
      : pair(o, aided, history_frames, history_ops), w(seed), faults(drive(&pair, &w, o, frames)) {}
  const EkfOptions o = small_options(false);
  FilterPair pair;
  RandomWorld w;
  const int faults;
};

TEST(FilterPair, WithoutTeamIncrementsTheTwoFiltersAreOne) {
  DrivenPair d(0x51, 10, /*aided=*/true, /*history_frames=*/0, /*history_ops=*/64);
  FilterPair& pair = d.pair;
  EXPECT_EQ(d.faults, 0);
  ASSERT_TRUE(pair.has_aided());
  EXPECT_EQ(pair.own().num_landmarks(), 4);
  EXPECT_TRUE(same(pair.own(), pair.aided()));
  EXPECT_EQ(&pair.estimate(), &pair.aided());
}

TEST(FilterPair, ATeamIncrementMovesTheAidedFilterAlone) {
  DrivenPair d(0x52, 5, true, /*history_frames=*/3, /*history_ops=*/256);
  FilterPair& pair = d.pair;
  const Eigen::VectorXd own_before = pair.own().mean();
  const Eigen::Vector2d z = pair.aided().landmark(2) + Eigen::Vector2d(0.05, -0.03);
  const Eigen::Matrix2d R = 0.01 * Eigen::Matrix2d::Identity();
  const UpdateReport r = pair.update_aided_position(5, 2, z, R);
  ASSERT_EQ(r.status, EkfStatus::kOk);
  EXPECT_EQ(pair.own().mean(), own_before);
  EXPECT_FALSE(same(pair.own(), pair.aided()));
  // The aided filter moved towards the increment.
  EXPECT_LT((pair.aided().landmark(2) - z).norm(), (pair.own().landmark(2) - z).norm());
  // Both histories restart from their filters as they are: still apart.
  pair.restart_history();
  EXPECT_FALSE(same(pair.own(), pair.aided()));
}

TEST(FilterPair, AnOperationTheOwnFilterRefusesNeverReachesTheAidedOne) {
  DrivenPair d(0x53, 3);
  FilterPair& pair = d.pair;
  RandomWorld& w = d.w;
  const EkfOptions& o = d.o;
  int faults = 0;
  EXPECT_EQ(pair.add(4, 1, w.sense(1, o), &faults), EkfStatus::kAlreadyMapped);  // landmark 1 is held
  EXPECT_EQ(pair.remove(4, 9), EkfStatus::kUnknownLandmark);  // landmark 9 is not
  // An outlier the own filter's innovation gate refuses corrects neither.
  const RangeBearing outlier{w.sense(0, o).range + 3.0, w.sense(0, o).bearing};
  EXPECT_EQ(pair.update(4, 0, outlier, true, &faults).status, EkfStatus::kGated);
  EXPECT_EQ(faults, 0);
  EXPECT_TRUE(same(pair.own(), pair.aided()));
}

TEST(FilterPair, ARelocalisationMovesEachFilterByItsOwnMotion) {
  DrivenPair d(0x54, 3);
  FilterPair& pair = d.pair;
  const Pose2 own0 = pair.own().pose(), aided0 = pair.aided().pose();
  ASSERT_EQ(pair.apply_rigid_motion(0.5, Eigen::Vector2d(1.0, 0.0), -0.25, Eigen::Vector2d(0.0, 2.0)), EkfStatus::kOk);
  EXPECT_NEAR(wrap_angle(pair.own().pose().theta - own0.theta), 0.5, 1e-12);
  EXPECT_NEAR(wrap_angle(pair.aided().pose().theta - aided0.theta), -0.25, 1e-12);
  const Eigen::Vector2d own_expected = rotation(0.5) * own0.translation() + Eigen::Vector2d(1.0, 0.0);
  EXPECT_LT((pair.own().pose().translation() - own_expected).norm(), 1e-12);
}

TEST(FilterPair, WithoutTheAidedFilterTheEstimateIsTheOwn) {
  DrivenPair d(0x55, 4, /*aided=*/false);
  FilterPair& pair = d.pair;
  EXPECT_EQ(d.faults, 0);
  EXPECT_FALSE(pair.has_aided());
  EXPECT_EQ(&pair.estimate(), &pair.own());
  EXPECT_EQ(pair.apply_rigid_motion(0.1, Eigen::Vector2d(0.0, 0.0), 0.0, Eigen::Vector2d(0.0, 0.0)), EkfStatus::kOk);
}

}  // namespace
}  // namespace elaslam

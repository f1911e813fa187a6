// SPDX-License-Identifier: Apache-2.0
// Proof that the filter's frame path allocates nothing after construction
// (docs/design.md section 3). Two independent guards watch the region:
//  - Eigen's EIGEN_RUNTIME_NO_MALLOC: every Eigen heap allocation asserts (the
//    filter's code is linked from elaslam_robot_no_malloc, the library's sources
//    built with the guard and asserts on; this target inherits both);
//  - a replaced global operator new that counts calls made inside the region.
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <new>
#include <random>
#include <string>
#include <tuple>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "../support/no_alloc.hpp"
#include "elaslam/robot_node/ekf_slam.hpp"
#include "elaslam/robot_node/mover_track.hpp"

#ifndef EIGEN_RUNTIME_NO_MALLOC
#error "test_ekf_no_alloc must be compiled with EIGEN_RUNTIME_NO_MALLOC"
#endif
#ifdef NDEBUG
#error "test_ekf_no_alloc needs assertions (Eigen's guard is an eigen_assert)"
#endif

namespace elaslam {
namespace {

using test::NoAllocRegion;  // tests/support/no_alloc.hpp: Eigen guard + counting operator new

int* volatile g_sink = nullptr;  // keeps the compiler from eliding new/delete pairs

// Statuses collected inside the region and checked outside it (gtest allocates).
struct Tally {
  std::array<int, 8> count{};
  void add(EkfStatus s) { ++count[static_cast<std::size_t>(s)]; }
  int of(EkfStatus s) const { return count[static_cast<std::size_t>(s)]; }
};

// Many frames of the node's work, successful and failing calls alike.
void run_frames(EkfSlam& ekf, std::mt19937_64& rng, int frames, Tally* tally) {
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const int max_id = ekf.options().max_landmark_id;
  for (int f = 0; f < frames; ++f) {
    const Pose2 u{0.3 + 0.1 * uni(rng), 0.05 * uni(rng), 0.1 * uni(rng)};
    tally->add(ekf.predict(u, odometry_covariance(u, OdometryNoise{1e-3, 1e-3, 1e-4}), 0.1));
    for (int k = 0; k < 12; ++k) {
      const int id = static_cast<int>((uni(rng) + 1.0) * 0.5 * (max_id - 1));
      const RangeBearing z{5.0 + 3.0 * uni(rng), 3.0 * uni(rng)};
      if (!ekf.has_landmark(id)) {
        tally->add(ekf.add_landmark(id, z));  // kOk or kFull
        continue;
      }
      RangeBearing y = observe(ekf.pose(), ekf.landmark(id));
      y.range = std::max(y.range + 0.05 * uni(rng), 0.01);
      tally->add(ekf.check(id, y).status);
      tally->add(ekf.update(id, y, k % 2 == 0).status);
      if (k == 5) tally->add(ekf.update(id, {y.range + 50.0, y.bearing}, true).status);  // kGated
      if (k == 7) {  // the team map's position measurement (update_position), and a refused one
        const Eigen::Matrix2d R = 0.04 * Eigen::Matrix2d::Identity();
        tally->add(ekf.check_position(id, ekf.landmark(id), R).status);
        tally->add(ekf.update_position(id, ekf.landmark(id) + Eigen::Vector2d(0.01, -0.01), R).status);
        tally->add(ekf.update_position(id, ekf.landmark(id), -R).status);
      }
    }
    // Failing calls must not allocate either (no error strings, no exceptions).
    tally->add(ekf.update(0, {nan, 0.0}).status);
    tally->add(ekf.update(max_id, {1.0, 0.0}).status);
    tally->add(ekf.add_landmark(-1, {1.0, 0.0}));
    tally->add(ekf.predict({nan, 0.0, 0.0}, Eigen::Matrix3d::Identity()));
    tally->add(ekf.remove_landmark(max_id + 3));
    for (int id = 0; id < max_id; ++id) {  // the first unmapped id
      if (ekf.has_landmark(id)) continue;
      tally->add(ekf.check(id, {1.0, 0.0}).status);
      tally->add(ekf.update(id, {1.0, 0.0}).status);
      break;
    }
    // Readers: the block accessors, and the full view (completes the upper triangle).
    if (ekf.num_landmarks() > 1) {
      const Eigen::Matrix2d c = ekf.landmark_cross_cov(ekf.id_at(0), ekf.id_at(1)) +
                                ekf.landmark_cov(ekf.id_at(1));
      tally->add(c.allFinite() ? EkfStatus::kOk : EkfStatus::kCovarianceFault);
    }
    if (f % 10 == 0) {
      const double trace = ekf.covariance().trace();
      tally->add(std::isfinite(trace + ekf.mean_diag()) ? EkfStatus::kOk
                                                        : EkfStatus::kCovarianceFault);
    }
    if (f % 3 == 0 && ekf.num_landmarks() > 0) {
      const int slot = static_cast<int>((uni(rng) + 1.0) * 0.5 * (ekf.num_landmarks() - 1));
      tally->add(ekf.remove_landmark(ekf.id_at(slot)));
    }
  }
}

// Parameters: (Joseph form, the odometer's calibration estimated).
class EkfNoAlloc : public ::testing::TestWithParam<std::tuple<bool, bool>> {};

TEST_P(EkfNoAlloc, FramePathAllocatesNothing) {
  EkfOptions o;
  o.capacity = 24;
  o.max_landmark_id = 40;
  o.joseph = std::get<0>(GetParam());
  if (std::get<1>(GetParam())) {
    o.calibration.turn_scale_sigma = o.calibration.speed_scale_sigma = 0.1;
    o.calibration.turn_bias_sigma = 0.01;
    o.calibration.turn_scale_walk = o.calibration.speed_scale_walk = 1e-3;
    o.calibration.turn_bias_walk = 1e-4;
  }
  EkfSlam ekf(o);  // all allocation happens here
  ekf.reset({0.0, 0.0, 0.0}, Eigen::Matrix3d::Identity() * 1e-4);
  std::mt19937_64 rng(4242);
  Tally tally;
  long allocations = -1;
  {
    NoAllocRegion guard;
    run_frames(ekf, rng, 300, &tally);
    allocations = test::allocations_in_region();
  }
  EXPECT_EQ(allocations, 0);
  // The region really exercised every path.
  EXPECT_GT(tally.of(EkfStatus::kOk), 3000);
  EXPECT_GT(tally.of(EkfStatus::kFull), 0);
  EXPECT_GT(tally.of(EkfStatus::kGated), 0);
  EXPECT_GT(tally.of(EkfStatus::kBadInput), 1000);
  EXPECT_GT(tally.of(EkfStatus::kUnknownLandmark), 0);
  EXPECT_EQ(tally.of(EkfStatus::kCovarianceFault), 0);
  EXPECT_EQ(tally.of(EkfStatus::kSingular), 0);
  EXPECT_GT(ekf.num_landmarks(), 0);
  EXPECT_EQ(ekf.calibration_cov()(0, 0) > 0.0, std::get<1>(GetParam()));
}

INSTANTIATE_TEST_SUITE_P(BothCovarianceForms, EkfNoAlloc, ::testing::Combine(::testing::Bool(), ::testing::Bool()),
                         [](const ::testing::TestParamInfo<std::tuple<bool, bool>>& i) {
                           return std::string(std::get<0>(i.param) ? "Joseph" : "Standard") +
                                  (std::get<1>(i.param) ? "Calibrated" : "");
                         });

// A mover track's frame: the IMM's mixing, prediction (several steps when frames
// were missed), updates, outliers held back and restarts, and its read-outs.
TEST(MoverTrackNoAlloc, FramesAllocateNothing) {
  MoverTrack track;
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  TrackSighting s;
  s.R = Eigen::Vector2d(0.0025, 3e-4).asDiagonal();
  s.pose_cov = Eigen::Vector3d(4e-4, 4e-4, 2.5e-5).asDiagonal();
  track.start(Eigen::Vector2d(3.0, 1.0), Eigen::Matrix2d::Identity() * 0.01, Eigen::Vector2d(3.0, 1.0), 0.0);
  long allocations = -1;
  double sum = 0.0;
  int restarts = 0, outliers = 0;
  {
    NoAllocRegion guard;
    for (int k = 1; k <= 400; ++k) {
      track.predict(k * 0.1 + (k % 50 == 0 ? 0.5 : 0.0));
      // A jump of the bearing at k = 97 and 194 (held back, then followed), one at
      // k = 291 alone (held back).
      const bool jumped = (k >= 97 && k < 291 && (k / 97) % 2 == 1) || k == 291;
      s.z = {3.2 + 0.05 * uni(rng), 0.3 + (jumped ? 1.5 : 0.0) + 0.02 * uni(rng)};
      const TrackUpdate u = track.update(s);
      restarts += u.restarted ? 1 : 0;
      outliers += u.outlier ? 1 : 0;
      sum += track.mean()(0) + track.covariance()(0, 0) + (track.validated() ? 1.0 : 0.0);
    }
    allocations = test::allocations_in_region();
  }
  EXPECT_EQ(allocations, 0);
  EXPECT_EQ(restarts, 2);  // the restart path ran inside the region: to the jump and back
  EXPECT_EQ(outliers, 3);
  EXPECT_TRUE(std::isfinite(sum));
}

TEST(EkfNoAllocGuard, CounterSeesAnAllocation) {
  long allocations = -1;
  {
    NoAllocRegion guard;
    g_sink = new int(3);
    delete g_sink;
    allocations = test::allocations_in_region();
  }
  EXPECT_EQ(allocations, 1);
}

TEST(EkfNoAllocGuard, EigenGuardCatchesAHeapAllocation) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_DEATH(
      {
        NoAllocRegion guard;
        Eigen::MatrixXd m(64, 64);
        m.setZero();
      },
      "heap allocation is forbidden");
}

}  // namespace
}  // namespace elaslam

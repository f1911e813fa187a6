// SPDX-License-Identifier: Apache-2.0
// EKF frame time: one frame = one predict + 15 updates, as the robot node does per
// sensor frame, with 16 to 512 landmarks in the map. EkfSlam (sparse H, the
// frame's covariance steps in one pass of rank 2 (symmetric) or 4 (Joseph) per
// update, O(n^2 k) per frame) against a dense textbook EKF in the same binary
// (full n x n products with a dense 2 x n H, O(n^3) per update).
//   build/bin/bench_ekf --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// Results and the machine: docs/benchmarks.md.
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>
#include <benchmark/benchmark.h>

#include "elaslam/robot_node/ekf_slam.hpp"
#include "elaslam/robot_node/mover_track.hpp"
// The filter's private kernels, for the covariance step alone (BM_CovarianceStep);
// the others are not used here.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#include "../robot_node/src/ekf_kernels.hpp"
#include "../tests/support/dense_augment.hpp"
#pragma GCC diagnostic pop

namespace elaslam {
namespace {

constexpr int kUpdatesPerFrame = 15;

// A robot at the origin among `n` landmarks within 20 m, with one fixed noisy
// observation of each (the robot does not move: u = 0, but U is not).
struct Scene {
  explicit Scene(int n) {
    std::mt19937_64 rng(1234);
    std::uniform_real_distribution<double> pos(-20.0, 20.0);
    std::normal_distribution<double> noise(0.0, 1.0);
    for (int i = 0; i < n; ++i) {
      Eigen::Vector2d l(pos(rng), pos(rng));
      if (l.norm() < 1.0) l.x() += 2.0;
      RangeBearing z = observe(Pose2{}, l);
      z.range += 0.05 * noise(rng);
      z.bearing += 0.005 * noise(rng);
      observations.push_back(z);
    }
  }
  std::vector<RangeBearing> observations;  // by id
  Eigen::Matrix3d U = Eigen::Vector3d(1e-4, 1e-4, 1e-5).asDiagonal();
  Eigen::Matrix3d P0 = Eigen::Vector3d(1e-4, 1e-4, 1e-5).asDiagonal();
};

EkfOptions options_for(int n, bool joseph) {
  EkfOptions o;
  o.capacity = n;
  o.max_landmark_id = n;
  o.range_sigma = 0.05;
  o.bearing_sigma = 0.005;
  o.joseph = joseph;
  return o;
}

// ---- the dense textbook reference (eqs 4-5, 8-12, 15 as printed) ---------------------

class DenseEkf {
 public:
  explicit DenseEkf(const EkfOptions& o) {
    W_ = Eigen::Vector2d(o.range_sigma * o.range_sigma, o.bearing_sigma * o.bearing_sigma)
             .asDiagonal();
  }
  void reset(const Eigen::Matrix3d& P0) {
    X_ = Eigen::Vector3d::Zero();
    P_ = P0;
  }
  void add(const RangeBearing& y) {
    test::dense_augment(y, W_, &X_, &P_);
    // Workspace for the frame, sized once (allocation is not what we measure).
    const Eigen::Index m = X_.size();
    F_ = Eigen::MatrixXd::Identity(m, m);
    G_ = Eigen::MatrixXd::Zero(m, 3);
    H_ = Eigen::MatrixXd::Zero(2, m);
    IKH_.resize(m, m);
    tmp_.resize(m, m);
    K_.resize(m, 2);
  }
  void predict(const Pose2& u, const Eigen::Matrix3d& U) {
    Eigen::Matrix3d F_x, F_u;
    const Pose2 next = motion(pose(), u, &F_x, &F_u);
    F_.topLeftCorner<3, 3>() = F_x;
    G_.topRows<3>() = F_u;
    X_.head<3>() << next.x, next.y, next.theta;
    tmp_.noalias() = F_ * P_;
    P_.noalias() = tmp_ * F_.transpose();
    P_.noalias() += G_ * U * G_.transpose();
  }
  void update(int slot, const RangeBearing& y) {
    const Eigen::Index off = 3 + 2 * slot;  // its state is [R; M], without calibration states
    Eigen::Matrix<double, 2, 3> H_x;
    Eigen::Matrix2d H_l;
    const RangeBearing h = observe(pose(), X_.segment<2>(off), &H_x, &H_l);
    H_.setZero();
    H_.leftCols<3>() = H_x;
    H_.middleCols<2>(off) = H_l;
    const Eigen::Vector2d nu(y.range - h.range, wrap_angle(y.bearing - h.bearing));
    const Eigen::Matrix2d Z = H_ * P_ * H_.transpose() + W_;
    K_.noalias() = P_ * H_.transpose() * Z.inverse();
    X_ += K_ * nu;
    X_(2) = wrap_angle(X_(2));
    IKH_.setIdentity();
    IKH_.noalias() -= K_ * H_;
    tmp_.noalias() = IKH_ * P_;
    P_.noalias() = tmp_ * IKH_.transpose();
    P_.noalias() += K_ * W_ * K_.transpose();
  }
  Pose2 pose() const { return {X_(0), X_(1), X_(2)}; }

 private:
  Eigen::Matrix2d W_;
  Eigen::VectorXd X_;
  Eigen::MatrixXd P_, F_, G_, H_, IKH_, tmp_, K_;
};

// ---- benchmarks ----------------------------------------------------------------------------

void run_ekf_frames(benchmark::State& state, bool joseph, bool full_view, bool calibrated = false) {
  const int n = static_cast<int>(state.range(0));
  const Scene scene(n);
  EkfOptions o = options_for(n, joseph);
  if (calibrated) {  // the odometer's calibration states estimated
    o.calibration.turn_scale_sigma = o.calibration.speed_scale_sigma = 0.1;
    o.calibration.turn_bias_sigma = 0.02;
    o.calibration.turn_scale_walk = o.calibration.speed_scale_walk = 1e-3;
    o.calibration.turn_bias_walk = 1e-4;
  }
  EkfSlam ekf(o);
  ekf.reset(Pose2{}, scene.P0);
  for (int id = 0; id < n; ++id) ekf.add_landmark(id, scene.observations[static_cast<std::size_t>(id)]);
  int next = 0;
  int failures = 0;
  for (auto _ : state) {
    failures += ekf.predict(Pose2{}, scene.U, 0.1) != EkfStatus::kOk;
    for (int k = 0; k < kUpdatesPerFrame; ++k) {
      const int id = next;
      next = (next + 1) % n;
      failures += ekf.update(id, scene.observations[static_cast<std::size_t>(id)]).status !=
                  EkfStatus::kOk;
    }
    if (full_view) benchmark::DoNotOptimize(ekf.covariance().data());
    benchmark::ClobberMemory();
  }
  if (failures != 0) state.SkipWithError("a filter call failed");
  state.counters["state_dim"] = ekf.state_dim();
}

// Default options: the symmetric form, the frame's 15 covariance steps in one
// rank-30 pass (applied at the next predict, inside the timed loop).
void BM_EkfSlamFrame(benchmark::State& state) { run_ekf_frames(state, false, false); }
void BM_EkfSlamFrameJosephForm(benchmark::State& state) { run_ekf_frames(state, true, false); }
// The same frame, then the full covariance view (completes the upper triangle):
// what a caller pays per frame if it needs all of P rather than blocks of it.
void BM_EkfSlamFrameWithFullView(benchmark::State& state) { run_ekf_frames(state, false, true); }
// The default frame with the odometer's calibration states estimated: the
// prediction's cross terms read 6 columns instead of 3.
void BM_EkfSlamFrameCalibrated(benchmark::State& state) { run_ekf_frames(state, false, false, true); }

void BM_DenseEkfFrame(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const Scene scene(n);
  DenseEkf ekf(options_for(n, true));
  ekf.reset(scene.P0);
  for (int id = 0; id < n; ++id) ekf.add(scene.observations[static_cast<std::size_t>(id)]);
  int next = 0;
  for (auto _ : state) {
    ekf.predict(Pose2{}, scene.U);
    for (int k = 0; k < kUpdatesPerFrame; ++k) {
      ekf.update(next, scene.observations[static_cast<std::size_t>(next)]);
      next = (next + 1) % n;
    }
    benchmark::ClobberMemory();
  }
}

// The frame's covariance step alone: the lower triangle of a state of n landmarks
// minus a rank-30 product (15 updates' factors, the symmetric form), the kernel
// EkfSlam applies once per frame. Its rate of fused multiply-adds is the practical
// ceiling of this machine for the frame (docs/benchmarks.md).
void BM_CovarianceStep(benchmark::State& state) {
  const int n = StateLayout::dim(static_cast<int>(state.range(0)));
  const int m = 2 * kUpdatesPerFrame;
  const Eigen::Index ld = n, ldf = n + kFactorPadRows;
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> u(-1e-3, 1e-3);
  Eigen::MatrixXd P = Eigen::MatrixXd::Identity(n, n);
  Eigen::MatrixXd F(ldf, m);
  for (Eigen::Index i = 0; i < F.size(); ++i) F.data()[i] = u(rng);
  for (auto _ : state) {
    lower_factor_downdate(P.data(), ld, n, F.data(), F.data(), ldf, m);
    benchmark::DoNotOptimize(P.data());
    benchmark::ClobberMemory();
  }
  const double fma = 0.5 * n * (n + 1.0) * m;  // one per entry of the triangle and factor column
  state.counters["FMA_per_s"] = benchmark::Counter(fma, benchmark::Counter::kIsIterationInvariantRate);
}

// Mover tracks' frame (robot_node/mover_track.hpp): each of n tracks mixed,
// predicted over one 0.1 s frame and updated with one sighting, as a frame with n
// movers in view would cost on top of the filter's (BM_EkfSlamFrame).
void BM_MoverTracksFrame(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  std::vector<MoverTrack> tracks(static_cast<std::size_t>(n));
  std::vector<TrackSighting> sightings(static_cast<std::size_t>(n));
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < n; ++i) {
    TrackSighting& s = sightings[static_cast<std::size_t>(i)];
    s.z = {2.0 + 1.5 * (u(rng) + 1.0), 3.0 * u(rng)};
    s.R = Eigen::Vector2d(0.0025, 3e-4).asDiagonal();
    s.pose_cov = Eigen::Vector3d(4e-4, 4e-4, 2.5e-5).asDiagonal();
    tracks[static_cast<std::size_t>(i)].start(s, inverse_observe(s.pose, s.z), 0.0);
  }
  double t = 0.0;
  for (auto _ : state) {
    t += 0.1;
    for (int i = 0; i < n; ++i) {
      MoverTrack& track = tracks[static_cast<std::size_t>(i)];
      track.predict(t);
      benchmark::DoNotOptimize(track.update(sightings[static_cast<std::size_t>(i)]).d2);
    }
    benchmark::ClobberMemory();
  }
}

void landmark_counts(benchmark::internal::Benchmark* b) {
  for (const int n : {16, 72, 150, 256, 512, 1024}) b->Arg(n);
  b->ArgName("landmarks")->Unit(benchmark::kMicrosecond);
}
// The dense reference stops at 512: at 1,024 one frame takes about half a minute.
void dense_landmark_counts(benchmark::internal::Benchmark* b) {
  for (const int n : {16, 72, 150, 256, 512}) b->Arg(n);
  b->ArgName("landmarks")->Unit(benchmark::kMicrosecond);
}

BENCHMARK(BM_EkfSlamFrame)->Apply(landmark_counts);
BENCHMARK(BM_EkfSlamFrameJosephForm)->Apply(landmark_counts);
BENCHMARK(BM_EkfSlamFrameWithFullView)->Apply(landmark_counts);
BENCHMARK(BM_EkfSlamFrameCalibrated)->Apply(landmark_counts);
BENCHMARK(BM_DenseEkfFrame)->Apply(dense_landmark_counts);
BENCHMARK(BM_CovarianceStep)->Apply(landmark_counts);
BENCHMARK(BM_MoverTracksFrame)->Arg(1)->Arg(36)->ArgName("tracks")->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace elaslam

BENCHMARK_MAIN();

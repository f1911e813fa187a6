// SPDX-License-Identifier: Apache-2.0
// Test support for the EKF tests: a dense textbook EKF (the known answer), a small
// random world, and random filter operations on both.
#pragma once

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>
#include <gtest/gtest.h>

#include "elaslam/robot_node/ekf_slam.hpp"
#include "../support/dense_augment.hpp"

namespace elaslam::test {

using Layout = StateLayout;
using Vec2 = Eigen::Vector2d;

// ---- dense textbook EKF: the known answer ------------------------------------------

// Full X = [R; C; M], full P, dense Jacobians of the whole state; eqs 4-5, 8-12 and
// 15 as printed, with O(n^3) products; the odometer's calibration states C as
// models.hpp states them (F_V = [[F_x, F_u du/dc], [0, I]], noise F_u J_r U J_r^T F_u^T,
// random walk over dt), propagated densely whether estimated or frozen. Landmarks are kept in insertion order and removed
// by deleting their rows and columns, so slots differ from EkfSlam's after a removal:
// the comparison goes by id.
class DenseEkf {
 public:
  explicit DenseEkf(const EkfOptions& o) : joseph_(o.joseph), cal_(o.calibration) {
    W_ = Vec2(o.range_sigma * o.range_sigma, o.bearing_sigma * o.bearing_sigma).asDiagonal();
  }
  void reset(const Pose2& pose, const Eigen::Matrix3d& cov) {
    X_ = Eigen::VectorXd(Layout::kVehicleDim);
    X_ << pose.x, pose.y, pose.theta, cal_.prior.turn_scale, cal_.prior.speed_scale, cal_.prior.turn_bias;
    P_ = Eigen::MatrixXd::Zero(Layout::kVehicleDim, Layout::kVehicleDim);
    P_.topLeftCorner<3, 3>() = cov;
    P_.block<3, 3>(Layout::kCalibration, Layout::kCalibration) =
        Eigen::Vector3d(cal_.turn_scale_sigma * cal_.turn_scale_sigma, cal_.speed_scale_sigma * cal_.speed_scale_sigma,
                        cal_.turn_bias_sigma * cal_.turn_bias_sigma)
            .asDiagonal();
    ids_.clear();
  }
  void predict(const Pose2& u_reported, const Eigen::Matrix3d& U, double dt = 0.0) {
    const Eigen::Index n = X_.size();
    const OdometryCalibration c{X_(Layout::kTurnScale), X_(Layout::kSpeedScale), X_(Layout::kTurnBias)};
    Eigen::Matrix3d F_x, F_u, J_c, J_r;
    const Pose2 u = calibrated_increment(u_reported, c, dt, &J_c, &J_r);
    const Pose2 next = motion(pose(), u, &F_x, &F_u);
    Eigen::MatrixXd F = Eigen::MatrixXd::Identity(n, n);
    F.topLeftCorner<3, 3>() = F_x;
    F.block<3, 3>(0, Layout::kCalibration) = F_u * J_c;
    Eigen::MatrixXd G = Eigen::MatrixXd::Zero(n, 3);
    G.topRows<3>() = F_u * J_r;
    Eigen::MatrixXd Q = Eigen::MatrixXd::Zero(n, n);
    Q.block<3, 3>(Layout::kCalibration, Layout::kCalibration) =
        (dt * Eigen::Vector3d(cal_.turn_scale_walk * cal_.turn_scale_walk, cal_.speed_scale_walk * cal_.speed_scale_walk,
                              cal_.turn_bias_walk * cal_.turn_bias_walk))
            .asDiagonal();
    X_.head<3>() << next.x, next.y, next.theta;
    P_ = (F * P_ * F.transpose() + G * U * G.transpose() + Q).eval();
  }
  // The dense H (2 x n), innovation and its covariance of an observation of `id`.
  void linearise(int id, const RangeBearing& y, Eigen::MatrixXd* H, Vec2* nu, Eigen::Matrix2d* Z) const {
    const Eigen::Index off = offset(id);
    Eigen::Matrix<double, 2, 3> H_x;
    Eigen::Matrix2d H_l;
    const RangeBearing h = observe(pose(), X_.segment<2>(off), &H_x, &H_l);
    *H = Eigen::MatrixXd::Zero(2, X_.size());
    H->leftCols<3>() = H_x;
    H->middleCols<2>(off) = H_l;
    *nu = Vec2(y.range - h.range, wrap_angle(y.bearing - h.bearing));
    *Z = *H * P_ * H->transpose() + W_;
  }
  void update(int id, const RangeBearing& y) {
    Eigen::MatrixXd H;
    Vec2 nu;
    Eigen::Matrix2d Z;
    linearise(id, y, &H, &nu, &Z);
    correct(H, nu, Z, W_);
  }
  // Schmidt ("consider") update of landmark `id` alone: the textbook gain with
  // every row but the landmark's zeroed, and the Joseph form (valid for any gain).
  void update_landmark_only(int id, const RangeBearing& y) {
    const Eigen::Index n = X_.size(), off = offset(id);
    Eigen::MatrixXd H;
    Vec2 nu;
    Eigen::Matrix2d Z;
    linearise(id, y, &H, &nu, &Z);
    Eigen::MatrixXd K = Eigen::MatrixXd::Zero(n, 2);
    K.middleRows<2>(off) = (P_ * H.transpose() * Z.inverse()).middleRows<2>(off);
    X_ += K * nu;
    const Eigen::MatrixXd IKH = Eigen::MatrixXd::Identity(n, n) - K * H;
    P_ = (IKH * P_ * IKH.transpose() + K * W_ * K.transpose()).eval();
  }
  // A direct measurement z = l + v, v ~ N(0, R), of landmark `id`'s position:
  // H selects the landmark; textbook gain, Joseph or standard form.
  void update_position(int id, const Vec2& z, const Eigen::Matrix2d& R) {
    const Eigen::Index off = offset(id);
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(2, X_.size());
    H.middleCols<2>(off).setIdentity();
    correct(H, z - X_.segment<2>(off), H * P_ * H.transpose() + R, R);
  }
  void move_landmark(int id, const Vec2& delta, const Eigen::Matrix2d& Q) {
    const Eigen::Index off = offset(id);
    X_.segment<2>(off) += delta;
    P_.block<2, 2>(off, off) += Q;
  }
  void add(int id, const RangeBearing& y) {
    dense_augment(y, W_, &X_, &P_);
    ids_.push_back(id);
  }
  void remove(int id) {
    const Eigen::Index off = offset(id), n = X_.size();
    std::vector<Eigen::Index> keep;
    for (Eigen::Index i = 0; i < n; ++i)
      if (i != off && i != off + 1) keep.push_back(i);
    Eigen::VectorXd X(n - 2);
    Eigen::MatrixXd P(n - 2, n - 2);
    for (std::size_t i = 0; i < keep.size(); ++i) {
      X(static_cast<Eigen::Index>(i)) = X_(keep[i]);
      for (std::size_t j = 0; j < keep.size(); ++j)
        P(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = P_(keep[i], keep[j]);
    }
    X_ = X;
    P_ = P;
    ids_.erase(ids_.begin() + (off - Layout::kVehicleDim) / 2);
  }

  Pose2 pose() const { return {X_(0), X_(1), X_(2)}; }
  const Eigen::VectorXd& X() const { return X_; }
  const Eigen::MatrixXd& P() const { return P_; }
  const std::vector<int>& ids() const { return ids_; }

 private:
  // The textbook correction (eqs 10-12) with the dense H, innovation nu, its
  // covariance Z = H P H^T + R and the measurement noise R: Joseph or standard form.
  void correct(const Eigen::MatrixXd& H, const Vec2& nu, const Eigen::Matrix2d& Z, const Eigen::Matrix2d& R) {
    const Eigen::Index n = X_.size();
    const Eigen::MatrixXd K = P_ * H.transpose() * Z.inverse();
    X_ += K * nu;
    X_(2) = wrap_angle(X_(2));
    if (joseph_) {
      const Eigen::MatrixXd IKH = Eigen::MatrixXd::Identity(n, n) - K * H;
      P_ = (IKH * P_ * IKH.transpose() + K * R * K.transpose()).eval();
    } else {
      P_ = (P_ - K * Z * K.transpose()).eval();
    }
  }
  Eigen::Index offset(int id) const {
    for (std::size_t k = 0; k < ids_.size(); ++k)
      if (ids_[k] == id) return Layout::landmark_offset(static_cast<int>(k));
    ADD_FAILURE() << "dense reference: unknown id " << id;
    return 0;
  }
  bool joseph_;
  CalibrationOptions cal_;
  Eigen::Matrix2d W_;
  Eigen::VectorXd X_;
  Eigen::MatrixXd P_;
  std::vector<int> ids_;
};

// Largest difference between the two filters, matching landmarks by id.
inline double max_difference(const EkfSlam& ekf, const DenseEkf& ref) {
  if (ekf.state_dim() != ref.X().size()) return HUGE_VAL;
  std::vector<Eigen::Index> index = {0, 1, 2, 3, 4, 5};  // reference index -> EkfSlam index (the vehicle block)
  for (const int id : ref.ids()) {
    const int slot = ekf.slot_of(id);
    if (slot < 0) return HUGE_VAL;
    index.push_back(Layout::landmark_offset(slot));
    index.push_back(Layout::landmark_offset(slot) + 1);
  }
  double d = 0.0;
  for (std::size_t i = 0; i < index.size(); ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    const double dx = ekf.mean()(index[i]) - ref.X()(ii);
    d = std::max(d, std::abs(i == Layout::kTheta ? wrap_angle(dx) : dx));
    for (std::size_t j = 0; j < index.size(); ++j) {
      d = std::max(d, std::abs(ekf.covariance()(index[i], index[j]) -
                               ref.P()(ii, static_cast<Eigen::Index>(j))));
    }
  }
  return d;
}

// ---- a small random world ---------------------------------------------------------------

// The truth for the random operation sequences: a robot wandering among landmarks
// with ids 0..num_ids-1 within 15 m of the origin.
struct RandomWorld {
  explicit RandomWorld(std::uint64_t seed, int num_ids = 25) : rng(seed) {
    for (int id = 0; id < num_ids; ++id) landmarks.push_back({uniform(-15, 15), uniform(-15, 15)});
  }
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }
  double gauss(double sigma) { return std::normal_distribution<double>(0.0, sigma)(rng); }
  int pick(int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng); }
  // True motion by a random increment; returns the noisy odometry reading.
  Pose2 move() {
    Pose2 u{uniform(0.0, 0.5), uniform(-0.1, 0.1), uniform(-0.3, 0.3)};
    if (compose(truth, u).translation().norm() > 12.0) u.theta += kPi;  // turn back, stay in
    truth = compose(truth, u);
    return {u.x + gauss(0.02), u.y + gauss(0.02), u.theta + gauss(0.01)};
  }
  RangeBearing sense(int id, const EkfOptions& o) {
    const RangeBearing h = observe(truth, landmarks[static_cast<std::size_t>(id)]);
    return {std::max(h.range + gauss(o.range_sigma), 0.05),
            wrap_angle(h.bearing + gauss(o.bearing_sigma))};
  }
  std::mt19937_64 rng;
  Pose2 truth{0.0, 0.0, 0.3};
  std::vector<Vec2> landmarks;
};

inline const OdometryNoise kOdoNoise{1e-3, 1e-3, 1e-4};
inline constexpr double kStepSeconds = 0.1;  // [s] the time each random prediction spans

struct OpCounts {
  int predicts = 0, updates = 0, adds = 0, removes = 0;
};

// One random operation on both filters (the reference may be null). Every call
// must succeed; the result is compared by the caller.
inline OpCounts random_operation(RandomWorld& w, EkfSlam& ekf, DenseEkf* ref,
                                 int max_landmarks) {
  OpCounts c;
  const double r = w.uniform(0.0, 1.0);
  const int n = ekf.num_landmarks();
  if (r < 0.3) {
    const Pose2 u = w.move();
    const Eigen::Matrix3d U = odometry_covariance(u, kOdoNoise);
    EXPECT_EQ(ekf.predict(u, U, kStepSeconds), EkfStatus::kOk);
    if (ref != nullptr) ref->predict(u, U, kStepSeconds);
    c.predicts = 1;
  } else if (r < 0.7 && n > 0) {
    const int id = ekf.id_at(w.pick(n));
    const RangeBearing z = w.sense(id, ekf.options());
    EXPECT_EQ(ekf.update(id, z).status, EkfStatus::kOk);
    if (ref != nullptr) ref->update(id, z);
    c.updates = 1;
  } else if (r < 0.9 && n < max_landmarks) {
    int id = w.pick(static_cast<int>(w.landmarks.size()));
    while (ekf.has_landmark(id)) id = (id + 1) % static_cast<int>(w.landmarks.size());
    const RangeBearing z = w.sense(id, ekf.options());
    EXPECT_EQ(ekf.add_landmark(id, z), EkfStatus::kOk);
    if (ref != nullptr) ref->add(id, z);
    c.adds = 1;
  } else if (n > 0) {
    const int id = ekf.id_at(w.pick(n));
    EXPECT_EQ(ekf.remove_landmark(id), EkfStatus::kOk);
    if (ref != nullptr) ref->remove(id);
    c.removes = 1;
  }
  return c;
}

inline EkfOptions small_options(bool joseph) {
  EkfOptions o;
  o.capacity = 20;
  o.max_landmark_id = 64;
  o.range_sigma = 0.05;
  o.bearing_sigma = 0.01;
  o.joseph = joseph;
  return o;
}

/// Largest difference of mean and covariance between two filters holding the same
/// landmarks in the same slots (HUGE_VAL when they do not: another size or order).
inline double difference(const EkfSlam& a, const EkfSlam& b) {
  if (a.state_dim() != b.state_dim()) return HUGE_VAL;
  for (int slot = 0; slot < a.num_landmarks(); ++slot)
    if (a.id_at(slot) != b.id_at(slot)) return HUGE_VAL;
  return std::max((a.mean() - b.mean()).cwiseAbs().maxCoeff(), (a.covariance() - b.covariance()).cwiseAbs().maxCoeff());
}

}  // namespace elaslam::test

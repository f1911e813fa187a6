// SPDX-License-Identifier: Apache-2.0
// Constructed scenes for the robot-node tests: a filter holding a known map, and
// frames observed from known true poses.
#pragma once

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "elaslam/robot_node/ekf_slam.hpp"
#include "elaslam/robot_node/ela_gate.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/robot_node/robot.hpp"
#include "elaslam/sensor_frame_t.hpp"

namespace elaslam::test {

inline EkfOptions filter_options() {
  EkfOptions o;
  o.capacity = 64;
  o.max_landmark_id = 64;
  o.range_sigma = 0.05;
  o.bearing_sigma = 0.01;
  return o;
}

inline RobotOptions robot_options(Mode mode) {
  RobotOptions o;
  o.mode = mode;
  o.ekf = filter_options();
  o.sensor_range = 6.0;
  o.fov_margin = 0.5;
  o.confirm_frames = 3;
  o.return_frames = 6;
  o.moving_after = 2;
  o.missing_frames = 3;
  return o;
}

/// Landmarks on a ring of radius r around the origin.
inline std::vector<Eigen::Vector2d> ring(int n, double r) {
  std::vector<Eigen::Vector2d> v;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * kPi * i / n + 0.1;
    v.emplace_back(r * std::cos(a), r * std::sin(a));
  }
  return v;
}

/// A filter at `pose` (tiny prior) that has mapped `lms` (ids 0..n-1) from exact observations.
inline EkfSlam mapped_filter(const Pose2& pose, const std::vector<Eigen::Vector2d>& lms,
                             const EkfOptions& o = filter_options()) {
  EkfSlam ekf(o);
  ekf.reset(pose, Eigen::Matrix3d::Identity() * 1e-6);
  for (int i = 0; i < static_cast<int>(lms.size()); ++i) ekf.add_landmark(i, observe(pose, lms[static_cast<std::size_t>(i)]));
  return ekf;
}

/// True worlds drawn from a filter's own distribution, x = mean + chol(P) n: for
/// tests of the gates' false-alarm rates (a consistent filter's tests fire at their
/// nominal rate on such draws). Landmarks by id 0..n-1.
class WorldSampler {
 public:
  WorldSampler(const EkfSlam& ekf, int num_landmarks)
      : ekf_(ekf), n_(num_landmarks), mean_(ekf.mean()), L_(Eigen::LLT<Eigen::MatrixXd>(sampled_cov(ekf)).matrixL()) {}
  /// One draw: the true pose, the true landmarks, and the whole state x.
  void draw(std::mt19937_64* rng, Pose2* pose, std::vector<Eigen::Vector2d>* landmarks, Eigen::VectorXd* x = nullptr) const {
    std::normal_distribution<double> n01;
    Eigen::VectorXd n = Eigen::VectorXd::Zero(mean_.size());
    const bool frozen = !ekf_.calibration_estimated();
    for (Eigen::Index i = 0; i < n.size(); ++i) {
      const bool calibration = i >= StateLayout::kCalibration && i < StateLayout::kVehicleDim;
      if (!(frozen && calibration)) n[i] = n01(*rng);  // frozen: constants, no draw (sampled_cov)
    }
    const Eigen::VectorXd s = mean_ + L_ * n;
    *pose = Pose2{s[0], s[1], s[2]};
    landmarks->clear();
    for (int i = 0; i < n_; ++i) landmarks->push_back(s.segment<2>(StateLayout::landmark_offset(ekf_.slot_of(i))));
    if (x) *x = s;
  }

 private:
  // P, with a frozen calibration's zero block (constants: no variance, which a
  // Cholesky factor does not take) replaced by the identity, and set back after each draw.
  static Eigen::MatrixXd sampled_cov(const EkfSlam& ekf) {
    Eigen::MatrixXd P = ekf.covariance();
    if (!ekf.calibration_estimated()) P.block<3, 3>(StateLayout::kCalibration, StateLayout::kCalibration).setIdentity();
    return P;
  }
  const EkfSlam& ekf_;
  int n_;
  Eigen::VectorXd mean_;
  Eigen::MatrixXd L_;
};

/// One frame seen from `truth` with odometer reading `odometer`; `noise` adds
/// Gaussian range/bearing noise (sigmas of the filter options) when given.
inline FrameInput frame_from(int frame, const Pose2& truth, const Pose2& odometer,
                             const std::vector<Eigen::Vector2d>& lms, const std::vector<int>& ids,
                             std::mt19937_64* noise = nullptr, const EkfOptions& o = filter_options()) {
  FrameInput in;
  in.frame = frame;
  in.odometer = odometer;
  in.noise = {1e-4, 1e-4, 1e-4};
  std::normal_distribution<double> n01(0.0, 1.0);
  for (int id : ids) {
    RangeBearing z = observe(truth, lms[static_cast<std::size_t>(id)]);
    if (noise) {
      z.range += o.range_sigma * n01(*noise);
      z.bearing = wrap_angle(z.bearing + o.bearing_sigma * n01(*noise));
    }
    in.obs[static_cast<std::size_t>(in.num_obs++)] = {id, z};
  }
  return in;
}

inline std::vector<int> all_ids(std::size_t n) {
  std::vector<int> v;
  for (std::size_t i = 0; i < n; ++i) v.push_back(static_cast<int>(i));
  return v;
}

/// The landmarks `lms` (ids 0..n-1) as seen from `truth`, as ElaGate's view holds
/// them (local position and its covariance from the filter's measurement noise).
inline std::vector<InView> view_of(const EkfSlam& ekf, const Pose2& truth, const std::vector<Eigen::Vector2d>& lms,
                                   std::mt19937_64* rng) {
  const FrameInput in = frame_from(0, truth, truth, lms, all_ids(lms.size()), rng);
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

/// The largest difference between two filters that hold landmarks 0..n-1, compared
/// by id (their slots may differ): pose, landmark positions and every covariance block.
inline double max_difference_by_id(const EkfSlam& a, const EkfSlam& b, int n) {
  double d = std::max({std::fabs(a.pose().x - b.pose().x), std::fabs(a.pose().y - b.pose().y),
                       std::fabs(a.pose().theta - b.pose().theta), (a.pose_cov() - b.pose_cov()).cwiseAbs().maxCoeff()});
  for (int i = 0; i < n; ++i) {
    d = std::max({d, (a.landmark(i) - b.landmark(i)).cwiseAbs().maxCoeff(),
                  (a.pose_landmark_cov(i) - b.pose_landmark_cov(i)).cwiseAbs().maxCoeff()});
    for (int j = 0; j < n; ++j) d = std::max(d, (a.landmark_cross_cov(i, j) - b.landmark_cross_cov(i, j)).cwiseAbs().maxCoeff());
  }
  return d;
}

/// A frame as robot `robot_id`'s SENSOR message (utime 1000 + frame).
inline sensor_frame_t to_msg(const FrameInput& in, int robot_id) {
  sensor_frame_t m{};
  m.utime = 1000 + in.frame;
  m.frame = in.frame;
  m.robot_id = static_cast<int16_t>(robot_id);
  m.odom_x = in.odometer.x;
  m.odom_y = in.odometer.y;
  m.odom_theta = in.odometer.theta;
  m.odom_var_trans_per_m = in.noise.var_trans_per_m;
  m.odom_var_rot_per_rad = in.noise.var_rot_per_rad;
  m.odom_var_rot_per_m = in.noise.var_rot_per_m;
  contract::set_count(&m.obs, &m.num_obs, in.num_obs);
  for (int k = 0; k < in.num_obs; ++k) {
    m.obs[static_cast<std::size_t>(k)].landmark_id = in.obs[static_cast<std::size_t>(k)].landmark_id;
    m.obs[static_cast<std::size_t>(k)].range = in.obs[static_cast<std::size_t>(k)].z.range;
    m.obs[static_cast<std::size_t>(k)].bearing = in.obs[static_cast<std::size_t>(k)].z.bearing;
  }
  return m;
}

}  // namespace elaslam::test

// SPDX-License-Identifier: Apache-2.0
#include "elaslam/robot_node/team_aid.hpp"

#include "elaslam/common/geometry.hpp"
#include "elaslam/robot_node/ekf_slam.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

namespace elaslam {

TeamChannel::TeamChannel(int max_landmark_id, double min_gain)
    : min_gain_(min_gain),
      Y_(static_cast<std::size_t>(std::max(max_landmark_id, 0)), Eigen::Matrix2d::Zero()),
      y_(static_cast<std::size_t>(std::max(max_landmark_id, 0)), Eigen::Vector2d::Zero()),
      epoch_(static_cast<std::size_t>(std::max(max_landmark_id, 0)), -1) {}

void TeamChannel::forget(int id) {
  if (id < 0 || id >= max_landmark_id()) return;
  Y_[static_cast<std::size_t>(id)].setZero();
  y_[static_cast<std::size_t>(id)].setZero();
  epoch_[static_cast<std::size_t>(id)] = -1;
}

void TeamChannel::restore(int id, int epoch, const Eigen::Matrix2d& Y, const Eigen::Vector2d& y) {
  if (id < 0 || id >= max_landmark_id()) return;
  Y_[static_cast<std::size_t>(id)] = Y;
  y_[static_cast<std::size_t>(id)] = y;
  epoch_[static_cast<std::size_t>(id)] = epoch;
}

void TeamChannel::clear() {
  std::fill(Y_.begin(), Y_.end(), Eigen::Matrix2d::Zero());
  std::fill(y_.begin(), y_.end(), Eigen::Vector2d::Zero());
  std::fill(epoch_.begin(), epoch_.end(), -1);
}

// dY = Y_new - Y_f = V diag(lambda) V^T. Directions with lambda > 0 carry the
// others' new information: there the measurement is v^T dy / lambda with variance
// 1 / lambda. Directions with none (lambda <= 0) get a variance a billion times the
// largest one and the current estimate as their value: no innovation, and an
// information of 1e-9 of the increment's, which the channel counts as fused.
bool TeamChannel::offer(int id, int epoch, const Eigen::Vector2d& g, const Eigen::Matrix2d& G, const Eigen::Vector2d& l,
                        const Eigen::Matrix2d& P_ll, TeamIncrement* out) const {
  if (id < 0 || id >= max_landmark_id() || !g.allFinite() || !G.allFinite() || !l.allFinite() || !P_ll.allFinite())
    return false;
  const Eigen::LLT<Eigen::Matrix2d> llt(0.5 * (G + G.transpose()));
  if (llt.info() != Eigen::Success) return false;
  const Eigen::Matrix2d Y_new = llt.solve(Eigen::Matrix2d::Identity());
  const Eigen::Vector2d y_new = Y_new * g;
  const auto i = static_cast<std::size_t>(id);
  const bool same = epoch == epoch_[i];  // else the landmark moved since: the team's data are new
  const Eigen::Matrix2d Y_f = same ? Y_[i] : Eigen::Matrix2d::Zero();
  const Eigen::Matrix2d dY = 0.5 * ((Y_new - Y_f) + (Y_new - Y_f).transpose());
  const Eigen::Vector2d dy = y_new - (same ? y_[i] : Eigen::Vector2d::Zero());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig;
  eig.computeDirect(dY);
  const Eigen::Vector2d lambda = eig.eigenvalues();  // ascending
  const Eigen::Matrix2d V = eig.eigenvectors();
  if (!(lambda(1) > 0.0) || !std::isfinite(lambda(1))) return false;
  const Eigen::Matrix2d dY_plus = V * lambda.cwiseMax(0.0).asDiagonal() * V.transpose();
  if (!((P_ll * dY_plus).trace() >= min_gain_)) return false;
  Eigen::Vector2d info = lambda, value;
  for (int k = 0; k < 2; ++k) {
    const Eigen::Vector2d v = V.col(k);
    if (lambda(k) > 1e-9 * lambda(1)) {
      value(k) = v.dot(dy) / lambda(k);
    } else {
      info(k) = 1e-9 * lambda(1);
      value(k) = v.dot(l);
    }
  }
  out->Y = V * info.asDiagonal() * V.transpose();
  out->z = V * value;
  out->R = V * info.cwiseInverse().asDiagonal() * V.transpose();
  out->R = 0.5 * (out->R + out->R.transpose()).eval();
  out->epoch = epoch;
  return true;
}

void TeamChannel::commit(int id, const TeamIncrement& inc) {
  if (id < 0 || id >= max_landmark_id()) return;
  const auto i = static_cast<std::size_t>(id);
  if (inc.epoch != epoch_[i]) {
    Y_[i].setZero();
    y_[i].setZero();
    epoch_[i] = inc.epoch;
  }
  Y_[i] += inc.Y;
  y_[i] += inc.Y * inc.z;
}

bool pose_drifted(const EkfSlam& own, const EkfSlam& aided, double threshold) {
  const Pose2 a = own.pose(), b = aided.pose();
  const Eigen::Vector3d d(a.x - b.x, a.y - b.y, wrap_angle(a.theta - b.theta));
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(own.pose_cov());
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0.0).all()) return false;
  return d.dot(ldlt.solve(d)) > threshold;
}

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// The textbook state augmentation (the paper's eq 15, as printed): a new landmark
// from the sighting `y` at the state's pose, with dense Jacobians J (n+2 x n) and
// Jz (n+2 x 2). Shared by the dense references the tests check EkfSlam against and
// the benchmark times it against.
#pragma once

#include <Eigen/Core>

#include "elaslam/robot_node/models.hpp"

namespace elaslam::test {

/// X (its pose in rows 0..2) and P grow by the landmark seen as `y` with noise W.
inline void dense_augment(const RangeBearing& y, const Eigen::Matrix2d& W, Eigen::VectorXd* X, Eigen::MatrixXd* P) {
  const Eigen::Index n = X->size();
  Eigen::Matrix<double, 2, 3> G_x;
  Eigen::Matrix2d G_z;
  const Eigen::Vector2d l = inverse_observe(Pose2{(*X)(0), (*X)(1), (*X)(2)}, y, &G_x, &G_z);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(n + 2, n), Jz = Eigen::MatrixXd::Zero(n + 2, 2);
  J.topRows(n).setIdentity();
  J.block(n, 0, 2, 3) = G_x;
  Jz.bottomRows<2>() = G_z;
  Eigen::VectorXd grown(n + 2);
  grown << *X, l;
  *X = grown;
  *P = (J * *P * J.transpose() + Jz * W * Jz.transpose()).eval();
}

}  // namespace elaslam::test

// SPDX-License-Identifier: Apache-2.0
#include "elaslam/robot_node/rigid_fit.hpp"

#include <cmath>
#include <limits>

#include <Eigen/Cholesky>

#include "elaslam/common/geometry.hpp"
#include "elaslam/robot_node/models.hpp"

namespace elaslam {

namespace {

// Gauss-Newton steps after the closed-form start. The cost is quadratic in t and
// nearly so in phi when the weights change little with phi: two or three steps
// settle it to rounding; the loop stops earlier then.
constexpr int kMaxIterations = 8;
constexpr double kStepTolerance = 1e-12;  // [rad] and [m]

// J = [[0, -1], [1, 0]]: d R(phi) / d phi = J R(phi).
Eigen::Vector2d perp(const Eigen::Vector2d& v) { return {-v.y(), v.x()}; }

}  // namespace

double aligned_d2(const PointPair& p, const RigidMotion& T) {
  const Eigen::Matrix2d R = rotation(T.rotation);
  const Eigen::Vector2d r = R * p.a + T.translation - p.b;
  return mahalanobis2(r, R * p.A * R.transpose() + p.B);
}

bool fit_rigid_motion(const PointPair* pairs, int n, RigidMotion* out) {
  if (n < 2) return false;
  // Closed-form start: weighted centroids and cross-covariance (scalar weights).
  double wsum = 0.0;
  Eigen::Vector2d ca = Eigen::Vector2d::Zero(), cb = Eigen::Vector2d::Zero();
  for (int i = 0; i < n; ++i) {
    const double tr = (pairs[i].A + pairs[i].B).trace();
    if (!(tr > 0.0) || !std::isfinite(tr)) return false;
    const double w = 2.0 / tr;
    wsum += w;
    ca += w * pairs[i].a;
    cb += w * pairs[i].b;
  }
  ca /= wsum;
  cb /= wsum;
  Eigen::Matrix2d S = Eigen::Matrix2d::Zero();
  for (int i = 0; i < n; ++i) {
    const double w = 2.0 / (pairs[i].A + pairs[i].B).trace();
    S += w * (pairs[i].a - ca) * (pairs[i].b - cb).transpose();
  }
  const double sin_part = S(0, 1) - S(1, 0), cos_part = S(0, 0) + S(1, 1);
  if (std::hypot(sin_part, cos_part) <= 1e-12 * std::max(1.0, S.cwiseAbs().maxCoeff())) return false;
  double phi = std::atan2(sin_part, cos_part);
  Eigen::Vector2d t = cb - rotation(phi) * ca;

  // Gauss-Newton on (phi, t) with the full weights C_i^-1 at the current phi.
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (int it = 0; it <= kMaxIterations; ++it) {
    const Eigen::Matrix2d R = rotation(phi);
    H.setZero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    double cost = 0.0;
    for (int i = 0; i < n; ++i) {
      const PointPair& p = pairs[i];
      const Eigen::Vector2d Ra = R * p.a;
      const Eigen::Vector2d r = Ra + t - p.b;
      const Eigen::LLT<Eigen::Matrix2d> llt(R * p.A * R.transpose() + p.B);
      if (llt.info() != Eigen::Success) return false;
      const Eigen::Matrix2d W = llt.solve(Eigen::Matrix2d::Identity());
      Eigen::Matrix<double, 2, 3> Jr;
      Jr.col(0) = perp(Ra);
      Jr.rightCols<2>().setIdentity();
      H += Jr.transpose() * W * Jr;
      g += Jr.transpose() * W * r;
      cost += r.dot(W * r);
    }
    out->cost = cost;
    if (it == kMaxIterations) break;
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(H);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0.0).all()) return false;
    const Eigen::Vector3d step = -ldlt.solve(g);
    if (!step.allFinite()) return false;
    phi = wrap_angle(phi + step(0));
    t += step.tail<2>();
    if (step.cwiseAbs().maxCoeff() < kStepTolerance) {
      it = kMaxIterations - 1;  // one more pass: H, the cost at the solution
    }
  }
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(H);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0.0).all()) return false;
  out->rotation = phi;
  out->translation = t;
  out->cov = ldlt.solve(Eigen::Matrix3d::Identity());
  out->cov = 0.5 * (out->cov + out->cov.transpose()).eval();
  return out->cov.allFinite();
}

}  // namespace elaslam

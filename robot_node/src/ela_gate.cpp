#include "elaslam/robot_node/ela_gate.hpp"

#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/LU>

namespace elaslam {
namespace {

// d2 = r^T C^-1 r for a 2x2 symmetric C; +inf when C is not positive definite.
double mahalanobis2(const Eigen::Vector2d& r, const Eigen::Matrix2d& C) {
  const double det = C(0, 0) * C(1, 1) - C(0, 1) * C(1, 0);
  if (!(det > 0.0) || !(C(0, 0) > 0.0)) return std::numeric_limits<double>::infinity();
  const Eigen::Matrix2d inv = (Eigen::Matrix2d() << C(1, 1), -C(0, 1), -C(1, 0), C(0, 0)).finished() / det;
  return r.dot(inv * r);
}

// Relative vector d_ij = l_i - l_j in W and its covariance S_ij.
void relative(const EkfSlam& ekf, int id_i, int id_j, Eigen::Vector2d* d, Eigen::Matrix2d* S) {
  *d = ekf.landmark(id_i) - ekf.landmark(id_j);
  const Eigen::Matrix2d Pij = ekf.landmark_cross_cov(id_i, id_j);
  *S = ekf.landmark_cov(id_i) + ekf.landmark_cov(id_j) - Pij - Pij.transpose();
}

// R(th)^T d and the covariance it carries: R^T S R + J var(th) J^T.
LocalPrediction rotate_into_body(const EkfSlam& ekf, const Eigen::Vector2d& d_W, const Eigen::Matrix2d& S_W) {
  const Pose2 pose = ekf.pose();
  const double var_th = ekf.pose_cov()(StateLayout::kTheta, StateLayout::kTheta);
  const Eigen::Matrix2d Rt = rotation(pose.theta).transpose();
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  // d/dth of R(th)^T d = [-s c; -c -s] d
  const Eigen::Vector2d J(-s * d_W.x() + c * d_W.y(), -c * d_W.x() - s * d_W.y());
  LocalPrediction p;
  p.mean = Rt * d_W;
  p.cov = Rt * S_W * Rt.transpose() + var_th * J * J.transpose();
  return p;
}

}  // namespace

const char* to_string(GateKind k) {
  switch (k) {
    case GateKind::kNone: return "none";
    case GateKind::kInnovation: return "innovation";
    case GateKind::kMulti: return "ela_multi";
    case GateKind::kConsensus: return "consensus";
    case GateKind::kCandidate: return "candidate";
  }
  return "?";
}

void set_local(InView* v, const Eigen::Matrix2d& W) {
  Eigen::Matrix2d J;
  v->m = observation_to_local(v->z, &J);
  v->M = J * W * J.transpose();
}

LocalPrediction predict_from_neighbour(const EkfSlam& ekf, int id_i, const InView& j) {
  Eigen::Vector2d d;
  Eigen::Matrix2d S;
  relative(ekf, id_i, j.id, &d, &S);
  LocalPrediction p = rotate_into_body(ekf, d, S);
  p.mean += j.m;
  p.cov += j.M;
  return p;
}

double pair_d2(const EkfSlam& ekf, const InView& i, const InView& j) {
  Eigen::Vector2d d;
  Eigen::Matrix2d S;
  relative(ekf, i.id, j.id, &d, &S);
  const LocalPrediction rel = rotate_into_body(ekf, d, S);
  return mahalanobis2((i.m - j.m) - rel.mean, i.M + j.M + rel.cov);
}

double ela_multi_d2(const EkfSlam& ekf, const InView* view, int n, int i, const std::uint8_t* active) {
  // Mean (eq 16): product of the Gaussians predicted from each neighbour j, i.e.
  // information weights W_j = (sum_k C_k^-1)^-1 C_j^-1, summing to I.
  Eigen::Matrix2d Lambda = Eigen::Matrix2d::Zero();
  Eigen::Vector2d eta = Eigen::Vector2d::Zero();
  for (int j = 0; j < n; ++j) {
    if (j == i || (active && !active[j])) continue;
    const LocalPrediction p = predict_from_neighbour(ekf, view[i].id, view[j]);
    const Eigen::LLT<Eigen::Matrix2d> llt(p.cov);
    if (llt.info() != Eigen::Success) continue;  // a degenerate neighbour adds no information
    const Eigen::Matrix2d info = llt.solve(Eigen::Matrix2d::Identity());
    Lambda += info;
    eta += info * p.mean;
  }
  const Eigen::LLT<Eigen::Matrix2d> llt(Lambda);
  if (llt.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
  const Eigen::Matrix2d fused_cov = llt.solve(Eigen::Matrix2d::Identity());
  const Eigen::Vector2d residual = view[i].m - fused_cov * eta;

  // Covariance of the residual. The product of Gaussians treats the neighbours'
  // predictions as independent, but they all contain l_i, the heading and
  // correlated map errors; (sum_j W_j C_j W_j^T) would be overconfident (a static
  // landmark then fails ~5x more often than the gate allows). So the weights are
  // kept and the residual's covariance is computed exactly from its parts:
  //   r = m_i - sum_j W_j (m_j + R^T (l_i - l_j)) - (sum_j W_j J_j) dth
  const Pose2 pose = ekf.pose();
  const Eigen::Matrix2d Rt = rotation(pose.theta).transpose();
  const double var_th = ekf.pose_cov()(StateLayout::kTheta, StateLayout::kTheta);
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  Eigen::Matrix2d cov = view[i].M;
  Eigen::Vector2d J = Eigen::Vector2d::Zero();
  Eigen::Matrix2d map_cov = Rt * ekf.landmark_cov(view[i].id) * Rt.transpose();  // R^T P_ii R
  for (int j = 0; j < n; ++j) {
    if (j == i || (active && !active[j])) continue;
    const LocalPrediction p = predict_from_neighbour(ekf, view[i].id, view[j]);
    const Eigen::LLT<Eigen::Matrix2d> lj(p.cov);
    if (lj.info() != Eigen::Success) continue;
    const Eigen::Matrix2d Wj = fused_cov * lj.solve(Eigen::Matrix2d::Identity());
    const Eigen::Matrix2d Aj = Wj * Rt;
    cov += Wj * view[j].M * Wj.transpose();
    const Eigen::Vector2d d = ekf.landmark(view[i].id) - ekf.landmark(view[j].id);
    J += Wj * Eigen::Vector2d(-s * d.x() + c * d.y(), -c * d.x() - s * d.y());
    const Eigen::Matrix2d cross = Rt * ekf.landmark_cross_cov(view[i].id, view[j].id) * Aj.transpose();
    map_cov -= cross + cross.transpose();  // - R^T P_ij A_j^T - A_j P_ji R
    for (int k = 0; k < n; ++k) {
      if (k == i || (active && !active[k])) continue;
      const LocalPrediction pk = predict_from_neighbour(ekf, view[i].id, view[k]);
      const Eigen::LLT<Eigen::Matrix2d> lk(pk.cov);
      if (lk.info() != Eigen::Success) continue;
      const Eigen::Matrix2d Ak = fused_cov * lk.solve(Eigen::Matrix2d::Identity()) * Rt;
      map_cov += Aj * ekf.landmark_cross_cov(view[j].id, view[k].id) * Ak.transpose();  // A_j P_jk A_k^T
    }
  }
  cov += map_cov + var_th * J * J.transpose();
  return mahalanobis2(residual, 0.5 * (cov + cov.transpose()));
}

}  // namespace elaslam

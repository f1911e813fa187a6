// SPDX-License-Identifier: Apache-2.0
#include "elaslam/robot_node/ela_gate.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "elaslam/common/contract.hpp"
#include "elaslam/common/stats.hpp"

namespace elaslam {
namespace {

// d/dth of R(th)^T d = [-s c; -c -s] d (c, s: cos and sin of th).
Eigen::Vector2d heading_jacobian(double c, double s, const Eigen::Vector2d& d) {
  return {-s * d.x() + c * d.y(), -c * d.x() - s * d.y()};
}

// A Gaussian prediction of where a landmark should appear in the robot frame.
struct LocalPrediction {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
};

// The heading's covariance with landmark `id`: row theta of P_Rl.
Eigen::RowVector2d heading_landmark_cov(const EkfSlam& ekf, int id) {
  return ekf.pose_landmark_cov(id).row(StateLayout::kTheta);
}

// Relative vector d_ij = l_i - l_j in W, its covariance S_ij and its covariance with
// the heading c_ij = P_th,li - P_th,lj.
void relative(const EkfSlam& ekf, int id_i, int id_j, Eigen::Vector2d* d, Eigen::Matrix2d* S, Eigen::RowVector2d* c) {
  *d = ekf.landmark(id_i) - ekf.landmark(id_j);
  const Eigen::Matrix2d Pij = ekf.landmark_cross_cov(id_i, id_j);
  *S = ekf.landmark_cov(id_i) + ekf.landmark_cov(id_j) - Pij - Pij.transpose();
  *c = heading_landmark_cov(ekf, id_i) - heading_landmark_cov(ekf, id_j);
}

// R(th)^T d and the covariance it carries, exactly to first order in the joint
// estimate (th, d): R^T S R + J var(th) J^T + R^T c^T J^T + J c R, with
// J = d(R(th)^T d)/d th. The cross term is large in SLAM: a map built under a
// heading error is rotated by it, so d's error and th's are strongly correlated.
LocalPrediction rotate_into_body(const EkfSlam& ekf, const Eigen::Vector2d& d_W, const Eigen::Matrix2d& S_W,
                                 const Eigen::RowVector2d& c_W) {
  const Pose2 pose = ekf.pose();
  const double var_th = ekf.pose_cov()(StateLayout::kTheta, StateLayout::kTheta);
  const Eigen::Matrix2d Rt = rotation(pose.theta).transpose();
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  const Eigen::Vector2d J = heading_jacobian(c, s, d_W);
  const Eigen::Matrix2d cross = J * (c_W * Rt.transpose());  // J Cov(th, d) R
  LocalPrediction p;
  p.mean = Rt * d_W;
  p.cov = Rt * S_W * Rt.transpose() + var_th * J * J.transpose() + cross + cross.transpose();
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
    case GateKind::kDrift: return "drift";
    case GateKind::kCandidateDrift: return "candidate_drift";
  }
  return "?";
}

void set_local(InView* v, const Eigen::Matrix2d& W) {
  Eigen::Matrix2d J;
  v->m = observation_to_local(v->z, &J);
  v->M = J * W * J.transpose();
}

double pair_d2(const EkfSlam& ekf, const InView& i, const InView& j) {
  Eigen::Vector2d d;
  Eigen::Matrix2d S;
  Eigen::RowVector2d c;
  relative(ekf, i.id, j.id, &d, &S, &c);
  const LocalPrediction rel = rotate_into_body(ekf, d, S, c);
  return mahalanobis2((i.m - j.m) - rel.mean, i.M + j.M + rel.cov);
}

Eigen::Matrix2d neighbour_weight(const EkfSlam& ekf, const InView& j) {
  const Eigen::Matrix2d Rt = rotation(ekf.pose().theta).transpose();
  const Eigen::LLT<Eigen::Matrix2d> llt(j.M + Rt * ekf.landmark_cov(j.id) * Rt.transpose());
  if (llt.info() != Eigen::Success) return Eigen::Matrix2d::Zero();  // a degenerate neighbour adds nothing
  return llt.solve(Eigen::Matrix2d::Identity());
}

double ela_multi_d2(const EkfSlam& ekf, const InView* view, int n, int i, const std::uint8_t* active) {
  // The reference computation (tests, benchmarks): scratch of its own, per call.
  std::vector<Eigen::Matrix2d> info(static_cast<std::size_t>(std::max(n, 0)));  // b_j, the weight of neighbour j
  std::vector<std::uint8_t> use(static_cast<std::size_t>(std::max(n, 0)), 0);    // j shapes the ELA (active, not i)
  const Eigen::Matrix2d Rt0 = rotation(ekf.pose().theta).transpose();
  // Mean: the predictions p_ij = m_j + R^T (l_i - l_j), fused with weights
  // W_j = (sum_k b_k)^-1 b_j, which sum to I.
  Eigen::Matrix2d Lambda = Eigen::Matrix2d::Zero();
  Eigen::Vector2d eta = Eigen::Vector2d::Zero();
  for (int j = 0; j < n; ++j) {
    if (j == i || (active && !active[j])) continue;
    const auto uj = static_cast<std::size_t>(j);
    info[uj] = neighbour_weight(ekf, view[j]);
    use[uj] = 1;
    Lambda += info[uj];
    eta += info[uj] * (view[j].m + Rt0 * (ekf.landmark(view[i].id) - ekf.landmark(view[j].id)));
  }
  const Eigen::LLT<Eigen::Matrix2d> llt(Lambda);
  if (llt.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
  const Eigen::Matrix2d fused_cov = llt.solve(Eigen::Matrix2d::Identity());
  const Eigen::Vector2d residual = view[i].m - fused_cov * eta;

  // Covariance of the residual. The predictions all contain l_i, the heading and
  // correlated map errors, so they are not independent (treating them so, a static
  // landmark failed ~5x more often than the gate allows). The residual's covariance
  // is computed exactly (to first order) from its parts, the residual being linear
  // in the estimate's errors e and the noises n:
  //   r = n_i - sum_j W_j n_j - R^T e_li + sum_j A_j e_lj - g e_th,
  //   A_j = W_j R^T, g = sum_j W_j J_j,
  // so cov(r) = M_i + sum_j W_j M_j W_j^T + H P H^T over (th, l_i, l_j...), the
  // heading-landmark cross-covariances included.
  const Pose2 pose = ekf.pose();
  const Eigen::Matrix2d Rt = rotation(pose.theta).transpose();
  const double var_th = ekf.pose_cov()(StateLayout::kTheta, StateLayout::kTheta);
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  std::vector<Eigen::Matrix2d> A(info.size());  // A_j = W_j R^T
  for (int j = 0; j < n; ++j)
    if (use[static_cast<std::size_t>(j)]) A[static_cast<std::size_t>(j)] = fused_cov * info[static_cast<std::size_t>(j)] * Rt;
  Eigen::Matrix2d cov = view[i].M;
  Eigen::Vector2d J = Eigen::Vector2d::Zero();
  Eigen::Matrix2d map_cov = Rt * ekf.landmark_cov(view[i].id) * Rt.transpose();  // R^T P_ii R
  Eigen::RowVector2d th_l = heading_landmark_cov(ekf, view[i].id) * Rt.transpose();  // P_th,li R - sum_j P_th,lj A_j^T
  for (int j = 0; j < n; ++j) {
    const auto uj = static_cast<std::size_t>(j);
    if (!use[uj]) continue;
    const Eigen::Matrix2d Wj = fused_cov * info[uj];
    const Eigen::Matrix2d& Aj = A[uj];
    cov += Wj * view[j].M * Wj.transpose();
    const Eigen::Vector2d d = ekf.landmark(view[i].id) - ekf.landmark(view[j].id);
    J += Wj * heading_jacobian(c, s, d);
    const Eigen::Matrix2d cross = Rt * ekf.landmark_cross_cov(view[i].id, view[j].id) * Aj.transpose();
    map_cov -= cross + cross.transpose();  // - R^T P_ij A_j^T - A_j P_ji R
    th_l -= heading_landmark_cov(ekf, view[j].id) * Aj.transpose();
    for (int k = 0; k < n; ++k) {
      if (!use[static_cast<std::size_t>(k)]) continue;
      map_cov += Aj * ekf.landmark_cross_cov(view[j].id, view[k].id) * A[static_cast<std::size_t>(k)].transpose();  // A_j P_jk A_k^T
    }
  }
  const Eigen::Matrix2d th_cross = J * th_l;  // cov(-g e_th, -R^T e_li + sum_j A_j e_lj)
  cov += map_cov + var_th * J * J.transpose() + th_cross + th_cross.transpose();
  return mahalanobis2(residual, 0.5 * (cov + cov.transpose()));
}

// ---- ElaGate ------------------------------------------------------------------------

ElaGate::ElaGate(const RobotOptions& options)
    : mode_(options.mode),
      ela_threshold_(chi2_quantile(options.ela_gate_probability, 2)),
      drift_lambda_(options.drift_memory),
      drift_scale_(1.0 - options.drift_memory * options.drift_memory),
      drift_threshold_(chi2_quantile(options.drift_gate_probability, 2)),
      candidate_drift_(options.candidate_drift_test),
      solver_(options.ela_gate_probability) {
  const auto n = static_cast<std::size_t>(options.max_observations);
  view_.reserve(n);
  prior_.reserve(n);
  Hx_.resize(n);
  Hl_.resize(n);
  Q_.resize(n * n);
  b_.resize(n);
  v_.resize(n);
  lm_.resize(n);
  c_.resize(n);
  d2_.reserve(n);
  mask_.reserve(n);
  kept_.reserve(n);
  kept_d2_.reserve(n);
  verdicts_.reserve(n);
  records_.reserve(n);  // every observation of a frame has at most one record
}

void ElaGate::clear() {
  view_.clear();
  records_.clear();
}

void ElaGate::add_to_view(int id, const RangeBearing& z) {
  InView v;
  v.id = id;
  v.z = z;
  view_.push_back(v);
}

// d2 of view_[k]'s innovation against the prior; infinite when it has none.
double ElaGate::prior_d2(int k) const {
  const UpdateReport& r = prior_[static_cast<std::size_t>(k)];
  return r.status == EkfStatus::kOk ? r.d2 : std::numeric_limits<double>::infinity();
}

// Record k's verdict. Called in view order: records_[k] is view_[k]'s.
void ElaGate::decide(int k, const GateRecord& g, bool alone) {
  records_.push_back(g);
  verdicts_[static_cast<std::size_t>(k)] = {g.inside, alone};
}

// A single landmark in view (or left): its ELA is the EKF's predicted observation.
void ElaGate::decide_alone(int k) {
  const double d2 = prior_d2(k);
  decide(k, {view_[static_cast<std::size_t>(k)].id, GateKind::kInnovation, d2, ela_threshold_, d2 <= ela_threshold_},
         true);
}

void ElaGate::judge_view(const EkfSlam& ekf, LMap* lmap) {
  const int n = view_size();
  verdicts_.assign(view_.size(), ElaVerdict{});
  mask_.assign(view_.size(), 1);
  // Every landmark's innovation against the prior, once: the single tests, the
  // consensus ranking and the drift test all read it.
  prior_.clear();
  for (InView& v : view_) {
    set_local(&v, ekf.measurement_cov());
    prior_.push_back(ekf.check(v.id, v.z));
  }
  if (n > 0) {
    if (mode_ == Mode::kConsensus && n >= 2) {
      judge_consensus(ekf);
    } else {
      judge_eq16(ekf);
    }
  }
  if (drift_lambda_ > 0.0) judge_drift(lmap);
}

// Is landmark a a worse candidate to set aside than b (both outside their ELAs)? The
// larger eq-16 d2; on a tie, the larger prior innovation (as consensus ranks). With
// two landmarks in view the eq-16 residuals are each other's negatives with the same
// covariance, so their d2 tie (up to rounding) and only the prior can tell the mover.
bool ElaGate::worse(int a, int b) const {
  const double da = d2_[static_cast<std::size_t>(a)], db = d2_[static_cast<std::size_t>(b)];
  if (std::abs(da - db) > 1e-9 * std::max(da, db)) return da > db;
  return prior_d2(a) > prior_d2(b);
}

// Eq 16 for every landmark in view. A landmark found outside its ELA stops shaping
// the others' ELAs: the worst one is set aside and the rest re-tested, until all
// that remain agree (one moving neighbour would otherwise shift every other
// landmark's ELA by its displacement / (n - 1) and flag them too).
//
// Setting aside the worst first can go wrong when several movers have gone far the
// same way (after frames missed: a restart, a radio outage, where the movers were
// not caught as they went): they pull the static landmarks' ELAs, the statics come
// out worst and are set aside one by one, and the movers remain, agreeing with each
// other. So when more landmarks were set aside than remain, the set-aside ones are
// judged among themselves the same way; if more of them agree with each other than
// remained, they are the reference (static landmarks are the majority, paper
// section 3), and a landmark of the first survivors rejoins them if it agrees with
// them (as consensus re-tests a landmark outside its clique).
void ElaGate::judge_eq16(const EkfSlam& ekf) {
  const int n = view_size();
  d2_.assign(view_.size(), 0.0);
  if (n >= 2) prepare_eq16(ekf);
  int active = settle_eq16(n);
  const int aside = n - active;
  if (aside >= 2 && aside > active) {
    kept_ = mask_;
    kept_d2_ = d2_;
    for (std::size_t i = 0; i < mask_.size(); ++i) mask_[i] = kept_[i] ? 0 : 1;
    prepare_eq16(ekf);
    const int others = settle_eq16(aside);
    if (others > active) {
      ++regroups_;
      active = others;
      for (int i = 0; i < n; ++i) {
        const auto ui = static_cast<std::size_t>(i);
        if (!kept_[ui]) continue;
        d2_[ui] = eq16_d2(i);
        if (d2_[ui] <= ela_threshold_) {
          mask_[ui] = 1;
          ++active;
        }
      }
    } else {  // the first survivors stand
      mask_ = kept_;
      d2_ = kept_d2_;
      prepare_eq16(ekf);
    }
  }
  for (int i = 0; i < n; ++i) {
    const auto ui = static_cast<std::size_t>(i);
    if (active < 2 && mask_[ui]) {
      decide_alone(i);
    } else {
      decide(i, {view_[ui].id, GateKind::kMulti, d2_[ui], ela_threshold_, mask_[ui] != 0}, false);
    }
  }
}

// Eq 16 over the active set (mask_, `active` landmarks, totals prepared): set aside
// the worst landmark outside its ELA until all that remain agree or fewer than two
// remain. Returns how many remain; d2_ holds each landmark's last d2.
int ElaGate::settle_eq16(int active) {
  const int n = view_size();
  while (active >= 2) {
    int worst = -1;
    for (int i = 0; i < n; ++i)
      if (mask_[static_cast<std::size_t>(i)]) d2_[static_cast<std::size_t>(i)] = eq16_d2(i);
    for (int i = 0; i < n; ++i)
      if (mask_[static_cast<std::size_t>(i)] && d2_[static_cast<std::size_t>(i)] > ela_threshold_ &&
          (worst < 0 || worse(i, worst)))
        worst = i;
    if (worst < 0) break;
    set_aside_eq16(worst);
    --active;
  }
  return active;
}

// Everything eq 16 needs for the view, once per frame (ela_multi_d2 spells out the
// algebra): Q_ij for every pair and v_i = sum_k Q_ik b_k over the active set
// (mask_) for every landmark, O(n^2); the active set's totals, O(n).
void ElaGate::prepare_eq16(const EkfSlam& ekf) {
  const int n = view_size();
  const auto N = static_cast<std::size_t>(n);
  const Pose2 pose = ekf.pose();
  Rt_ = rotation(pose.theta).transpose();
  var_th_ = ekf.pose_cov()(StateLayout::kTheta, StateLayout::kTheta);
  cos_th_ = std::cos(pose.theta);
  sin_th_ = std::sin(pose.theta);
  D_ << -sin_th_, cos_th_, -cos_th_, -sin_th_;  // heading_jacobian(c, s, d) = D d
  for (std::size_t i = 0; i < N; ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      Q_[i * N + j] = Rt_ * ekf.landmark_cross_cov(view_[i].id, view_[j].id) * Rt_.transpose();
      Q_[j * N + i] = Q_[i * N + j].transpose();
    }
    Q_[i * N + i] = Rt_ * ekf.landmark_cov(view_[i].id) * Rt_.transpose();
    lm_[i] = ekf.landmark(view_[i].id);
    c_[i] = heading_landmark_cov(ekf, view_[i].id) * Rt_.transpose();
    const Eigen::LLT<Eigen::Matrix2d> llt(view_[i].M + Q_[i * N + i]);  // neighbour_weight
    b_[i] = llt.info() == Eigen::Success ? Eigen::Matrix2d(llt.solve(Eigen::Matrix2d::Identity()))
                                         : Eigen::Matrix2d::Zero();
  }
  tot_.Lambda.setZero();
  tot_.S1.setZero();
  tot_.T.setZero();
  tot_.eta.setZero();
  tot_.sigma.setZero();
  tot_.S4.setZero();
  for (std::size_t j = 0; j < N; ++j) {
    if (!mask_[j]) continue;
    const Eigen::Matrix2d& b = b_[j];
    tot_.Lambda += b;
    tot_.S1 += b * view_[j].M * b;
    tot_.eta += b * (view_[j].m - Rt_ * lm_[j]);
    tot_.sigma += b * (D_ * lm_[j]);
    tot_.S4 += c_[j] * b;
  }
  for (std::size_t i = 0; i < N; ++i) {
    Eigen::Matrix2d v = Eigen::Matrix2d::Zero();
    for (std::size_t k = 0; k < N; ++k)
      if (mask_[k]) v += Q_[i * N + k] * b_[k];
    v_[i] = v;
    if (mask_[i]) tot_.T += b_[i] * v;
  }
}

// Landmark m stops shaping the others' ELAs: its terms leave the totals, O(1), and
// every v_i, O(n).
void ElaGate::set_aside_eq16(int m) {
  const auto N = static_cast<std::size_t>(view_size());
  const auto um = static_cast<std::size_t>(m);
  mask_[um] = 0;
  const Eigen::Matrix2d& b = b_[um];
  const Eigen::Matrix2d vm = v_[um];
  tot_.Lambda -= b;
  tot_.S1 -= b * view_[um].M * b;
  tot_.eta -= b * (view_[um].m - Rt_ * lm_[um]);
  tot_.sigma -= b * (D_ * lm_[um]);
  tot_.S4 -= c_[um] * b;
  // T = sum_jk b_j Q_jk b_k without j = m and k = m: minus row m (b_m v_m), minus
  // column m (its transpose), plus the (m, m) term taken twice.
  tot_.T += -b * vm - vm.transpose() * b + b * Q_[um * N + um] * b;
  for (std::size_t i = 0; i < N; ++i) v_[i] -= Q_[i * N + um] * b;
}

// Eq 16's d2 of landmark i against the active set (mask_): its neighbours' sums
// are the active set's totals, minus its own terms when it is in the set (the same
// numbers as ela_multi_d2 with mask_).
double ElaGate::eq16_d2(int i) const {
  const auto ui = static_cast<std::size_t>(i);
  const auto N = static_cast<std::size_t>(view_size());
  const Eigen::Matrix2d bi = mask_[ui] ? b_[ui] : Eigen::Matrix2d::Zero();
  const Eigen::Matrix2d& vi = v_[ui];
  const Eigen::Matrix2d& Qii = Q_[ui * N + ui];
  const Eigen::Matrix2d Lambda = tot_.Lambda - bi;
  const Eigen::LLT<Eigen::Matrix2d> llt(Lambda);
  if (llt.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
  const Eigen::Matrix2d F = llt.solve(Eigen::Matrix2d::Identity());
  const Eigen::Vector2d Rl = Rt_ * lm_[ui];
  const Eigen::Vector2d eta = tot_.eta - bi * (view_[ui].m - Rl) + Lambda * Rl;  // sum b_j p_ij
  const Eigen::Vector2d residual = view_[ui].m - F * eta;
  const Eigen::Matrix2d S1 = tot_.S1 - bi * view_[ui].M * bi;
  const Eigen::Matrix2d S2 = vi - Qii * bi;                                  // sum_j Q_ij b_j
  const Eigen::Matrix2d T = tot_.T - bi * vi - vi.transpose() * bi + bi * Qii * bi;
  const Eigen::Vector2d S3 = Lambda * (D_ * lm_[ui]) - (tot_.sigma - bi * (D_ * lm_[ui]));  // sum b_j D (l_i - l_j)
  const Eigen::RowVector2d S4 = tot_.S4 - c_[ui] * bi;
  const Eigen::Matrix2d cross = S2 * F.transpose();
  Eigen::Matrix2d cov = view_[ui].M + F * S1 * F.transpose() + Qii - cross - cross.transpose() + F * T * F.transpose();
  const Eigen::Vector2d J = F * S3;
  const Eigen::Matrix2d th_cross = J * (c_[ui] - S4 * F.transpose());
  cov += var_th_ * J * J.transpose() + th_cross + th_cross.transpose();
  return mahalanobis2(residual, 0.5 * (cov + cov.transpose()));
}

// The joint covariance of the landmarks' innovations against the prior, for the
// consensus solver's joint prior test: block (i, j) = H_i P H_j^T (+ W when i = j),
// H_i = [H_x, H_l] of landmark i (pose and landmark columns only). O(n^2).
void ElaGate::set_joint_prior(const EkfSlam& ekf) {
  const int n = view_size();
  const Pose2 pose = ekf.pose();
  const Eigen::Matrix3d Ppp = ekf.pose_cov();
  for (int i = 0; i < n; ++i) {
    const auto ui = static_cast<std::size_t>(i);
    observe(pose, ekf.landmark(view_[ui].id), &Hx_[ui], &Hl_[ui]);
    solver_.set_innovation(i, prior_[ui].innovation);
  }
  for (int i = 0; i < n; ++i) {
    const auto ui = static_cast<std::size_t>(i);
    const Eigen::Matrix<double, 3, 2> Ppi = ekf.pose_landmark_cov(view_[ui].id);
    for (int j = 0; j <= i; ++j) {
      const auto uj = static_cast<std::size_t>(j);
      const Eigen::Matrix<double, 3, 2> Ppj = ekf.pose_landmark_cov(view_[uj].id);
      Eigen::Matrix2d S = Hx_[ui] * Ppp * Hx_[uj].transpose() + Hx_[ui] * Ppj * Hl_[uj].transpose() +
                          Hl_[ui] * Ppi.transpose() * Hx_[uj].transpose() +
                          Hl_[ui] * ekf.landmark_cross_cov(view_[ui].id, view_[uj].id) * Hl_[uj].transpose();
      if (i == j) S += ekf.measurement_cov();
      solver_.set_joint_block(i, j, S);
      solver_.set_joint_block(j, i, S.transpose());
    }
  }
  solver_.joint(true);
}

// Largest mutually consistent set of the landmarks in view; outside it = moving.
// A best set of fewer than two falls back to each landmark's single test.
void ElaGate::judge_consensus(const EkfSlam& ekf) {
  const int n = view_size();
  solver_.reset(n);
  set_joint_prior(ekf);
  for (int i = 0; i < n; ++i) {
    const InView& vi = view_[static_cast<std::size_t>(i)];
    const double d2 = prior_d2(i);
    solver_.set_prior_d2(i, std::isfinite(d2) ? d2 : 1e12);
    for (int j = i + 1; j < n; ++j)
      if (pair_d2(ekf, vi, view_[static_cast<std::size_t>(j)]) <= ela_threshold_) solver_.add_edge(i, j);
  }
  const std::uint64_t chosen = solver_.solve();
  const bool fallback = __builtin_popcountll(chosen) < 2;
  // The clique is the static reference. A landmark outside it may only have failed
  // one pair test by chance (1 % per pair at the default gate, several pairs per
  // landmark): it is re-tested against the whole clique with the fused ELA (eq 16
  // restricted to the clique, mask_) and admitted when it agrees.
  for (int i = 0; i < n; ++i) mask_[static_cast<std::size_t>(i)] = (chosen >> i) & 1u;
  if (!fallback) prepare_eq16(ekf);  // eq 16 over the clique, O(n^2) for the view
  for (int i = 0; i < n; ++i) {
    const int id = view_[static_cast<std::size_t>(i)].id;
    if (fallback) {  // fewer than two agree: each landmark's single test
      decide_alone(i);
    } else if (mask_[static_cast<std::size_t>(i)]) {
      decide(i, {id, GateKind::kConsensus, 0.0, ela_threshold_, true}, false);
    } else {
      const double d2 = eq16_d2(i);
      decide(i, {id, GateKind::kConsensus, d2, ela_threshold_, d2 <= ela_threshold_}, false);
    }
  }
}

// A slow mover passes every single-frame test while the filter follows it, but its
// innovations are not white. Each STATIC landmark in view that passed its test
// keeps an exponentially weighted sum of its whitened innovations (against the
// prior, before this frame's corrections); under the model the sum has covariance
// I / (1 - lambda^2), so |sum|^2 (1 - lambda^2) is chi-square with 2 dof. Tested
// every frame on a memory of ~1 / (1 - lambda) sightings, it has its own, stricter
// gate (drift_gate_probability); failing it is an out-of-ELA verdict like any
// other, and the drift test is then the test that decided. (The ELA residual of
// eq 16 in place of the innovation cancels the robot's pose error, but also hides
// a drift shared with co-moving neighbours; measured worse, docs/adr/0012-drift-test.md.)
void ElaGate::judge_drift(LMap* lmap) {
  for (std::size_t k = 0; k < view_.size(); ++k) {
    if (!verdicts_[k].inside || prior_[k].status != EkfStatus::kOk) continue;
    const double d2 = lmap->add_drift(view_[k].id, drift_lambda_, prior_[k].whitened).squaredNorm() * drift_scale_;
    if (d2 > drift_threshold_) {
      verdicts_[k].inside = false;
      records_[k] = {view_[k].id, GateKind::kDrift, d2, drift_threshold_, false};
    }
  }
}

// The candidate's ELA is the filter's prediction of it: the innovation against the
// candidate's anchor, whose covariance carries exactly the pose uncertainty accrued
// since the anchor. A refined candidate's innovations are white if it stands still;
// their running sum is the test for a mover the estimate keeps following.
bool ElaGate::judge_candidate(int id, const UpdateReport& r, LMap* lmap) {
  const bool checked = r.status == EkfStatus::kOk;
  GateRecord g{id, GateKind::kCandidate, checked ? r.d2 : std::numeric_limits<double>::infinity(), ela_threshold_,
               checked && r.d2 <= ela_threshold_};
  if (g.inside && candidate_drift_) {
    const LMapEntry& e = lmap->add_innovation(id, r.whitened);
    const double d2 = e.innovation_sum.squaredNorm() / e.innovations;
    if (d2 > ela_threshold_) g = {id, GateKind::kCandidateDrift, d2, ela_threshold_, false};
  }
  records_.push_back(g);
  return g.inside;
}

}  // namespace elaslam

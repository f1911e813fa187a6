// Fixed-memory planar EKF-SLAM (DESIGN.md section 4; paper eqs 3-15).
//
// Cost per call, n = state dimension: predict O(n), update O(n^2) (the rank-2/4
// covariance downdate; everything else is O(n)), add and remove O(n). Nothing
// here allocates after the constructor: scratch lives in members, small blocks
// are fixed-size, and products that Eigen might route through its blocked GEMM
// (which may allocate) are written as coefficient-wise expressions or loops.
#include "elaslam/robot_node/ekf_slam.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "elaslam/common/stats.hpp"

namespace elaslam {

namespace {

using Index = Eigen::Index;
using Matrix25 = Eigen::Matrix<double, 2, 5>;
using Matrix5 = Eigen::Matrix<double, 5, 5>;

// A variance may come out this far below zero from rounding alone (relative to the
// prior variance, plus an absolute (1 um)^2 / (1 urad)^2) before it counts as a
// fault. Anything more negative means P was not positive semi-definite.
constexpr double kNegativeVarianceRelTol = 1e-9;
constexpr double kNegativeVarianceAbsTol = 1e-12;
// |a_i| * |b_j| below this cannot overflow when two such products are summed.
constexpr double kMaxProduct = 1e300;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool finite(const RangeBearing& z) { return std::isfinite(z.range) && std::isfinite(z.bearing); }

// Runtime dispatch for the two O(n^2) kernels below: on x86-64 the loader picks
// an AVX2+FMA build when the CPU has it (about 2x faster, DESIGN.md section 4
// budget), else the baseline SSE2 build. Other targets get the plain build.
#if defined(__x86_64__) && defined(__linux__) && defined(__GNUC__) && !defined(__clang__) && \
    (__GNUC__ >= 11)
#define ELASLAM_MULTIVERSION __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define ELASLAM_MULTIVERSION
#endif

// The covariance downdates work on the full active block, column by column, four
// columns at a time so that each row's factors are loaded once. Entry (i, j) and
// entry (j, i) evaluate the same products summed in the same order (float * and +
// commute), so a symmetric P stays symmetric bit for bit with no separate
// symmetrisation pass (which, being a strided transpose, would cost more than the
// update itself). EkfSlam.CovarianceStaysExactlySymmetric checks this.
inline double dot2(double u0, double u1, double v0, double v1) { return u0 * v0 + u1 * v1; }

// P(0:n, 0:n) -= A A^T, A = [a0 a1] (n x 2).
ELASLAM_MULTIVERSION void sym_rank2_downdate(double* __restrict P, Index ld, Index n,
                                             const double* __restrict a0,
                                             const double* __restrict a1) {
  Index j = 0;
  for (; j + 4 <= n; j += 4) {
    double* __restrict c0 = P + j * ld;
    double* __restrict c1 = c0 + ld;
    double* __restrict c2 = c1 + ld;
    double* __restrict c3 = c2 + ld;
    for (Index i = 0; i < n; ++i) {
      c0[i] -= dot2(a0[i], a1[i], a0[j], a1[j]);
      c1[i] -= dot2(a0[i], a1[i], a0[j + 1], a1[j + 1]);
      c2[i] -= dot2(a0[i], a1[i], a0[j + 2], a1[j + 2]);
      c3[i] -= dot2(a0[i], a1[i], a0[j + 3], a1[j + 3]);
    }
  }
  for (; j < n; ++j) {
    double* __restrict c = P + j * ld;
    for (Index i = 0; i < n; ++i) c[i] -= dot2(a0[i], a1[i], a0[j], a1[j]);
  }
}

// P(0:n, 0:n) -= A B^T + B A^T, A = [a0 a1], B = [b0 b1] (n x 2).
ELASLAM_MULTIVERSION void sym_rank4_downdate(double* __restrict P, Index ld, Index n,
                                             const double* __restrict a0,
                                             const double* __restrict a1,
                                             const double* __restrict b0,
                                             const double* __restrict b1) {
  Index j = 0;
  for (; j + 4 <= n; j += 4) {
    double* __restrict c0 = P + j * ld;
    double* __restrict c1 = c0 + ld;
    double* __restrict c2 = c1 + ld;
    double* __restrict c3 = c2 + ld;
    for (Index i = 0; i < n; ++i) {
      c0[i] -= dot2(a0[i], a1[i], b0[j], b1[j]) + dot2(b0[i], b1[i], a0[j], a1[j]);
      c1[i] -= dot2(a0[i], a1[i], b0[j + 1], b1[j + 1]) + dot2(b0[i], b1[i], a0[j + 1], a1[j + 1]);
      c2[i] -= dot2(a0[i], a1[i], b0[j + 2], b1[j + 2]) + dot2(b0[i], b1[i], a0[j + 2], a1[j + 2]);
      c3[i] -= dot2(a0[i], a1[i], b0[j + 3], b1[j + 3]) + dot2(b0[i], b1[i], a0[j + 3], a1[j + 3]);
    }
  }
  for (; j < n; ++j) {
    double* __restrict c = P + j * ld;
    for (Index i = 0; i < n; ++i) {
      c[i] -= dot2(a0[i], a1[i], b0[j], b1[j]) + dot2(b0[i], b1[i], a0[j], a1[j]);
    }
  }
}

// Everything about one observation that needs only the 5x5 block of P on the robot
// and the landmark (eqs 8, 9, 13).
struct Innovation {
  Matrix25 H;               // [H_x H_l], the non-zero columns of H
  Eigen::Matrix2d L;        // lower Cholesky factor of Z
  Eigen::Vector2d nu;       // innovation z = y - h(X), bearing wrapped
  Eigen::Vector2d w;        // L^-1 nu, so d2 = |w|^2
  double d2 = 0.0;
};

// Z = H P H^T + W (eq 9) from the 5x5 block; kSingular unless Z is positive definite.
EkfStatus innovate(const Eigen::MatrixXd& P, const Eigen::VectorXd& x, Index off,
                   const Eigen::Matrix2d& W, const RangeBearing& y, Innovation* out) {
  using L = StateLayout;
  const Pose2 pose{x(L::kX), x(L::kY), x(L::kTheta)};
  Eigen::Matrix<double, 2, 3> H_x;
  Eigen::Matrix2d H_l;
  const RangeBearing h = observe(pose, x.segment<2>(off), &H_x, &H_l);  // eq 7
  out->H << H_x, H_l;
  out->nu << y.range - h.range, wrap_angle(y.bearing - h.bearing);  // eq 8
  Matrix5 P5;
  P5 << P.topLeftCorner<3, 3>(), P.block<3, 2>(0, off),  //
      P.block<2, 3>(off, 0), P.block<2, 2>(off, off);
  const Eigen::Matrix2d Z = out->H * P5 * out->H.transpose() + W;
  // 2x2 Cholesky by hand: the comparisons also reject NaN.
  const double z00 = Z(0, 0), z10 = 0.5 * (Z(1, 0) + Z(0, 1));
  if (!(z00 > 0.0)) return EkfStatus::kSingular;
  const double l00 = std::sqrt(z00), l10 = z10 / l00;
  const double s = Z(1, 1) - l10 * l10;
  if (!(s > 0.0) || !std::isfinite(s)) return EkfStatus::kSingular;
  out->L << l00, 0.0, l10, std::sqrt(s);
  out->w(0) = out->nu(0) / l00;
  out->w(1) = (out->nu(1) - l10 * out->w(0)) / out->L(1, 1);
  out->d2 = out->w.squaredNorm();  // nu^T Z^-1 nu
  return EkfStatus::kOk;
}

}  // namespace

const char* to_string(EkfStatus s) {
  switch (s) {
    case EkfStatus::kOk: return "ok";
    case EkfStatus::kGated: return "gated";
    case EkfStatus::kUnknownLandmark: return "unknown_landmark";
    case EkfStatus::kAlreadyMapped: return "already_mapped";
    case EkfStatus::kFull: return "full";
    case EkfStatus::kBadInput: return "bad_input";
    case EkfStatus::kSingular: return "singular";
    case EkfStatus::kCovarianceFault: return "covariance_fault";
  }
  return "invalid_status";
}

// ---- construction ---------------------------------------------------------------

EkfSlam::EkfSlam(const EkfOptions& options) : options_(options) {
  // Start-up only: a bad configuration must stop the node before it runs, with a
  // reason (config validation should already have caught it).
  const auto fail = [](const std::string& what) {
    throw std::invalid_argument("EkfSlam: " + what);
  };
  if (options.capacity < 0) fail("capacity must be >= 0");
  if (options.max_landmark_id < 0) fail("max_landmark_id must be >= 0");
  if (!(options.range_sigma > 0.0) || !std::isfinite(options.range_sigma))
    fail("range_sigma must be finite and > 0 [m]");
  if (!(options.bearing_sigma > 0.0) || !std::isfinite(options.bearing_sigma))
    fail("bearing_sigma must be finite and > 0 [rad]");
  if (!(options.gate_probability > 0.0 && options.gate_probability < 1.0))
    fail("gate_probability must be in (0, 1)");

  W_ = Eigen::Vector2d(options.range_sigma * options.range_sigma,
                       options.bearing_sigma * options.bearing_sigma)
           .asDiagonal();
  gate_threshold_ = chi2_quantile(options.gate_probability, 2);

  const Index n_max = Layout::dim(options.capacity);
  x_ = Eigen::VectorXd::Zero(n_max);
  P_ = Eigen::MatrixXd::Zero(n_max, n_max);
  id_to_slot_.assign(static_cast<std::size_t>(options.max_landmark_id), -1);
  slot_to_id_.assign(static_cast<std::size_t>(options.capacity), -1);
  PHt_ = Eigen::MatrixXd::Zero(n_max, 2);
  K_ = Eigen::MatrixXd::Zero(n_max, 2);
  tmp_rows_ = Eigen::MatrixXd::Zero(Layout::kPoseDim, n_max);
  reset(Pose2{}, Eigen::Matrix3d::Zero());
}

void EkfSlam::reset(const Pose2& pose, const Eigen::Matrix3d& pose_cov) {
  for (int slot = 0; slot < num_landmarks_; ++slot) {
    id_to_slot_[static_cast<std::size_t>(slot_to_id_[static_cast<std::size_t>(slot)])] = -1;
    slot_to_id_[static_cast<std::size_t>(slot)] = -1;
  }
  num_landmarks_ = 0;
  x_.setZero();
  x_.head<3>() << pose.x, pose.y, wrap_angle(pose.theta);
  P_.topLeftCorner<3, 3>() = 0.5 * (pose_cov + pose_cov.transpose());
}

// ---- prediction (eqs 3-6) -----------------------------------------------------

EkfStatus EkfSlam::predict(const Pose2& increment, const Eigen::Matrix3d& U) {
  const bool finite_u = std::isfinite(increment.x) && std::isfinite(increment.y) &&
                        std::isfinite(increment.theta) && U.allFinite();
  if (!finite_u || (U - U.transpose()).cwiseAbs().maxCoeff() > 1e-9 * U.cwiseAbs().maxCoeff() ||
      (U.diagonal().array() < 0.0).any()) {
    return EkfStatus::kBadInput;
  }
  Eigen::Matrix3d F_x, F_u;
  const Pose2 next = motion(pose(), increment, &F_x, &F_u);  // eq 4
  const Index m = state_dim() - Layout::kPoseDim;             // landmark part of X

  // Compute into temporaries, commit only when healthy.
  Eigen::Matrix3d P_RR = F_x * P_.topLeftCorner<3, 3>() * F_x.transpose() +
                         F_u * U * F_u.transpose();  // eq 5, robot block
  P_RR = 0.5 * (P_RR + P_RR.transpose()).eval();
  // eq 5, cross terms: landmarks do not move, so P_RL <- F_x P_RL and no more.
  auto P_RL_new = tmp_rows_.leftCols(m);
  P_RL_new.noalias() = F_x * P_.block(0, Layout::kPoseDim, Layout::kPoseDim, m);
  if (!P_RR.allFinite() || (P_RR.diagonal().array() < 0.0).any() || !P_RL_new.allFinite()) {
    return EkfStatus::kCovarianceFault;
  }

  x_.head<3>() << next.x, next.y, next.theta;  // theta wrapped by compose()
  P_.topLeftCorner<3, 3>() = P_RR;
  P_.block(0, Layout::kPoseDim, Layout::kPoseDim, m) = P_RL_new;
  P_.block(Layout::kPoseDim, 0, m, Layout::kPoseDim) = P_RL_new.transpose();
  return EkfStatus::kOk;
}

// ---- correction (eqs 7-13) ----------------------------------------------------

EkfStatus EkfSlam::locate(int id, const RangeBearing& z, int* slot) const {
  if (!valid_id(id) || !finite(z) || !(z.range > 0.0)) return EkfStatus::kBadInput;
  *slot = slot_of(id);
  return *slot < 0 ? EkfStatus::kUnknownLandmark : EkfStatus::kOk;
}

UpdateReport EkfSlam::check(int id, const RangeBearing& z) const {
  UpdateReport report;
  report.threshold = gate_threshold_;
  int slot = -1;
  report.status = locate(id, z, &slot);
  if (report.status != EkfStatus::kOk) return report;
  Innovation inn;
  report.status = innovate(P_, x_, Layout::landmark_offset(slot), W_, z, &inn);
  if (report.status != EkfStatus::kOk) return report;
  report.d2 = inn.d2;
  report.innovation = inn.nu;
  return report;
}

UpdateReport EkfSlam::update(int id, const RangeBearing& z, bool gate) {
  UpdateReport report;
  report.threshold = gate ? gate_threshold_ : 0.0;
  int slot = -1;
  report.status = locate(id, z, &slot);
  if (report.status != EkfStatus::kOk) return report;
  const Index off = Layout::landmark_offset(slot);
  Innovation inn;
  report.status = innovate(P_, x_, off, W_, z, &inn);
  if (report.status != EkfStatus::kOk) return report;
  report.d2 = inn.d2;
  report.innovation = inn.nu;
  if (gate && inn.d2 > gate_threshold_) {
    report.status = EkfStatus::kGated;
    return report;
  }
  compute_gain(off, inn.H, inn.L);
  if (!correction_healthy(inn.nu, inn.w)) {
    report.status = EkfStatus::kCovarianceFault;
    return report;
  }
  apply_correction(inn.nu, inn.w);
  return report;
}

// P H^T from the five non-zero columns of H (O(n)), then the gain factors:
//   Joseph:   K = P H^T Z^-1 (eq 10) in K_, and B = P H^T - K Z / 2 in PHt_, so that
//             (I-KH)P(I-KH)^T + K W K^T = P - K PHt^T - PHt K^T + K Z K^T
//                                      = P - K B^T - B K^T            (rank 4);
//   standard: M = P H^T L^-T in K_, so that P - K Z K^T = P - M M^T   (eq 12, rank 2).
// In exact arithmetic both equal P - PHt Z^-1 PHt^T; the Joseph form adds
// E Z E^T for an error E in K, so it stays positive semi-definite for any gain.
void EkfSlam::compute_gain(Index off, const Matrix25& H, const Eigen::Matrix2d& L) {
  const Index n = state_dim();
  for (int r = 0; r < 2; ++r) {
    PHt_.col(r).head(n) = P_.col(0).head(n) * H(r, 0) + P_.col(1).head(n) * H(r, 1) +
                          P_.col(2).head(n) * H(r, 2) + P_.col(off).head(n) * H(r, 3) +
                          P_.col(off + 1).head(n) * H(r, 4);
  }
  // M = PHt L^-T: each row m_i = L^-1 pht_i.
  K_.col(0).head(n) = PHt_.col(0).head(n) / L(0, 0);
  K_.col(1).head(n) = (PHt_.col(1).head(n) - L(1, 0) * K_.col(0).head(n)) / L(1, 1);
  if (!options_.joseph) return;
  // K = M L^-1: each row k_i = L^-T m_i.
  K_.col(1).head(n) /= L(1, 1);
  K_.col(0).head(n) = (K_.col(0).head(n) - L(1, 0) * K_.col(1).head(n)) / L(0, 0);
  const Eigen::Matrix2d half_Z = 0.5 * L * L.transpose();
  for (int c = 0; c < 2; ++c) {
    PHt_.col(c).head(n) -= K_.col(0).head(n) * half_Z(0, c) + K_.col(1).head(n) * half_Z(1, c);
  }
}

// O(n) preview of the update: the new mean and the new diagonal of P must be
// finite, the diagonal non-negative (up to rounding), and no off-diagonal product
// may overflow. Then the O(n^2) step cannot make P or X non-finite.
bool EkfSlam::correction_healthy(const Eigen::Vector2d& nu, const Eigen::Vector2d& w) const {
  const Index n = state_dim();
  const auto A = K_.topRows(n);
  const auto B = PHt_.topRows(n);
  // Mean step: Joseph K nu, standard M w (the same vector, eq 11).
  const Eigen::Vector2d v = options_.joseph ? nu : w;
  for (Index i = 0; i < n; ++i) {
    const double dx = A(i, 0) * v(0) + A(i, 1) * v(1);
    const double p = P_(i, i);
    const double p_new = options_.joseph ? p - 2.0 * dot2(A(i, 0), A(i, 1), B(i, 0), B(i, 1))
                                         : p - dot2(A(i, 0), A(i, 1), A(i, 0), A(i, 1));
    if (!std::isfinite(x_(i) + dx) || !std::isfinite(p_new) ||
        p_new < -(kNegativeVarianceRelTol * p + kNegativeVarianceAbsTol)) {
      return false;
    }
  }
  const double a_max = A.cwiseAbs().maxCoeff();
  const double b_max = options_.joseph ? B.cwiseAbs().maxCoeff() : a_max;
  return n == 0 || a_max * b_max < kMaxProduct;
}

void EkfSlam::apply_correction(const Eigen::Vector2d& nu, const Eigen::Vector2d& w) {
  const Index n = state_dim();
  const Index ld = P_.outerStride();
  if (options_.joseph) {
    x_.head(n) += K_.col(0).head(n) * nu(0) + K_.col(1).head(n) * nu(1);  // eq 11
    sym_rank4_downdate(P_.data(), ld, n, K_.col(0).data(), K_.col(1).data(), PHt_.col(0).data(),
                       PHt_.col(1).data());
  } else {
    // eq 11: K nu = M L^-1 nu = M w
    x_.head(n) += K_.col(0).head(n) * w(0) + K_.col(1).head(n) * w(1);
    sym_rank2_downdate(P_.data(), ld, n, K_.col(0).data(), K_.col(1).data());  // eq 12
  }
  x_(Layout::kTheta) = wrap_angle(x_(Layout::kTheta));
}

// ---- map management ---------------------------------------------------------------

// Augmentation by the inverse observation (eq 15): l = g(R, y),
//   P_ll = G_x P_RR G_x^T + G_z W G_z^T,  P_lX = G_x P_RX.
EkfStatus EkfSlam::add_landmark(int id, const RangeBearing& z) {
  if (!valid_id(id) || !finite(z) || !(z.range > 0.0)) return EkfStatus::kBadInput;
  if (has_landmark(id)) return EkfStatus::kAlreadyMapped;
  if (num_landmarks_ >= options_.capacity) return EkfStatus::kFull;

  Eigen::Matrix<double, 2, 3> G_x;
  Eigen::Matrix2d G_z;
  const Eigen::Vector2d p_LinW = inverse_observe(pose(), z, &G_x, &G_z);
  const int slot = num_landmarks_;
  const Index off = Layout::landmark_offset(slot);
  const Index n = state_dim();
  Eigen::Matrix2d P_ll = G_x * P_.topLeftCorner<3, 3>() * G_x.transpose() +
                         G_z * W_ * G_z.transpose();
  P_ll = 0.5 * (P_ll + P_ll.transpose()).eval();
  // The new rows lie outside the active block: writing them first leaves the
  // filter's state untouched if the result is refused below.
  auto P_lX = P_.block(off, 0, Layout::kLandmarkDim, n);
  P_lX.noalias() = G_x * P_.topRows<3>().leftCols(n);
  if (!p_LinW.allFinite() || !P_ll.allFinite() || (P_ll.diagonal().array() < 0.0).any() ||
      !P_lX.allFinite()) {
    return EkfStatus::kCovarianceFault;
  }
  P_.block(0, off, n, Layout::kLandmarkDim) = P_lX.transpose();
  P_.block<2, 2>(off, off) = P_ll;
  x_.segment<2>(off) = p_LinW;
  id_to_slot_[static_cast<std::size_t>(id)] = slot;
  slot_to_id_[static_cast<std::size_t>(slot)] = id;
  ++num_landmarks_;
  return EkfStatus::kOk;
}

// Marginalising a Gaussian = dropping its rows and columns. To keep the active
// block contiguous, the last slot's rows/columns move into the hole (O(n) copies).
EkfStatus EkfSlam::remove_landmark(int id) {
  if (!valid_id(id)) return EkfStatus::kBadInput;
  const int hole = slot_of(id);
  if (hole < 0) return EkfStatus::kUnknownLandmark;
  const int last = num_landmarks_ - 1;
  const Index oh = Layout::landmark_offset(hole), ol = Layout::landmark_offset(last);
  const Index n_new = Layout::dim(last);  // active dimension after removal
  constexpr Index kL = Layout::kLandmarkDim;
  if (hole != last) {
    const int moved_id = slot_to_id_[static_cast<std::size_t>(last)];
    // Columns first (contiguous), then the diagonal block, then the rows as the
    // transpose of the new columns, skipping the diagonal block they share.
    P_.block(0, oh, n_new, kL) = P_.block(0, ol, n_new, kL);
    P_.block<2, 2>(oh, oh) = P_.block<2, 2>(ol, ol);
    P_.block(oh, 0, kL, oh) = P_.block(0, oh, oh, kL).transpose();
    const Index tail = n_new - (oh + kL);
    P_.block(oh, oh + kL, kL, tail) = P_.block(oh + kL, oh, tail, kL).transpose();
    x_.segment<2>(oh) = x_.segment<2>(ol);
    id_to_slot_[static_cast<std::size_t>(moved_id)] = hole;
    slot_to_id_[static_cast<std::size_t>(hole)] = moved_id;
  }
  // Clear the vacated slot so that the inactive part of P stays zero.
  P_.block(0, ol, n_new + kL, kL).setZero();
  P_.block(ol, 0, kL, n_new + kL).setZero();
  x_.segment<2>(ol).setZero();
  id_to_slot_[static_cast<std::size_t>(id)] = -1;
  slot_to_id_[static_cast<std::size_t>(last)] = -1;
  --num_landmarks_;
  return EkfStatus::kOk;
}

// ---- accessors --------------------------------------------------------------------

bool EkfSlam::has_landmark(int id) const { return slot_of(id) >= 0; }

int EkfSlam::slot_of(int id) const {
  return valid_id(id) ? id_to_slot_[static_cast<std::size_t>(id)] : -1;
}

Pose2 EkfSlam::pose() const { return {x_(Layout::kX), x_(Layout::kY), x_(Layout::kTheta)}; }

Eigen::Matrix3d EkfSlam::pose_cov() const { return P_.topLeftCorner<3, 3>(); }

// Unmapped ids give NaN rather than a throw: library code never throws per frame.
Eigen::Vector2d EkfSlam::landmark(int id) const {
  const int slot = slot_of(id);
  if (slot < 0) return Eigen::Vector2d::Constant(kNaN);
  return x_.segment<2>(Layout::landmark_offset(slot));
}

Eigen::Matrix2d EkfSlam::landmark_cov(int id) const { return landmark_cross_cov(id, id); }

Eigen::Matrix2d EkfSlam::landmark_cross_cov(int id_i, int id_j) const {
  const int si = slot_of(id_i), sj = slot_of(id_j);
  if (si < 0 || sj < 0) return Eigen::Matrix2d::Constant(kNaN);
  return P_.block<2, 2>(Layout::landmark_offset(si), Layout::landmark_offset(sj));
}

Eigen::Matrix<double, 3, 2> EkfSlam::pose_landmark_cov(int id) const {
  const int slot = slot_of(id);
  if (slot < 0) return Eigen::Matrix<double, 3, 2>::Constant(kNaN);
  return P_.block<3, 2>(0, Layout::landmark_offset(slot));
}

double EkfSlam::mean_diag() const { return covariance().diagonal().mean(); }  // eq 19

}  // namespace elaslam

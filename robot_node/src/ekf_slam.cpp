// SPDX-License-Identifier: Apache-2.0
// Fixed-memory planar EKF-SLAM (docs/design.md section 3): prediction (paper eqs 3-6),
// correction (eqs 7-13), augmentation (eq 15) and mean(diag(P)) (eq 19) on the
// state of eqs 1-2 with the odometer's calibration states (updates need
// no change for them: H has zero columns there, and every row of the gain comes
// from P's columns like the landmarks'); ekf_slam.hpp lists where the other
// equations live.
//
// Cost per call, n = state dimension: predict O(n), update O(n k) for the k-th
// update in a row (its gain against P and the k - 1 covariance steps still
// pending), add and remove O(n); the pending covariance steps of a frame's updates
// are applied together, one O(n^2 k) pass over the lower triangle, when anything
// next reads P (settle). Only the lower triangle of P (and the 3x3 robot block in
// full) is kept current; the block accessors read it directly and covariance()
// completes the upper triangle on demand. Nothing here allocates after the constructor:
// scratch lives in members, small blocks are fixed-size, and products that Eigen
// might route through its blocked GEMM (which may allocate) are written as
// coefficient-wise expressions or loops (ekf_kernels.hpp).
#include "elaslam/robot_node/ekf_slam.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "ekf_kernels.hpp"
#include "elaslam/common/stats.hpp"

namespace elaslam {

namespace {

// Dimensions of the state layout's blocks, for fixed-size block expressions.
constexpr int kR = StateLayout::kPoseDim;         // the robot R = (x, y, theta)
constexpr int kC = StateLayout::kCalibrationDim;  // the odometer's calibration C = (s_w, s_v, b)
constexpr int kV = StateLayout::kVehicleDim;      // the vehicle block V = [R; C]
constexpr int kL = StateLayout::kLandmarkDim;     // one landmark l = (x, y)
constexpr int kCal = StateLayout::kCalibration;   // offset of C in X and P
constexpr int kObs = 2;                           // one observation (range, bearing)

using Matrix5 = Eigen::Matrix<double, kR + kL, kR + kL>;  // robot and one landmark

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool finite(const RangeBearing& z) { return std::isfinite(z.range) && std::isfinite(z.bearing); }

// ---- the order of three-term sums ----------------------------------------------------
//
// add_landmark's P_lX = G_x P_RX^T and update_landmark_only's P_RX H_x^T are sums
// of three products per entry. Each entry is added in the order Eigen's
// coefficient-based product gives it in the pose-only layout (3 pose states, a
// leading dimension of 3 + 2 capacity): left to right, (a0 + a1) + a2, for the
// entries it pairs in a vector register, a0 + (a1 + a2) for the others, by where
// the entry sits in that layout (measured for every size up to 128 landmarks).
// With the calibration states frozen the filter is then the pose-only filter bit
// for bit (tests/golden's references; both orders are equally exact), and the
// loops never allocate.
//
// The index of state i in the pose-only layout (-1: a calibration state).
Index index_before(Index i) { return i < kCal ? i : (i < kV ? -1 : i - kC); }
double sum3(double a0, double a1, double a2, bool left_to_right) {
  return left_to_right ? (a0 + a1) + a2 : a0 + (a1 + a2);
}

// The 2x2 diagonal block at `off` from the lower triangle.
Eigen::Matrix2d diagonal_block(const Eigen::MatrixXd& P, Index off) {
  Eigen::Matrix2d B;
  B << P(off, off), P(off + 1, off), P(off + 1, off), P(off + 1, off + 1);
  return B;
}

// The stored 5x5 block of P on the robot and the landmark at `off` (lower storage).
Matrix5 stored_block5(const Eigen::MatrixXd& P, Index off) {
  Matrix5 P5;
  const Eigen::Matrix<double, 2, 3> P_lR = P.block<kL, kR>(off, 0);
  P5 << P.topLeftCorner<kR, kR>(), P_lR.transpose(),  //
      P_lR, diagonal_block(P, off);
  return P5;
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

// H and the innovation nu (eqs 7-8) from the mean.
void observation_model(const Eigen::VectorXd& x, Index off, const RangeBearing& y, Innovation* out) {
  using L = StateLayout;
  const Pose2 pose{x(L::kX), x(L::kY), x(L::kTheta)};
  Eigen::Matrix<double, 2, 3> H_x;
  Eigen::Matrix2d H_l;
  const RangeBearing h = observe(pose, x.segment<kL>(off), &H_x, &H_l);  // eq 7
  out->H << H_x, H_l;
  out->nu << y.range - h.range, wrap_angle(y.bearing - h.bearing);  // eq 8
}

// L, w and d2 from Z = H P H^T + W (eq 9); kSingular unless Z is positive definite.
EkfStatus factor_innovation(const Eigen::Matrix2d& Z, Innovation* out) {
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

// Z = H P H^T + W (eq 9) from the 5x5 block.
EkfStatus innovate(const Matrix5& P5, const Eigen::VectorXd& x, Index off, const Eigen::Matrix2d& W,
                   const RangeBearing& y, Innovation* out) {
  observation_model(x, off, y, out);
  return factor_innovation(out->H * P5 * out->H.transpose() + W, out);
}

void fill_report(const Innovation& inn, UpdateReport* r) {
  r->d2 = inn.d2;
  r->innovation = inn.nu;
  r->whitened = inn.w;
}

// The innovation of a located landmark into `inn`, and its numbers into `r`; false
// (with r->status set) when the landmark was not located or Z is not positive definite.
// P5 is the block of P on the robot and the landmark at `off`.
bool innovation_report(const Matrix5& P5, const Eigen::VectorXd& x, Index off, const Eigen::Matrix2d& W,
                       const RangeBearing& z, Innovation* inn, UpdateReport* r) {
  r->status = innovate(P5, x, off, W, z, inn);
  if (r->status != EkfStatus::kOk) return false;
  fill_report(*inn, r);
  return true;
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
  const CalibrationOptions& c = options.calibration;
  if (!(c.prior.turn_scale > 0.0) || !(c.prior.speed_scale > 0.0) || !std::isfinite(c.prior.turn_scale) ||
      !std::isfinite(c.prior.speed_scale) || !std::isfinite(c.prior.turn_bias))
    fail("calibration prior: scales must be finite and > 0, the turn bias finite");
  for (double v : {c.turn_scale_sigma, c.speed_scale_sigma, c.turn_bias_sigma, c.turn_scale_walk, c.speed_scale_walk,
                   c.turn_bias_walk})
    if (!(v >= 0.0) || !std::isfinite(v)) fail("calibration sigmas and random walks must be finite and >= 0");
  calibration_estimated_ = c.estimated();
  calibration_walk_var_ << c.turn_scale_walk * c.turn_scale_walk, c.speed_scale_walk * c.speed_scale_walk,
      c.turn_bias_walk * c.turn_bias_walk;

  W_ = Eigen::Vector2d(options.range_sigma * options.range_sigma,
                       options.bearing_sigma * options.bearing_sigma)
           .asDiagonal();
  gate_threshold_ = chi2_quantile(options.gate_probability, 2);

  const Index n_max = Layout::dim(options.capacity);
  x_ = Eigen::VectorXd::Zero(n_max);
  P_ = Eigen::MatrixXd::Zero(n_max, n_max);
  id_to_slot_.assign(static_cast<std::size_t>(options.max_landmark_id), -1);
  slot_to_id_.assign(static_cast<std::size_t>(options.capacity), -1);
  PHt_ = Eigen::MatrixXd::Zero(n_max, kObs);
  fa_ = Eigen::MatrixXd::Zero(n_max + kFactorPadRows, kMaxFactorCols);  // padded: lower_factor_downdate
  if (options.joseph) fb_ = Eigen::MatrixXd::Zero(n_max + kFactorPadRows, kMaxFactorCols);
  diag_ = Eigen::VectorXd::Zero(n_max);
  tmp_rows_ = Eigen::MatrixXd::Zero(n_max, Layout::kPoseDim);
  lm_cols_ = Eigen::MatrixXd::Zero(n_max, kL);
  reset(Pose2{}, Eigen::Matrix3d::Zero());
}

void EkfSlam::reset(const Pose2& pose, const Eigen::Matrix3d& pose_cov) {
  // Outside the active block P_ is kept zero (remove_landmark clears what it
  // vacates), so clearing the active block is enough. Pending steps are void.
  pending_cols_ = 0;
  P_.topLeftCorner(state_dim(), state_dim()).setZero();
  for (int slot = 0; slot < num_landmarks_; ++slot) {
    id_to_slot_[static_cast<std::size_t>(slot_to_id_[static_cast<std::size_t>(slot)])] = -1;
    slot_to_id_[static_cast<std::size_t>(slot)] = -1;
  }
  num_landmarks_ = 0;
  x_.setZero();
  x_.head<kR>() << pose.x, pose.y, wrap_angle(pose.theta);
  P_.topLeftCorner<kR, kR>() = 0.5 * (pose_cov + pose_cov.transpose());
  const CalibrationOptions& c = options_.calibration;
  x_.segment<kC>(kCal) << c.prior.turn_scale, c.prior.speed_scale, c.prior.turn_bias;
  P_.block<kC, kC>(kCal, kCal) =
      Eigen::Vector3d(c.turn_scale_sigma * c.turn_scale_sigma, c.speed_scale_sigma * c.speed_scale_sigma,
                      c.turn_bias_sigma * c.turn_bias_sigma)
          .asDiagonal();
  upper_stale_ = false;
}

// ---- prediction (eqs 3-6) -----------------------------------------------------

EkfStatus EkfSlam::predict(const Pose2& increment, const Eigen::Matrix3d& U, double dt) {
  // U must be a covariance: finite, symmetric, non-negative variances. (Positive
  // semi-definiteness beyond that is the caller's; a negative variance it causes
  // is refused below.) dt: finite and >= 0.
  const bool finite_u = std::isfinite(increment.x) && std::isfinite(increment.y) &&
                        std::isfinite(increment.theta) && U.allFinite() && std::isfinite(dt);
  if (!finite_u || (U - U.transpose()).cwiseAbs().maxCoeff() > 1e-9 * U.cwiseAbs().maxCoeff() ||
      (U.diagonal().array() < 0.0).any() || dt < 0.0) {
    return EkfStatus::kBadInput;
  }
  settle();
  // The calibrated increment u(c) and its Jacobians du/dc, du/du_r (models.hpp).
  Eigen::Matrix3d F_x, F_u, J_c, J_r;
  const Pose2 u = calibrated_increment(increment, calibration(), dt, &J_c, &J_r);
  const Pose2 next = motion(pose(), u, &F_x, &F_u);  // eq 4
  const Index m = state_dim() - Layout::kVehicleDim;  // landmark part of X
  // The reported increment's noise in u's coordinates: J_r U J_r^T, J_r diagonal
  // (entry by entry, so that J_r = I leaves U's bits as they are).
  const Eigen::Vector3d j = J_r.diagonal();
  const Eigen::Matrix3d U_u = (U.array() * (j * j.transpose()).array()).matrix();

  // Compute into temporaries, commit only when healthy.
  Eigen::Matrix3d P_RR = F_x * P_.topLeftCorner<kR, kR>() * F_x.transpose() +
                         F_u * U_u * F_u.transpose();  // eq 5, robot block
  Eigen::Matrix3d F_c = Eigen::Matrix3d::Zero(), P_CR, P_CC;
  if (calibration_estimated_) {
    // eq 5 on V = [R; C] with F_V = [[F_x, F_c], [0, I]]: the terms through C. P_CR
    // and P_CC are read from the lower triangle.
    F_c = F_u * J_c;
    const Eigen::Matrix3d P_CR_old = P_.block<kC, kR>(kCal, Layout::kX);
    const Eigen::Matrix3d P_CC_old = P_.block<kC, kC>(kCal, kCal).selfadjointView<Eigen::Lower>();
    const Eigen::Matrix3d A = F_x * P_CR_old.transpose() * F_c.transpose();
    P_RR += A + A.transpose() + F_c * P_CC_old * F_c.transpose();
    P_CR = P_CR_old * F_x.transpose() + P_CC_old * F_c.transpose();
    P_CC = P_CC_old;
    P_CC.diagonal() += calibration_walk_var_ * dt;  // the random walk over the step
  }
  P_RR = 0.5 * (P_RR + P_RR.transpose()).eval();
  // eq 5, cross terms: landmarks do not move, so P_LR <- P_LR F_x^T (+ P_LC F_c^T
  // with the calibration estimated) and no more. P_LR sits below the vehicle block
  // (lower storage): each row becomes F_x times itself (plus F_c times its P_LC
  // part), computed into the m x 3 scratch first.
  const double F[3][3] = {{F_x(0, 0), F_x(0, 1), F_x(0, 2)},
                          {F_x(1, 0), F_x(1, 1), F_x(1, 2)},
                          {F_x(2, 0), F_x(2, 1), F_x(2, 2)}};
  const Index ld = P_.outerStride();
  const Index first = Layout::landmark_offset(0);
  double* t0 = tmp_rows_.col(0).data();
  double* t1 = tmp_rows_.col(1).data();
  double* t2 = tmp_rows_.col(2).data();
  const double* col = P_.data() + first;  // column 0 at the first landmark row
  bool cross_ok = false;
  if (calibration_estimated_) {
    const double G[3][3] = {{F_c(0, 0), F_c(0, 1), F_c(0, 2)},
                            {F_c(1, 0), F_c(1, 1), F_c(1, 2)},
                            {F_c(2, 0), F_c(2, 1), F_c(2, 2)}};
    cross_ok = predict_cross_rows_calibrated(m, col, col + ld, col + 2 * ld, col + kCal * ld, col + (kCal + 1) * ld,
                                             col + (kCal + 2) * ld, F, G, t0, t1, t2);
  } else {
    cross_ok = predict_cross_rows(m, col, col + ld, col + 2 * ld, F, t0, t1, t2);
  }
  if (!P_RR.allFinite() || (P_RR.diagonal().array() < 0.0).any() || !cross_ok) {
    return EkfStatus::kCovarianceFault;
  }
  if (calibration_estimated_ && (!P_CR.allFinite() || !P_CC.allFinite())) return EkfStatus::kCovarianceFault;

  x_.head<kR>() << next.x, next.y, next.theta;  // theta wrapped by compose()
  P_.topLeftCorner<kR, kR>() = P_RR;
  if (calibration_estimated_) {
    P_.block<kC, kR>(kCal, Layout::kX) = P_CR;
    P_.block<kC, kC>(kCal, kCal) = P_CC;
    upper_stale_ = true;
  }
  std::copy(t0, t0 + m, P_.data() + first);
  std::copy(t1, t1 + m, P_.data() + ld + first);
  std::copy(t2, t2 + m, P_.data() + 2 * ld + first);
  upper_stale_ = upper_stale_ || m > 0;
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
  const Index off = Layout::landmark_offset(slot);
  Innovation inn;
  innovation_report(block5(off), x_, off, W_, z, &inn, &report);
  return report;
}

UpdateReport EkfSlam::update(int id, const RangeBearing& z, bool gate) {
  UpdateReport report;
  report.threshold = gate ? gate_threshold_ : 0.0;
  int slot = -1;
  report.status = locate(id, z, &slot);
  if (report.status != EkfStatus::kOk) return report;
  // The factors of this update must fit beside the pending ones.
  if (pending_cols_ + factor_cols() > kMaxFactorCols) settle();
  const Index off = Layout::landmark_offset(slot);
  Innovation inn;
  observation_model(x_, off, z, &inn);
  // P H^T first (pending steps included): Z = H (P H^T) + W needs only five of its rows.
  compute_pht(off, inn.H);
  const Index rows[5] = {Layout::kX, Layout::kY, Layout::kTheta, off, off + 1};
  Eigen::Matrix2d Z = W_;
  for (int r = 0; r < 5; ++r)
    for (int b = 0; b < kObs; ++b) Z.col(b) += inn.H.col(r) * PHt_(rows[r], b);
  report.status = factor_innovation(Z, &inn);
  if (report.status != EkfStatus::kOk) return report;
  fill_report(inn, &report);
  if (gate && inn.d2 > gate_threshold_) {
    report.status = EkfStatus::kGated;
    return report;
  }
  if (!compute_gain(inn.L, inn.nu, inn.w)) {
    report.status = EkfStatus::kCovarianceFault;
    return report;
  }
  apply_correction(inn.nu, inn.w);
  return report;
}

UpdateReport EkfSlam::update_landmark_only(int id, const RangeBearing& z) {
  UpdateReport report;
  int slot = -1;
  report.status = locate(id, z, &slot);
  if (report.status != EkfStatus::kOk) return report;
  settle();  // the step below is applied at once
  const Index off = Layout::landmark_offset(slot);
  const Index n = state_dim();
  Innovation inn;
  if (!innovation_report(stored_block5(P_, off), x_, off, W_, z, &inn, &report)) return report;
  // P H^T (n x 2) from the robot columns (complete) and the landmark's columns.
  load_landmark_columns(off);
  auto PHt = PHt_.topRows(n);
  // The robot part's three-term sums in the order of before (index_before): left
  // to right but for the last row of column 0 and the first of column 1 (that
  // layout's odd sizes left them alone); the landmark part's two-term sums have
  // one order.
  const Index n_before = n - kC;
  for (Index i = 0; i < n; ++i) {
    const Index b = index_before(i);
    for (int c = 0; c < kObs; ++c) {
      const bool left_to_right = c == 0 ? b != n_before - 1 : b != 0;
      const double robot = sum3(P_(i, 0) * inn.H(c, 0), P_(i, 1) * inn.H(c, 1), P_(i, 2) * inn.H(c, 2), left_to_right);
      PHt(i, c) = robot + (lm_cols_(i, 0) * inn.H(c, kR) + lm_cols_(i, 1) * inn.H(c, kR + 1));
    }
  }
  // K_l = (P H^T)_l Z^-1 with Z = L L^T.
  const Eigen::Matrix2d Z = inn.L * inn.L.transpose();
  const Eigen::Matrix2d K_l = PHt.middleRows<kL>(off) * Z.inverse();
  Eigen::Matrix2d P_ll = P_.block<kL, kL>(off, off).selfadjointView<Eigen::Lower>();
  P_ll -= K_l * Z * K_l.transpose();
  P_ll = 0.5 * (P_ll + P_ll.transpose()).eval();
  const Eigen::Vector2d x_l = x_.segment<kL>(off) + K_l * inn.nu;
  if (!x_l.allFinite() || !P_ll.allFinite() || (P_ll.diagonal().array() < 0.0).any()) {
    report.status = EkfStatus::kCovarianceFault;
    return report;
  }
  // Row block l in lower storage: columns before it along its rows, rows after it
  // down its columns.
  P_.block(off, 0, kL, off).noalias() -= K_l * PHt.topRows(off).transpose();
  const Index below = n - off - kL;
  if (below > 0) P_.block(off + kL, off, below, kL).noalias() -= PHt.bottomRows(below) * K_l.transpose();
  P_.block<kL, kL>(off, off) = P_ll;
  x_.segment<kL>(off) = x_l;
  upper_stale_ = true;
  return report;
}

// A linear measurement of the landmark's position: H = [0 .. I .. 0], so P H^T is
// the landmark's two columns and Z = P_ll + R. position_innovation checks the input
// and fills the report (innovation, whitened, d2) and the factor L of Z = L L^T.
// update_position then puts the gain factors where update() puts them
// (compute_gain): Joseph K = P H^T Z^-1 and B = P H^T - K Z / 2, standard
// M = P H^T L^-T; the same health check and covariance step follow.
bool EkfSlam::position_innovation(int id, const Eigen::Vector2d& z, const Eigen::Matrix2d& R, int* slot,
                                  Eigen::Matrix2d* L, UpdateReport* report) const {
  const bool r_ok = R.allFinite() && std::fabs(R(0, 1) - R(1, 0)) <= 1e-9 * R.cwiseAbs().maxCoeff() &&
                    R(0, 0) > 0.0 && R(1, 1) > 0.0 && R.determinant() > 0.0;
  if (!valid_id(id) || !z.allFinite() || !r_ok) {
    report->status = EkfStatus::kBadInput;
    return false;
  }
  *slot = slot_of(id);
  if (*slot < 0) {
    report->status = EkfStatus::kUnknownLandmark;
    return false;
  }
  const Index off = Layout::landmark_offset(*slot);
  // P H^T = the landmark's two columns (pending steps included); Z = P_ll + R.
  Matrix25 H = Matrix25::Zero();
  H(0, kR) = 1.0;
  H(1, kR + 1) = 1.0;
  compute_pht(off, H);
  Eigen::Matrix2d Z = PHt_.block<kL, kL>(off, 0) + R;
  Z = 0.5 * (Z + Z.transpose()).eval();
  const Eigen::LLT<Eigen::Matrix2d> llt(Z);
  if (llt.info() != Eigen::Success) {
    report->status = EkfStatus::kSingular;
    return false;
  }
  *L = llt.matrixL();
  report->innovation = z - x_.segment<kL>(off);
  report->whitened = L->triangularView<Eigen::Lower>().solve(report->innovation);
  report->d2 = report->whitened.squaredNorm();
  return true;
}

UpdateReport EkfSlam::check_position(int id, const Eigen::Vector2d& z, const Eigen::Matrix2d& R) const {
  UpdateReport report;
  int slot = -1;
  Eigen::Matrix2d L;
  position_innovation(id, z, R, &slot, &L, &report);
  return report;
}

UpdateReport EkfSlam::update_position(int id, const Eigen::Vector2d& z, const Eigen::Matrix2d& R) {
  UpdateReport report;
  int slot = -1;
  Eigen::Matrix2d L;
  if (pending_cols_ + factor_cols() > kMaxFactorCols) settle();
  if (!position_innovation(id, z, R, &slot, &L, &report)) return report;
  if (!compute_gain(L, report.innovation, report.whitened)) {  // from position_innovation's P H^T
    report.status = EkfStatus::kCovarianceFault;
    return report;
  }
  apply_correction(report.innovation, report.whitened);
  return report;
}

EkfStatus EkfSlam::move_landmark(int id, const Eigen::Vector2d& delta, const Eigen::Matrix2d& Q) {
  const double scale = Q.cwiseAbs().maxCoeff();
  const bool q_ok = Q.allFinite() && std::fabs(Q(0, 1) - Q(1, 0)) <= 1e-9 * scale && Q(0, 0) >= 0.0 &&
                    Q(1, 1) >= 0.0 && Q.determinant() >= -1e-12 * scale * scale;
  if (!valid_id(id) || !delta.allFinite() || !q_ok) return EkfStatus::kBadInput;
  const int slot = slot_of(id);
  if (slot < 0) return EkfStatus::kUnknownLandmark;
  settle();
  const Index off = Layout::landmark_offset(slot);
  x_.segment<kL>(off) += delta;
  P_(off, off) += Q(0, 0);
  P_(off + 1, off) += 0.5 * (Q(1, 0) + Q(0, 1));
  P_(off + 1, off + 1) += Q(1, 1);
  upper_stale_ = true;
  return EkfStatus::kOk;
}

// The landmark's two columns of P into lm_cols_: above the landmark block they are
// read along its rows (lower storage), from the block down along the columns.
void EkfSlam::load_landmark_columns(Index off) const {
  const Index n = state_dim();
  lm_cols_.topRows(off) = P_.block(off, 0, 2, off).transpose();
  lm_cols_.block(off, 0, n - off, 1) = P_.col(off).segment(off, n - off);
  lm_cols_(off, 1) = P_(off + 1, off);
  lm_cols_.block(off + 1, 1, n - off - 1, 1) = P_.col(off + 1).segment(off + 1, n - off - 1);
}

// The block of P on the robot and the landmark at `off` with the pending steps
// applied: the stored block minus the pending factors' rows of those five states,
// O(25 k) for k pending columns.
Matrix5 EkfSlam::block5(Index off) const {
  Matrix5 P5 = stored_block5(P_, off);
  if (pending_cols_ == 0) return P5;
  const Index rows[5] = {Layout::kX, Layout::kY, Layout::kTheta, off, off + 1};
  const Eigen::MatrixXd& fb = options_.joseph ? fb_ : fa_;
  for (int q = 0; q < pending_cols_; ++q) {
    Eigen::Matrix<double, 5, 1> a, b;
    for (int r = 0; r < 5; ++r) {
      a(r) = fa_(rows[r], q);
      b(r) = fb(rows[r], q);
    }
    P5.noalias() -= a * b.transpose();
  }
  return 0.5 * (P5 + P5.transpose());
}

// G = P H^T into PHt_ from the five non-zero columns of H, O(n), corrected for the
// pending steps (P = P_ - A B^T, so G -= A (H B^T)^T, O(n k)).
void EkfSlam::compute_pht(Index off, const Matrix25& H) const {
  const Index n = state_dim();
  GainCoefficients c{};
  for (int k = 0; k < 5; ++k) {
    c.h0[k] = H(0, k);
    c.h1[k] = H(1, k);
  }
  double* g0 = PHt_.col(0).data();
  double* g1 = PHt_.col(1).data();
  // Robot columns 0..2 of P are complete (the robot block is kept full).
  pht_rows(c, n, off, P_.data(), P_.outerStride(), g0, g1);
  if (pending_cols_ == 0) return;
  const Index rows[5] = {Layout::kX, Layout::kY, Layout::kTheta, off, off + 1};
  const Eigen::MatrixXd& fb = options_.joseph ? fb_ : fa_;
  for (int q = 0; q < pending_cols_; ++q) {  // E = H B^T on the five states, 2 x k, by rows
    double e0 = 0.0, e1 = 0.0;
    for (int r = 0; r < 5; ++r) {
      e0 += c.h0[r] * fb(rows[r], q);
      e1 += c.h1[r] * fb(rows[r], q);
    }
    erow0_[static_cast<std::size_t>(q)] = e0;
    erow1_[static_cast<std::size_t>(q)] = e1;
  }
  subtract_factor_rows(n, fa_.data(), fa_.outerStride(), pending_cols_, erow0_.data(), erow1_.data(), g0, g1);
}

// The gain factors of one correction from G = P H^T (compute_pht), into the next
// free columns of fa_:
//   Joseph:   K = G Z^-1 (eq 10) and B = G - K Z / 2, so that
//             (I-KH)P(I-KH)^T + K W K^T = P - K G^T - G K^T + K Z K^T
//                                      = P - K B^T - B K^T            (rank 4);
//   standard: M = G L^-T, so that P - K Z K^T = P - M M^T             (eq 12, rank 2).
// In exact arithmetic both equal P - G Z^-1 G^T; the Joseph form adds E Z E^T for
// an error E in K, so it stays positive semi-definite for any gain.
// With them, the O(n) preview of the update: the new mean and the new diagonal of
// P must be finite, the diagonal non-negative (up to rounding), and no
// off-diagonal product may overflow; then the covariance step cannot make P or X
// non-finite. Mean step: Joseph K nu, standard M w (the same vector, eq 11);
// diagonal step: Joseph 2 k_i . b_i, standard m_i . m_i. False: refuse the update.
bool EkfSlam::compute_gain(const Eigen::Matrix2d& L, const Eigen::Vector2d& nu, const Eigen::Vector2d& w) {
  const Index n = state_dim();
  const GainCoefficients c = gain_coefficients(Matrix25::Zero(), L);
  const double* g0 = PHt_.col(0).data();
  const double* g1 = PHt_.col(1).data();
  const int p = pending_cols_;
  double* k0 = fa_.col(p).data();
  double* k1 = fa_.col(p + 1).data();
  // The health check below reads P's diagonal: P_'s, or diag_ (P's with the
  // pending steps in) while steps are pending.
  const double* diag = p == 0 ? P_.data() : diag_.data();
  const Index stride = p == 0 ? P_.outerStride() + 1 : 1;
  if (!options_.joseph) {
    gain_standard(c, n, g0, g1, k0, k1);
    return rows_healthy(n, diag, stride, x_.data(), k0, k1, k0, k1, w(0), w(1), 1.0);
  }
  double* b0 = fa_.col(p + 2).data();
  double* b1 = fa_.col(p + 3).data();
  gain_joseph(c, n, g0, g1, k0, k1, b0, b1);
  return rows_healthy(n, diag, stride, x_.data(), k0, k1, b0, b1, nu(0), nu(1), 2.0);
}

// The mean step now (eq 11); the covariance step joins the pending ones (settle).
void EkfSlam::apply_correction(const Eigen::Vector2d& nu, const Eigen::Vector2d& w) {
  const Index n = state_dim();
  const bool joseph = options_.joseph;
  const int p = pending_cols_;
  const Eigen::Vector2d& v = joseph ? nu : w;  // Joseph: K nu; standard: K nu = M L^-1 nu = M w
  const double* a0 = fa_.col(p).data();
  const double* a1 = fa_.col(p + 1).data();
  const double* b0 = joseph ? fa_.col(p + 2).data() : a0;
  const double* b1 = joseph ? fa_.col(p + 3).data() : a1;
  if (p == 0) diag_.head(n) = P_.diagonal().head(n);
  commit_rows(n, x_.data(), diag_.data(), a0, a1, b0, b1, v(0), v(1), joseph ? 2.0 : 1.0);
  x_(Layout::kTheta) = wrap_angle(x_(Layout::kTheta));
  if (joseph) {  // P -= [K B] [B K]^T = K B^T + B K^T
    fb_.col(p).head(n) = fa_.col(p + 2).head(n);
    fb_.col(p + 1).head(n) = fa_.col(p + 3).head(n);
    fb_.col(p + 2).head(n) = fa_.col(p).head(n);
    fb_.col(p + 3).head(n) = fa_.col(p + 1).head(n);
  }
  pending_cols_ += factor_cols();
  upper_stale_ = true;
}

// The pending covariance steps, one pass over the lower triangle (O(n^2 k)).
void EkfSlam::settle() const {
  if (pending_cols_ == 0) return;
  const double* fb = options_.joseph ? fb_.data() : fa_.data();
  lower_factor_downdate(P_.data(), P_.outerStride(), state_dim(), fa_.data(), fb, fa_.outerStride(),
                        pending_cols_);
  pending_cols_ = 0;
  // Keep the robot block full: columns 0..2 of P stay complete.
  P_(Layout::kX, Layout::kY) = P_(Layout::kY, Layout::kX);
  P_(Layout::kX, Layout::kTheta) = P_(Layout::kTheta, Layout::kX);
  P_(Layout::kY, Layout::kTheta) = P_(Layout::kTheta, Layout::kY);
  upper_stale_ = true;
}

void EkfSlam::complete_upper_triangle() const {
  mirror_lower_to_upper(P_.data(), P_.outerStride(), state_dim());
  upper_stale_ = false;
}

// ---- map management ---------------------------------------------------------------

// Augmentation by the inverse observation (eq 15): l = g(R, y),
//   P_ll = G_x P_RR G_x^T + G_z W G_z^T,  P_lX = G_x P_RX.
// g depends on the pose alone: the new landmark's cross terms with the calibration
// states are G_x P_RC (rows 3..5 of the robot columns, P_CR).
EkfStatus EkfSlam::add_landmark(int id, const RangeBearing& z) {
  if (!valid_id(id) || !finite(z) || !(z.range > 0.0)) return EkfStatus::kBadInput;
  if (has_landmark(id)) return EkfStatus::kAlreadyMapped;
  if (num_landmarks_ >= options_.capacity) return EkfStatus::kFull;
  settle();

  Eigen::Matrix<double, 2, 3> G_x;
  Eigen::Matrix2d G_z;
  const Eigen::Vector2d p_LinW = inverse_observe(pose(), z, &G_x, &G_z);
  const int slot = num_landmarks_;
  const Index off = Layout::landmark_offset(slot);
  const Index n = state_dim();
  Eigen::Matrix2d P_ll = G_x * P_.topLeftCorner<kR, kR>() * G_x.transpose() +
                         G_z * W_ * G_z.transpose();
  P_ll = 0.5 * (P_ll + P_ll.transpose()).eval();
  // The new rows lie outside the active block: writing them first leaves the
  // filter's state untouched if the result is refused below. P_RX^T is the
  // (complete) robot columns 0..2.
  auto P_lX = P_.block(off, 0, Layout::kLandmarkDim, n);
  // Column j summed in the order of before (index_before): left to right where
  // its two rows were aligned in that layout, at odd columns (the new landmark's
  // rows were at an odd offset and the leading dimension odd).
  for (Index j = 0; j < n; ++j) {
    const bool left_to_right = index_before(j) % 2 != 0;
    for (int r = 0; r < kL; ++r)
      P_lX(r, j) = sum3(G_x(r, 0) * P_(j, 0), G_x(r, 1) * P_(j, 1), G_x(r, 2) * P_(j, 2), left_to_right);
  }
  if (!p_LinW.allFinite() || !P_ll.allFinite() || (P_ll.diagonal().array() < 0.0).any() ||
      !P_lX.allFinite()) {
    P_lX.setZero();  // outside the active block P_ stays zero
    return EkfStatus::kCovarianceFault;
  }
  P_.block<kL, kL>(off, off) = P_ll;
  x_.segment<kL>(off) = p_LinW;
  id_to_slot_[static_cast<std::size_t>(id)] = slot;
  slot_to_id_[static_cast<std::size_t>(slot)] = id;
  ++num_landmarks_;
  upper_stale_ = true;
  return EkfStatus::kOk;
}

// Marginalising a Gaussian = dropping its rows and columns. To keep the active
// block contiguous, the last slot's entries move into the hole (O(n) copies, all
// within the lower triangle).
EkfStatus EkfSlam::remove_landmark(int id) {
  if (!valid_id(id)) return EkfStatus::kBadInput;
  const int hole = slot_of(id);
  if (hole < 0) return EkfStatus::kUnknownLandmark;
  settle();
  const int last = num_landmarks_ - 1;
  const Index oh = Layout::landmark_offset(hole), ol = Layout::landmark_offset(last);
  if (hole != last) {
    const int moved_id = slot_to_id_[static_cast<std::size_t>(last)];
    // Robot and the slots before the hole: along the rows.
    P_.block(oh, 0, kL, oh) = P_.block(ol, 0, kL, oh);
    // Slots between hole and last: P(s, hole) = P(last, s)^T.
    const Index between = ol - (oh + kL);
    P_.block(oh + kL, oh, between, kL) = P_.block(ol, oh + kL, kL, between).transpose();
    P_.block<kL, kL>(oh, oh) = P_.block<kL, kL>(ol, ol);
    x_.segment<kL>(oh) = x_.segment<kL>(ol);
    id_to_slot_[static_cast<std::size_t>(moved_id)] = hole;
    slot_to_id_[static_cast<std::size_t>(hole)] = moved_id;
  }
  // Clear the vacated slot so that the inactive part of P stays zero.
  P_.block(0, ol, ol + kL, kL).setZero();
  P_.block(ol, 0, kL, ol + kL).setZero();
  x_.segment<kL>(ol).setZero();
  id_to_slot_[static_cast<std::size_t>(id)] = -1;
  slot_to_id_[static_cast<std::size_t>(last)] = -1;
  --num_landmarks_;
  upper_stale_ = true;
  return EkfStatus::kOk;
}

// ---- accessors (all read the lower triangle) ---------------------------------------

// ---- state file -----------------------------------------------------------------

EkfStatus EkfSlam::restore(const Eigen::VectorXd& x, const Eigen::MatrixXd& P, const std::vector<int>& slot_ids) {
  const int n = static_cast<int>(slot_ids.size());
  const Index dim = Layout::dim(n);
  if (n > options_.capacity || x.size() != dim || P.rows() != dim || P.cols() != dim) return EkfStatus::kBadInput;
  std::vector<std::uint8_t> used(static_cast<std::size_t>(options_.max_landmark_id), 0);
  for (int id : slot_ids) {
    if (!valid_id(id) || used[static_cast<std::size_t>(id)]) return EkfStatus::kBadInput;
    used[static_cast<std::size_t>(id)] = 1;
  }
  std::fill(id_to_slot_.begin(), id_to_slot_.end(), -1);
  std::fill(slot_to_id_.begin(), slot_to_id_.end(), -1);
  for (int slot = 0; slot < n; ++slot) {
    slot_to_id_[static_cast<std::size_t>(slot)] = slot_ids[static_cast<std::size_t>(slot)];
    id_to_slot_[static_cast<std::size_t>(slot_ids[static_cast<std::size_t>(slot)])] = slot;
  }
  num_landmarks_ = n;
  pending_cols_ = 0;
  x_.setZero();
  x_.head(dim) = x;
  P_.setZero();  // the inactive part of P stays zero (reset, remove_landmark)
  P_.topLeftCorner(dim, dim) = P;
  upper_stale_ = false;
  return EkfStatus::kOk;
}

EkfStatus EkfSlam::assign(const EkfSlam& other) {
  if (&other == this) return EkfStatus::kOk;
  if (other.options_.capacity != options_.capacity || other.options_.max_landmark_id != options_.max_landmark_id)
    return EkfStatus::kBadInput;
  other.settle();
  settle();
  const Index old_dim = state_dim(), dim = other.state_dim();
  for (int slot = 0; slot < num_landmarks_; ++slot) id_to_slot_[static_cast<std::size_t>(slot_to_id_[static_cast<std::size_t>(slot)])] = -1;
  for (int slot = 0; slot < other.num_landmarks_; ++slot) {
    const int id = other.slot_to_id_[static_cast<std::size_t>(slot)];
    slot_to_id_[static_cast<std::size_t>(slot)] = id;
    id_to_slot_[static_cast<std::size_t>(id)] = slot;
  }
  for (int slot = other.num_landmarks_; slot < num_landmarks_; ++slot) slot_to_id_[static_cast<std::size_t>(slot)] = -1;
  num_landmarks_ = other.num_landmarks_;
  x_.head(dim) = other.x_.head(dim);
  // The lower triangle (and the robot block) is what is current; the inactive part
  // of P stays zero (reset, remove_landmark).
  for (Index c = 0; c < dim; ++c) P_.col(c).segment(c, dim - c) = other.P_.col(c).segment(c, dim - c);
  P_.topLeftCorner<kR, kR>() = other.P_.topLeftCorner<kR, kR>();
  if (old_dim > dim) {
    x_.segment(dim, old_dim - dim).setZero();
    P_.block(dim, 0, old_dim - dim, old_dim).setZero();
    P_.block(0, dim, old_dim, old_dim - dim).setZero();
  }
  upper_stale_ = true;
  return EkfStatus::kOk;
}

EkfStatus EkfSlam::apply_rigid_motion(double rotation, const Eigen::Vector2d& translation) {
  if (!std::isfinite(rotation) || !translation.allFinite()) return EkfStatus::kBadInput;
  settle();
  if (upper_stale_) complete_upper_triangle();
  const double c = std::cos(rotation), s = std::sin(rotation);
  const Index n = state_dim();
  // A = blockdiag(R on the robot's position, 1 on its heading, R on each landmark):
  // rows first (A P), then columns ((A P) A^T), each block's pair in place.
  const auto turn_pair = [c, s](double* a, double* b) {
    const double u = *a, v = *b;
    *a = c * u - s * v;
    *b = s * u + c * v;
  };
  const auto position_block = [](int k) { return k == 0 ? Index{Layout::kX} : Layout::landmark_offset(k - 1); };
  for (int k = 0; k <= num_landmarks_; ++k) {
    const Index o = position_block(k);
    for (Index j = 0; j < n; ++j) turn_pair(&P_(o, j), &P_(o + 1, j));
  }
  for (int k = 0; k <= num_landmarks_; ++k) {
    const Index o = position_block(k);
    for (Index i = 0; i < n; ++i) turn_pair(&P_(i, o), &P_(i, o + 1));
    Eigen::Vector2d p = x_.segment<kL>(o);
    turn_pair(&p.x(), &p.y());
    x_.segment<kL>(o) = p + translation;
  }
  static_assert(Layout::kY == Layout::kX + 1, "the robot's position is one block");
  x_(Layout::kTheta) = wrap_angle(x_(Layout::kTheta) + rotation);
  upper_stale_ = false;  // A P A^T of a symmetric P: both triangles current
  return EkfStatus::kOk;
}

bool EkfSlam::has_landmark(int id) const { return slot_of(id) >= 0; }

int EkfSlam::slot_of(int id) const {
  return valid_id(id) ? id_to_slot_[static_cast<std::size_t>(id)] : -1;
}

Pose2 EkfSlam::pose() const { return {x_(Layout::kX), x_(Layout::kY), x_(Layout::kTheta)}; }

OdometryCalibration EkfSlam::calibration() const {
  return {x_(Layout::kTurnScale), x_(Layout::kSpeedScale), x_(Layout::kTurnBias)};
}

Eigen::Matrix3d EkfSlam::calibration_cov() const {
  settle();
  return P_.block<kC, kC>(kCal, kCal).selfadjointView<Eigen::Lower>();
}

Eigen::Matrix3d EkfSlam::pose_cov() const {
  settle();
  return P_.topLeftCorner<kR, kR>();
}

// Unmapped ids give NaN rather than a throw: library code never throws per frame.
Eigen::Vector2d EkfSlam::landmark(int id) const {
  const int slot = slot_of(id);
  if (slot < 0) return Eigen::Vector2d::Constant(kNaN);
  return x_.segment<kL>(Layout::landmark_offset(slot));
}

Eigen::Matrix2d EkfSlam::landmark_cov(int id) const {
  const int slot = slot_of(id);
  if (slot < 0) return Eigen::Matrix2d::Constant(kNaN);
  settle();
  return diagonal_block(P_, Layout::landmark_offset(slot));
}

Eigen::Matrix2d EkfSlam::landmark_cross_cov(int id_i, int id_j) const {
  const int si = slot_of(id_i), sj = slot_of(id_j);
  if (si < 0 || sj < 0) return Eigen::Matrix2d::Constant(kNaN);
  settle();
  const Index oi = Layout::landmark_offset(si), oj = Layout::landmark_offset(sj);
  if (si == sj) return diagonal_block(P_, oi);
  return si > sj ? Eigen::Matrix2d(P_.block<kL, kL>(oi, oj))
                 : Eigen::Matrix2d(P_.block<kL, kL>(oj, oi).transpose());
}

Eigen::Matrix<double, 3, 2> EkfSlam::pose_landmark_cov(int id) const {
  const int slot = slot_of(id);
  if (slot < 0) return Eigen::Matrix<double, 3, 2>::Constant(kNaN);
  settle();
  return P_.block<kL, kR>(Layout::landmark_offset(slot), 0).transpose();
}

double EkfSlam::mean_diag() const {  // eq 19, over R and M (not C)
  settle();
  // Summed in index order, as Eigen's mean() of the diagonal sums it.
  double sum = P_(Layout::kX, Layout::kX);
  for (Index i = Layout::kY; i < state_dim(); ++i)
    if (i < kCal || i >= kCal + kC) sum += P_(i, i);
  return sum / static_cast<double>(state_dim() - kC);
}

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
#include "elaslam/robot_node/mover_track.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/LU>

#include "elaslam/common/stats.hpp"
#include "elaslam/common/track_motion.hpp"

namespace elaslam {
namespace {

using Mat2 = Eigen::Matrix2d;
using Vec2 = Eigen::Vector2d;
using Mat42 = Eigen::Matrix<double, 4, 2>;

void require(bool ok, const char* key, const char* what) {
  if (!ok) throw std::invalid_argument(std::string("mover track: ") + key + " " + what);
}
bool positive(double v) { return std::isfinite(v) && v > 0.0; }

/// A sighting's world position and its covariance, the pose's included.
Vec2 position_of(const TrackSighting& s, Mat2* P) {
  Eigen::Matrix<double, 2, 3> G_x;
  Mat2 G_z;
  const Vec2 p = inverse_observe(s.pose, s.z, &G_x, &G_z);
  *P = G_x * s.pose_cov * G_x.transpose() + G_z * s.R * G_z.transpose();
  return p;
}

/// Per-axis 2x2 blocks [[a, b], [c, d]] of (p, v) written onto both axes of the
/// 4x4 (p_x, p_y, v_x, v_y) matrix.
TrackMatrix per_axis(double a, double b, double c, double d) {
  TrackMatrix M = TrackMatrix::Zero();
  for (int k = 0; k < 2; ++k) {
    M(k, k) = a;
    M(k, k + 2) = b;
    M(k + 2, k) = c;
    M(k + 2, k + 2) = d;
  }
  return M;
}

}  // namespace

const char* motion_model_name(MotionModel m) {
  switch (m) {
    case MotionModel::kStatic: return "static";
    case MotionModel::kBounded: return "bounded";
    case MotionModel::kConstantVelocity: return "constant_velocity";
  }
  return "unknown";
}

MoverTrack::MoverTrack(const MoverTrackOptions& o) : options_(o) {
  require(positive(o.model_sojourn_s), "model_sojourn_s", "must be positive and finite");
  require(positive(o.static_walk_m_per_sqrt_s), "static_walk_m_per_sqrt_s", "must be positive and finite");
  require(positive(o.bounded_sigma_m), "bounded_sigma_m", "must be positive and finite");
  require(positive(o.bounded_omega_rad_s), "bounded_omega_rad_s", "must be positive and finite");
  require(positive(o.bounded_damping), "bounded_damping", "must be positive and finite");
  require(positive(o.cv_accel_sigma), "cv_accel_sigma", "must be positive and finite");
  require(positive(o.initial_speed_sigma_mps), "initial_speed_sigma_mps", "must be positive and finite");
  require(positive(o.max_step_s), "max_step_s", "must be positive and finite");
  double sum = 0.0;
  for (double p : o.initial_probabilities) {
    require(std::isfinite(p) && p >= 0.0, "initial_probabilities", "must be finite and not negative");
    sum += p;
  }
  require(sum > 0.0, "initial_probabilities", "must not all be 0");
  require(o.restart_probability > 0.0 && o.restart_probability < 1.0, "restart_probability", "must be in (0, 1)");
  require(o.validation_probability > 0.0 && o.validation_probability < 1.0, "validation_probability",
          "must be in (0, 1)");
  require(o.validation_sightings >= 1 && o.validation_sightings <= kMaxValidationSightings, "validation_sightings",
          "must be in 1..64");
  require(std::isfinite(o.noise_memory_sightings) && o.noise_memory_sightings >= 1.0, "noise_memory_sightings",
          "must be at least 1 and finite");
  require(std::isfinite(o.max_noise_scale) && o.max_noise_scale >= 1.0, "max_noise_scale",
          "must be at least 1 and finite");
  restart_d2_ = chi2_quantile(o.restart_probability, 2);
  valid_d2_ = chi2_quantile(o.validation_probability, 2 * o.validation_sightings);
  // Stationary variance of a damped spring's offset under white acceleration of
  // spectral density q: q / (4 zeta w^3).
  const double w = o.bounded_omega_rad_s;
  bounded_q_ = 4.0 * o.bounded_damping * w * w * w * o.bounded_sigma_m * o.bounded_sigma_m;
}

void MoverTrack::start(const Vec2& p, const Mat2& P, const Vec2& anchor, double t) {
  TrackVector x = TrackVector::Zero();
  x.head<2>() = p;
  TrackMatrix C = TrackMatrix::Zero();
  C.topLeftCorner<2, 2>() = P;
  const double s2 = options_.initial_speed_sigma_mps * options_.initial_speed_sigma_mps;
  C(2, 2) = C(3, 3) = s2;
  double sum = 0.0;
  for (double q : options_.initial_probabilities) sum += q;
  for (int j = 0; j < kMotionModels; ++j) {
    x_[j] = x;
    P_[j] = C;
    mu_[j] = options_.initial_probabilities[j] / sum;
  }
  anchor_ = anchor;
  t_ = t;
  active_ = true;
  window_count_ = window_next_ = 0;
  sightings_ = 0;
  pending_ = false;
  mean_nis_ = 2.0;
  noise_scale_ = 1.0;
}

void MoverTrack::start(const TrackSighting& s, const Vec2& anchor, double t) {
  Mat2 P;
  const Vec2 p = position_of(s, &P);
  start(p, P, anchor, t);
  sightings_ = 1;
}

void MoverTrack::transition(MotionModel m, double dt, TrackMatrix* F, TrackVector* c, TrackMatrix* Q) const {
  const double dt2 = dt * dt;
  c->setZero();
  switch (m) {
    case MotionModel::kStatic: {
      const double walk = options_.static_walk_m_per_sqrt_s;
      *F = per_axis(1.0, 0.0, 0.0, 0.0);
      // The velocity is held at zero; a small variance keeps the covariance regular.
      constexpr double kRestSpeedVar = 1e-6;  // [m^2/s^2]: (1 mm/s)^2
      *Q = per_axis(walk * walk * dt, 0.0, 0.0, kRestSpeedVar);
      return;
    }
    case MotionModel::kBounded: {
      // A = [[0, 1], [-w^2, -2 zeta w]] per axis, about the equilibrium (anchor, 0);
      // F = I + A dt + A^2 dt^2 / 2 (error O((w dt)^3), dt <= max_step_s).
      const double w = options_.bounded_omega_rad_s, z = options_.bounded_damping;
      const double a21 = -w * w, a22 = -2.0 * z * w;
      // A^2 = [[a21, a22], [a22 a21, a21 + a22^2]]
      *F = per_axis(1.0 + a21 * dt2 / 2, dt + a22 * dt2 / 2, a21 * dt + a22 * a21 * dt2 / 2,
                    1.0 + a22 * dt + (a21 + a22 * a22) * dt2 / 2);
      // Q = q int_0^dt phi(s) phi(s)' ds, phi(s) = Phi(s) (0, 1)' the response to an
      // impulse of acceleration, Phi(s) the same expansion; by 3-point Gauss-Legendre
      // (exact for the polynomial of degree 4 this is).
      const double nodes[3] = {0.5 * dt * (1.0 - std::sqrt(0.6)), 0.5 * dt, 0.5 * dt * (1.0 + std::sqrt(0.6))};
      const double weights[3] = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};
      double qpp = 0.0, qpv = 0.0, qvv = 0.0;
      for (int i = 0; i < 3; ++i) {
        const double u = nodes[i];
        const double phi_p = u + a22 * u * u / 2, phi_v = 1.0 + a22 * u + (a21 + a22 * a22) * u * u / 2;
        qpp += weights[i] * phi_p * phi_p;
        qpv += weights[i] * phi_p * phi_v;
        qvv += weights[i] * phi_v * phi_v;
      }
      const double q = bounded_q_ * dt;
      *Q = per_axis(q * qpp, q * qpv, q * qpv, q * qvv);
      TrackVector eq = TrackVector::Zero();
      eq.head<2>() = anchor_;
      *c = (TrackMatrix::Identity() - *F) * eq;
      return;
    }
    case MotionModel::kConstantVelocity: {
      constant_velocity_step(dt, options_.cv_accel_sigma, F, Q);
      return;
    }
  }
}

Eigen::Matrix3d MoverTrack::switching(double dt) const {
  const double stay = std::exp(-dt / options_.model_sojourn_s);
  const double leave = (1.0 - stay) / (kMotionModels - 1);
  Eigen::Matrix3d pi = Eigen::Matrix3d::Constant(leave);
  pi.diagonal().setConstant(stay);
  return pi;
}

void MoverTrack::predict_model(int j, double dt) {
  // F and Q depend on the step alone (frames come at a steady rate): computed once
  // per step length; the bounded model's c = (I - F) (anchor, 0) follows the anchor.
  if (dt != step_cached_) {
    TrackVector c;
    for (int m = 0; m < kMotionModels; ++m) transition(static_cast<MotionModel>(m), dt, &F_step_[m], &c, &Q_step_[m]);
    step_cached_ = dt;
  }
  // Every model moves each axis alike: F = [[a I, b I], [c I, d I]] on (p, v), so
  // F x and F P F' take 2 x 2 blocks (a third of the general 4 x 4 products).
  const TrackMatrix& F = F_step_[j];
  const double a = F(0, 0), b = F(0, 2), c = F(2, 0), d = F(2, 2);
  TrackVector& x = x_[j];
  const Vec2 p = x.head<2>(), v = x.tail<2>();
  x.head<2>() = a * p + b * v;
  x.tail<2>() = c * p + d * v;
  // The spring pulls towards (anchor, 0): x' = F x + (I - F) (anchor, 0).
  if (static_cast<MotionModel>(j) == MotionModel::kBounded) {
    x.head<2>() += (1.0 - a) * anchor_;
    x.tail<2>() -= c * anchor_;
  }
  TrackMatrix& P = P_[j];
  const Mat2 A = P.topLeftCorner<2, 2>(), B = P.topRightCorner<2, 2>(), C = P.bottomRightCorner<2, 2>();
  const Mat2 Bs = B + B.transpose();
  const Mat2 App = a * a * A + a * b * Bs + b * b * C;
  const Mat2 Bpv = a * c * A + a * d * B + b * c * B.transpose() + b * d * C;
  const Mat2 Cvv = c * c * A + c * d * Bs + d * d * C;
  P.topLeftCorner<2, 2>() = 0.5 * (App + App.transpose());
  P.topRightCorner<2, 2>() = Bpv;
  P.bottomLeftCorner<2, 2>() = Bpv.transpose();
  P.bottomRightCorner<2, 2>() = 0.5 * (Cvv + Cvv.transpose());
  P += Q_step_[j];
}

void MoverTrack::predict(double t) {
  if (!active_ || !(t > t_)) return;
  const double dt = t - t_;
  // Mixing (IMM step 1): c_j = sum_i pi_ij mu_i; each model starts from the
  // moment-matched mixture of all models, weighted by mu_{i|j} = pi_ij mu_i / c_j.
  // The switching matrix depends on the interval alone (frames come at a steady
  // rate): computed once per interval length.
  if (dt != switching_cached_) {
    switching_step_ = switching(dt);
    switching_cached_ = dt;
  }
  const Eigen::Matrix3d& pi = switching_step_;
  std::array<double, kMotionModels> c{};
  for (int j = 0; j < kMotionModels; ++j) {
    for (int i = 0; i < kMotionModels; ++i) c[j] += pi(i, j) * mu_[i];
  }
  std::array<TrackVector, kMotionModels> x0{};
  std::array<TrackMatrix, kMotionModels> P0{};
  for (int j = 0; j < kMotionModels; ++j) {
    x0[j].setZero();
    for (int i = 0; i < kMotionModels; ++i) x0[j] += (pi(i, j) * mu_[i] / c[j]) * x_[i];
    P0[j].setZero();
    for (int i = 0; i < kMotionModels; ++i) {
      const TrackVector d = x_[i] - x0[j];
      P0[j] += (pi(i, j) * mu_[i] / c[j]) * (P_[i] + d * d.transpose());
    }
  }
  x_ = x0;
  P_ = P0;
  mu_ = c;
  // Prediction (IMM step 2), in equal steps no longer than max_step_s.
  const int steps = std::max(1, static_cast<int>(std::ceil(dt / options_.max_step_s - 1e-9)));
  const double h = dt / steps;
  for (int j = 0; j < kMotionModels; ++j) {
    for (int k = 0; k < steps; ++k) predict_model(j, h);
  }
  t_ = t;
}

TrackUpdate MoverTrack::update(const TrackSighting& s) {
  TrackUpdate out;
  if (!active_) return out;
  std::array<Vec2, kMotionModels> nu{};
  std::array<Mat2, kMotionModels> S{}, S_inv{}, R_total{}, S_raw{};
  std::array<Mat2, kMotionModels> H_l{};
  std::array<Mat42, kMotionModels> PHt{};
  std::array<double, kMotionModels> loglik{};
  double min_d2 = std::numeric_limits<double>::infinity();
  for (int j = 0; j < kMotionModels; ++j) {
    Eigen::Matrix<double, 2, 3> H_x;
    const RangeBearing h = observe(s.pose, x_[j].head<2>(), &H_x, &H_l[j]);
    nu[j] << s.z.range - h.range, wrap_angle(s.z.bearing - h.bearing);
    // The pose is considered, not estimated: its covariance widens the sighting's.
    const Mat2 R_stated = s.R + H_x * s.pose_cov * H_x.transpose();
    R_total[j] = noise_scale_ * R_stated;
    PHt[j] = P_[j].leftCols<2>() * H_l[j].transpose();
    const Mat2 HPHt = H_l[j] * PHt[j].topRows<2>();
    S[j] = HPHt + R_total[j];
    S_raw[j] = HPHt + R_stated;
    S_inv[j] = S[j].inverse();
    const double d2 = nu[j].dot(S_inv[j] * nu[j]);
    min_d2 = std::min(min_d2, d2);
    loglik[j] = -0.5 * d2 - 0.5 * std::log(S[j].determinant());
  }
  // The combined innovation under the predicted probabilities (its moments).
  Vec2 nu_bar = Vec2::Zero();
  for (int j = 0; j < kMotionModels; ++j) nu_bar += mu_[j] * nu[j];
  Mat2 S_bar = Mat2::Zero();
  for (int j = 0; j < kMotionModels; ++j) {
    const Vec2 d = nu[j] - nu_bar;
    S_bar += mu_[j] * (S[j] + d * d.transpose());
  }
  out.d2 = nu_bar.dot(S_bar.inverse() * nu_bar);
  if (!(min_d2 <= restart_d2_)) return unexplained(s, out);
  pending_ = false;
  if (options_.adapt_noise) {
    // Covariance matching: the unscaled combined innovation's d2 averages 2 on a
    // track whose stated noise is right.
    Mat2 S_bar_raw = Mat2::Zero();
    for (int j = 0; j < kMotionModels; ++j) {
      const Vec2 d = nu[j] - nu_bar;
      S_bar_raw += mu_[j] * (S_raw[j] + d * d.transpose());
    }
    const double a = 1.0 / options_.noise_memory_sightings;
    mean_nis_ = (1.0 - a) * mean_nis_ + a * nu_bar.dot(S_bar_raw.inverse() * nu_bar);
    noise_scale_ = std::clamp(mean_nis_ / 2.0, 1.0, options_.max_noise_scale);
  }
  for (int j = 0; j < kMotionModels; ++j) {
    const Mat42 K = PHt[j] * S_inv[j];
    x_[j] += K * nu[j];
    P_[j] -= K * PHt[j].transpose();
    P_[j] = 0.5 * (P_[j] + P_[j].transpose()).eval();
  }
  // Model probabilities (IMM step 3), in the log domain against underflow; a floor
  // keeps every model able to come back through the switching matrix.
  const double top = *std::max_element(loglik.begin(), loglik.end());
  double sum = 0.0;
  for (int j = 0; j < kMotionModels; ++j) {
    mu_[j] *= std::exp(loglik[j] - top);
    sum += mu_[j];
  }
  constexpr double kFloor = 1e-9;
  double floored = 0.0;
  for (int j = 0; j < kMotionModels; ++j) {
    mu_[j] = std::max(mu_[j] / sum, kFloor);
    floored += mu_[j];
  }
  for (double& m : mu_) m /= floored;
  // An object at rest anchors its next excursion where it rests.
  constexpr double kRestProbability = 0.9;
  if (mu_[0] > kRestProbability) anchor_ = x_[0].head<2>();
  window_[static_cast<std::size_t>(window_next_)] = out.d2;
  window_next_ = (window_next_ + 1) % options_.validation_sightings;
  window_count_ = std::min(window_count_ + 1, options_.validation_sightings);
  ++sightings_;
  return out;
}

// A sighting no model explains is a jump, a misread or a wrong association, not a
// motion. One alone is held back (the track unchanged); a second in a row that
// agrees with it, within the reach of a mover at initial_speed_sigma_mps over the
// time between them, restarts the track from the first and corrects it with the
// second.
TrackUpdate MoverTrack::unexplained(const TrackSighting& s, TrackUpdate out) {
  Mat2 P;
  const Vec2 p = position_of(s, &P);
  if (pending_) {
    const double reach = options_.initial_speed_sigma_mps * (t_ - pending_t_);
    const Mat2 C = pending_P_ + P + reach * reach * Mat2::Identity();
    const Vec2 d = p - pending_p_;
    if (d.dot(C.inverse() * d) <= restart_d2_) {
      const double now = t_;
      start(pending_p_, pending_P_, pending_p_, pending_t_);
      sightings_ = 1;
      ++restarts_;
      predict(now);
      const TrackUpdate second = update(s);
      out.restarted = true;
      out.d2 = second.d2;
      return out;
    }
  }
  pending_ = true;
  pending_p_ = p;
  pending_P_ = P;
  pending_t_ = t_;
  ++outliers_;
  out.outlier = true;
  return out;
}

TrackVector MoverTrack::mean() const {
  TrackVector m = TrackVector::Zero();
  for (int j = 0; j < kMotionModels; ++j) m += mu_[j] * x_[j];
  return m;
}

TrackMatrix MoverTrack::covariance() const {
  const TrackVector m = mean();
  TrackMatrix C = TrackMatrix::Zero();
  for (int j = 0; j < kMotionModels; ++j) {
    const TrackVector d = x_[j] - m;
    C += mu_[j] * (P_[j] + d * d.transpose());
  }
  return C;
}

MotionModel MoverTrack::likeliest() const {
  return static_cast<MotionModel>(std::max_element(mu_.begin(), mu_.end()) - mu_.begin());
}

bool MoverTrack::validated() const {
  if (!active_ || window_count_ < options_.validation_sightings) return false;
  double sum = 0.0;
  for (int k = 0; k < window_count_; ++k) sum += window_[static_cast<std::size_t>(k)];
  return sum <= valid_d2_;
}

}  // namespace elaslam

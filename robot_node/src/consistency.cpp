// SPDX-License-Identifier: Apache-2.0
#include "elaslam/robot_node/consistency.hpp"

#include <cmath>

namespace elaslam {
namespace {

// Standard normal quantile (Acklam's rational approximation, relative error < 1.2e-9).
double normal_quantile(double p) {
  static const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02, -2.759285104469687e+02,
                             1.383577518672690e+02, -3.066479806614716e+01, 2.506628277459239e+00};
  static const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                             6.680131188771972e+01, -1.328068155288572e+01};
  static const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                             -2.549732539343734e+00, 4.374664141464968e+00, 2.938163982698783e+00};
  static const double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                             3.754408661907416e+00};
  const double lo = 0.02425, hi = 1.0 - lo;
  if (p < lo) {
    const double q = std::sqrt(-2.0 * std::log(p));
    return (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
           ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
  }
  if (p > hi) {
    const double q = std::sqrt(-2.0 * std::log(1.0 - p));
    return -(((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
           ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
  }
  const double q = p - 0.5, r = q * q;
  return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
         (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
}

}  // namespace

ConsistencyMonitor::ConsistencyMonitor(int window_frames, double probability, int min_dof)
    : ring_(static_cast<std::size_t>(window_frames > 0 ? window_frames : 0)),
      z_(normal_quantile(probability)),
      min_dof_(min_dof) {}

double ConsistencyMonitor::threshold(int dof) const {
  const double k = dof, h = 2.0 / (9.0 * k);
  const double t = 1.0 - h + z_ * std::sqrt(h);
  return k * t * t * t;
}

bool ConsistencyMonitor::end_frame() {
  const double nis = frame_nis_;
  const int dof = frame_dof_;
  frame_nis_ = 0.0;
  frame_dof_ = 0;
  last_nis_ = nis;
  last_dof_ = dof;
  if (ring_.empty()) return inconsistent_ = false;
  Entry& e = ring_[next_];
  if (filled_ == ring_.size()) {
    nis_ -= e.nis;
    dof_ -= e.dof;
  } else {
    ++filled_;
  }
  e = {nis, dof};
  nis_ += nis;
  dof_ += dof;
  next_ = (next_ + 1) % ring_.size();
  if (dof_ <= 0) nis_ = 0.0;  // no rounding residue in an empty window
  // A verdict needs a full window and enough corrections in it.
  inconsistent_ = filled_ == ring_.size() && dof_ >= min_dof_ && nis_ > threshold(dof_);
  return inconsistent_;
}

std::vector<std::pair<double, int>> ConsistencyMonitor::window() const {
  std::vector<std::pair<double, int>> out;
  if (ring_.empty()) return out;
  const std::size_t first = filled_ == ring_.size() ? next_ : 0;
  for (std::size_t k = 0; k < filled_; ++k) {
    const Entry& e = ring_[(first + k) % ring_.size()];
    out.emplace_back(e.nis, e.dof);
  }
  return out;
}

void ConsistencyMonitor::restore(const std::vector<std::pair<double, int>>& frames) {
  restart();
  for (const auto& [nis, dof] : frames) {
    frame_nis_ = nis;
    frame_dof_ = dof;
    end_frame();
  }
}

void ConsistencyMonitor::restart() {
  for (Entry& e : ring_) e = {};
  next_ = filled_ = 0;
  nis_ = 0.0;
  dof_ = 0;
  frame_nis_ = 0.0;
  frame_dof_ = 0;
  last_nis_ = 0.0;
  last_dof_ = 0;
  inconsistent_ = false;
}

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
#include "elaslam/eval/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "elaslam/common/quantile.hpp"

namespace elaslam {

void MetricsAccumulator::add(const FrameData& f) {
  if (robot_ids_.empty()) {
    robot_ids_ = f.robot_ids;
    const std::size_t n = robot_ids_.size();
    err_sum_.assign(n, 0.0);
    err_sq_sum_.assign(n, 0.0);
    last_unc_.assign(n, 0.0);
    err_n_.assign(n, 0);
  }
  FrameMetrics m;
  m.frame = f.frame;
  m.time_s = f.time_s;
  // Eq 17 over the global map at this frame.
  double sum = 0.0, sq = 0.0, ssum = 0.0;
  int n = 0, ns = 0;
  for (const auto& [id, p] : f.map_landmarks) {
    if (id < 0 || id >= static_cast<int>(f.true_landmarks.size())) continue;
    const double e = (p - f.true_landmarks[static_cast<std::size_t>(id)]).norm();
    sum += e;
    sq += e * e;
    ++n;
    if (!f.truly_moving[static_cast<std::size_t>(id)]) ssum += e, ++ns;
  }
  m.map_landmarks = n;
  m.map_moving = static_cast<int>(f.map_moving.size());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  m.landmark_error = n ? sum / n : nan;
  m.landmark_rms = n ? std::sqrt(sq / n) : nan;
  m.landmark_static_error = ns ? ssum / ns : nan;
  // Robots.
  for (std::size_t r = 0; r < robot_ids_.size() && r < f.est_poses.size(); ++r) {
    if (!f.has_pose[r]) {
      m.robot_error.push_back(nan);
      m.robot_uncertainty.push_back(nan);
      continue;
    }
    const double e = std::hypot(f.est_poses[r].x - f.true_poses[r].x, f.est_poses[r].y - f.true_poses[r].y);
    err_sum_[r] += e;
    err_sq_sum_[r] += e * e;
    ++err_n_[r];
    last_unc_[r] = f.mean_diag_p[r];
    m.robot_error.push_back(e);
    m.robot_uncertainty.push_back(f.mean_diag_p[r]);
    if (r < f.processing_us.size()) processing_.push_back(f.processing_us[r]);
  }
  // Detection bookkeeping.
  if (ever_moving_.size() < f.truly_moving.size()) ever_moving_.resize(f.truly_moving.size(), 0);
  for (std::size_t i = 0; i < f.truly_moving.size(); ++i) ever_moving_[i] |= f.truly_moving[i];
  for (int id : f.observed) first_observed_.emplace(id, f.frame);
  for (int id : f.map_moving) first_flagged_.emplace(id, f.frame);
  frames_.push_back(std::move(m));
}

RunMetrics MetricsAccumulator::finish() const {
  RunMetrics out;
  out.frames = static_cast<int>(frames_.size());
  double s = 0.0, r = 0.0, st = 0.0;
  int n = 0, nst = 0;
  for (const auto& m : frames_) {
    if (m.map_landmarks == 0) continue;
    s += m.landmark_error;
    r += m.landmark_rms;
    ++n;
    if (!std::isnan(m.landmark_static_error)) st += m.landmark_static_error, ++nst;
  }
  out.landmark_error_mean = n ? s / n : 0.0;
  out.landmark_error_rms = n ? r / n : 0.0;
  out.landmark_error_static = nst ? st / nst : 0.0;
  for (std::size_t i = 0; i < robot_ids_.size(); ++i) {
    RobotMetrics rm;
    rm.id = robot_ids_[i];
    rm.frames = err_n_[i];
    rm.error_mean = err_n_[i] ? err_sum_[i] / err_n_[i] : 0.0;
    rm.error_rms = err_n_[i] ? std::sqrt(err_sq_sum_[i] / err_n_[i]) : 0.0;
    rm.final_uncertainty = last_unc_[i];
    out.robots.push_back(rm);
  }
  // Detection.
  double frames_to_detect = 0.0;
  for (const auto& [id, frame] : first_flagged_) {
    ++out.flagged;
    const bool moving = id >= 0 && id < static_cast<int>(ever_moving_.size()) && ever_moving_[static_cast<std::size_t>(id)];
    if (!moving) continue;
    ++out.true_positives;
    const auto seen = first_observed_.find(id);
    frames_to_detect += frame - (seen != first_observed_.end() ? seen->second : 0);
  }
  for (const auto& [id, frame] : first_observed_)
    if (id >= 0 && id < static_cast<int>(ever_moving_.size()) && ever_moving_[static_cast<std::size_t>(id)])
      ++out.detectable;
  out.precision = out.flagged ? static_cast<double>(out.true_positives) / out.flagged : 1.0;
  out.recall = out.detectable ? static_cast<double>(out.true_positives) / out.detectable : 1.0;
  out.mean_frames_to_detect = out.true_positives ? frames_to_detect / out.true_positives : 0.0;
  if (!processing_.empty()) {
    out.frame_us_p50 = quantile(processing_, 0.5);
    out.frame_us_p99 = quantile(processing_, 0.99);
    out.frame_us_max = *std::max_element(processing_.begin(), processing_.end());
  }
  return out;
}

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
#include "elaslam/eval/track_score.hpp"

#include <cmath>

#include <Eigen/LU>

#include "elaslam/common/stats.hpp"

namespace elaslam {
namespace {

/// Does `v` mark landmark `id`?
bool known(const std::vector<std::uint8_t>& v, int id) {
  return id >= 0 && id < static_cast<int>(v.size()) && v[static_cast<std::size_t>(id)] != 0;
}

}  // namespace

TrackScorer::TrueMotion TrackScorer::true_motion(double dt, const std::vector<Eigen::Vector2d>& truth,
                                                 const std::vector<std::uint8_t>& present) const {
  const std::size_t n = truth.size();
  TrueMotion m{std::vector<std::uint8_t>(n, 0), std::vector<Eigen::Vector2d>(n, Eigen::Vector2d::Zero()),
               std::vector<std::uint8_t>(n, 0)};
  if (!(dt > 0.0)) return m;
  for (std::size_t i = 0; i < n && i < last_truth_.size(); ++i) {
    if (!known(present, static_cast<int>(i)) || !known(last_present_, static_cast<int>(i))) continue;
    m.velocity[i] = (truth[i] - last_truth_[i]) / dt;
    m.has_velocity[i] = 1;
    m.moving[i] = m.velocity[i].norm() > TrackMetrics::kMovingSpeedMps ? 1 : 0;
  }
  return m;
}

void TrackScorer::score_velocity(const TrackSample& s, const Eigen::Vector2d& position_error, const Eigen::Vector2d& v,
                                 bool moving) {
  static const double kNeesLow = chi2_quantile(0.025, 4), kNeesHigh = chi2_quantile(0.975, 4);
  const Eigen::Vector2d v_est = s.x.tail<2>();
  if (moving) {
    ++n_moving_;
    const double ds = v_est.norm() - v.norm();
    speed2_ += ds * ds;
    const double angle = std::atan2(v.x() * v_est.y() - v.y() * v_est.x(), v.dot(v_est));
    heading2_ += angle * angle;
  } else {
    ++at_rest_;
  }
  if (s.stopped) {
    ++found_stopped_;
    if (!moving) ++found_and_at_rest_;
  }
  Eigen::Vector4d e;
  e << position_error, v_est - v;
  const Eigen::FullPivLU<Eigen::Matrix4d> lu(s.P);
  if (lu.isInvertible()) {
    const double nees = e.dot(lu.solve(e));
    nees_ += nees;
    ++n_nees_;
    if (nees >= kNeesLow && nees <= kNeesHigh) ++nees_in_;
  }
}

void TrackScorer::follow_stop(const std::pair<int, int>& key, const TrackSample& s, double time_s, bool was_moving,
                              bool moving, std::map<std::pair<int, int>, Open>* still_open) {
  auto open = open_stops_.find(key);
  if (open == open_stops_.end() && was_moving && !moving) {
    ++stops_;
    open = open_stops_.emplace(key, Open{time_s}).first;
  }
  if (open == open_stops_.end()) return;
  if (s.stopped) {
    ++stops_found_;
    latency_sum_ += time_s - open->second.since_s;
  } else if (!moving) {
    still_open->emplace(key, open->second);
  }
}

void TrackScorer::add(double time_s, const std::vector<Eigen::Vector2d>& truth, const std::vector<std::uint8_t>& present,
                      const std::vector<TrackSample>& tracks) {
  const double dt = have_last_ ? time_s - last_time_s_ : 0.0;
  if (was_moving_.size() < truth.size()) was_moving_.resize(truth.size(), 0);
  const TrueMotion motion = true_motion(dt, truth, present);
  std::map<std::pair<int, int>, Open> still_open;
  std::map<std::pair<int, int>, std::int64_t> sightings_now;
  for (const TrackSample& s : tracks) {
    if (s.sightings < min_sightings_ || !known(present, s.landmark_id) ||
        s.landmark_id >= static_cast<int>(truth.size()))
      continue;
    const auto i = static_cast<std::size_t>(s.landmark_id);
    const std::pair<int, int> key(s.robot, s.landmark_id);
    // Continuity: the same track as at the last frame, or a new segment.
    const auto last = last_sightings_.find(key);
    if (last != last_sightings_.end() && s.sightings >= last->second) {
      segment_time_s_ += dt;
    } else {
      ++segments_;
    }
    sightings_now[key] = s.sightings;
    ++n_;
    const Eigen::Vector2d position_error = s.x.head<2>() - truth[i];
    pos2_ += position_error.squaredNorm();
    if (!motion.has_velocity[i]) continue;
    score_velocity(s, position_error, motion.velocity[i], motion.moving[i] != 0);
    follow_stop(key, s, time_s, was_moving_[i] != 0, motion.moving[i] != 0, &still_open);
  }
  open_stops_ = std::move(still_open);
  last_sightings_ = std::move(sightings_now);
  for (std::size_t i = 0; i < truth.size(); ++i)
    if (motion.has_velocity[i]) was_moving_[i] = motion.moving[i];
  last_truth_ = truth;
  last_present_ = present;
  last_time_s_ = time_s;
  have_last_ = true;
}

TrackMetrics TrackScorer::finish() const {
  TrackMetrics m;
  m.samples = n_;
  m.moving_samples = n_moving_;
  if (n_ > 0) m.position_rms_m = std::sqrt(pos2_ / static_cast<double>(n_));
  if (n_moving_ > 0) {
    m.speed_rms_mps = std::sqrt(speed2_ / static_cast<double>(n_moving_));
    m.heading_rms_deg = std::sqrt(heading2_ / static_cast<double>(n_moving_)) * 180.0 / 3.14159265358979323846;
  }
  m.stopped_verdicts = found_stopped_;
  m.at_rest_samples = at_rest_;
  m.nees_samples = n_nees_;
  if (found_stopped_ > 0) m.stop_precision = static_cast<double>(found_and_at_rest_) / static_cast<double>(found_stopped_);
  if (at_rest_ > 0) m.stop_recall = static_cast<double>(found_and_at_rest_) / static_cast<double>(at_rest_);
  m.stops = stops_;
  m.stops_found = stops_found_;
  if (stops_found_ > 0) m.stop_latency_s = latency_sum_ / static_cast<double>(stops_found_);
  m.segments = segments_;
  if (segments_ > 0) m.mean_segment_s = segment_time_s_ / static_cast<double>(segments_);
  if (n_nees_ > 0) {
    m.nees_mean = nees_ / static_cast<double>(n_nees_);
    m.nees_in_band = static_cast<double>(nees_in_) / static_cast<double>(n_nees_);
  }
  return m;
}

}  // namespace elaslam

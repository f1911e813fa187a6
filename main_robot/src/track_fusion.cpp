// SPDX-License-Identifier: Apache-2.0
#include "elaslam/main_robot/track_fusion.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>

#include "elaslam/common/cov.hpp"

namespace elaslam {
namespace {

// The information matrix of a covariance the receivers' checks found positive
// semi-definite: a ridge of 1e-9 (m^2, (m/s)^2; far below any track's variance,
// whose position part is at least limits.cov_floor) keeps a singular one invertible.
Eigen::Matrix4d information(const Eigen::Matrix4d& P) {
  const Eigen::LLT<Eigen::Matrix4d> llt(P + 1e-9 * Eigen::Matrix4d::Identity());
  return llt.solve(Eigen::Matrix4d::Identity());
}

Eigen::Matrix4d inverse_spd(const Eigen::Matrix4d& I) {
  const Eigen::LLT<Eigen::Matrix4d> llt(I);
  return llt.solve(Eigen::Matrix4d::Identity());
}

}  // namespace

int FusedTrack::likeliest() const {
  const auto& p = estimate.probabilities;
  return static_cast<int>(std::max_element(p.begin(), p.end()) - p.begin());
}

double covariance_intersection(const TrackEstimate& a, const TrackEstimate& b, TrackEstimate* fused) {
  const Eigen::Matrix4d Ia = information(a.P), Ib = information(b.P);
  const auto trace_at = [&](double w) { return inverse_spd(w * Ia + (1.0 - w) * Ib).trace(); };
  // Golden-section search on [0, 1]: 60 steps narrow the bracket to 3e-13.
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double lo = 0.0, hi = 1.0, c = hi - g * (hi - lo), d = lo + g * (hi - lo);
  double fc = trace_at(c), fd = trace_at(d);
  for (int k = 0; k < 60; ++k) {
    if (fc < fd) {
      hi = d, d = c, fd = fc;
      c = hi - g * (hi - lo), fc = trace_at(c);
    } else {
      lo = c, c = d, fc = fd;
      d = lo + g * (hi - lo), fd = trace_at(d);
    }
  }
  // The search's weight, unless w = 1/2 or an end (one estimate alone) is as good
  // within 1e-9: where the trace is flat (equal covariances) the two count alike,
  // and an estimate that is better in every direction is taken alone, exactly.
  const double searched = 0.5 * (lo + hi);
  const double candidates[] = {0.5, 1.0, 0.0, searched};
  double traces[4], least = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 4; ++k) least = std::min(least, traces[k] = trace_at(candidates[k]));
  double w = searched;
  for (int k = 0; k < 4; ++k)
    if (traces[k] <= least * (1.0 + 1e-9)) {
      w = candidates[k];
      break;
    }
  fused->id = a.id;
  if (w == 1.0) {
    fused->x = a.x, fused->P = a.P;
  } else if (w == 0.0) {
    fused->x = b.x, fused->P = b.P;
  } else {
    fused->P = inverse_spd(w * Ia + (1.0 - w) * Ib);
    fused->x = fused->P * (w * Ia * a.x + (1.0 - w) * Ib * b.x);
  }
  for (std::size_t i = 0; i < fused->probabilities.size(); ++i)
    fused->probabilities[i] = w * a.probabilities[i] + (1.0 - w) * b.probabilities[i];
  return w;
}

TrackFusion::TrackFusion(int max_age_frames) : max_age_frames_(max_age_frames) {
  const std::size_t most = static_cast<std::size_t>(contract::kMaxRobots) * contract::kMaxTracks;
  order_.reserve(most);
  fused_.reserve(most);
}

void TrackFusion::take(const track_list_t& m) {
  RobotTracks& r = robots_[static_cast<std::size_t>(m.robot_id - 1)];
  r.frame = m.frame;
  r.count = std::min<int>(m.num_tracks, contract::kMaxTracks);
  for (int k = 0; k < r.count; ++k) {
    const track_t& t = m.tracks[static_cast<std::size_t>(k)];
    TrackEstimate& e = r.tracks[static_cast<std::size_t>(k)];
    e.id = t.id;
    e.x << t.x, t.y, t.vx, t.vy;
    e.P = read_cov_upper(t.cov);
    for (std::size_t i = 0; i < e.probabilities.size(); ++i) e.probabilities[i] = t.probabilities[i];
  }
}

void TrackFusion::forget(int robot_id) {
  RobotTracks& r = robots_[static_cast<std::size_t>(robot_id - 1)];
  r.frame = -1;
  r.count = 0;
}

int TrackFusion::robot_frame(int robot_id) const { return robots_[static_cast<std::size_t>(robot_id - 1)].frame; }

const std::vector<FusedTrack>& TrackFusion::fuse(int frame) {
  order_.clear();
  for (int r = 0; r < contract::kMaxRobots; ++r) {
    const RobotTracks& rt = robots_[static_cast<std::size_t>(r)];
    if (rt.frame < 0 || frame - rt.frame > max_age_frames_) continue;
    for (int k = 0; k < rt.count; ++k)
      order_.emplace_back(rt.tracks[static_cast<std::size_t>(k)].id, r * contract::kMaxTracks + k);
  }
  std::sort(order_.begin(), order_.end());  // by landmark, then robot
  fused_.clear();
  for (std::size_t i = 0; i < order_.size();) {
    const int id = order_[i].first;
    FusedTrack f;
    bool first = true;
    for (; i < order_.size() && order_[i].first == id; ++i) {
      const int r = order_[i].second / contract::kMaxTracks, k = order_[i].second % contract::kMaxTracks;
      const TrackEstimate& e = robots_[static_cast<std::size_t>(r)].tracks[static_cast<std::size_t>(k)];
      if (first) {
        f.estimate = e;
        first = false;
      } else {
        TrackEstimate running = f.estimate;
        covariance_intersection(running, e, &f.estimate);
      }
      f.contributors |= 1 << r;
    }
    fused_.push_back(f);
  }
  return fused_;
}

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
#include "elaslam/main_robot/track_fusion.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>

#include "elaslam/common/contract.hpp"
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

TrackEstimate predict_track(const TrackEstimate& e, double dt) {
  TrackEstimate out = e;
  if (!(dt > 0.0)) return out;
  Eigen::Matrix4d F, Q;
  constant_velocity_step(dt, kDefaultCvAccelSigma, &F, &Q);
  out.x = F * e.x;
  out.P = F * e.P * F.transpose() + Q;
  out.P = 0.5 * (out.P + out.P.transpose()).eval();
  return out;
}

TrackFusion::TrackFusion(int max_age_frames) : max_age_frames_(max_age_frames) {
  const std::size_t most = static_cast<std::size_t>(contract::kMaxRobots) * kCapacity;
  order_.reserve(most);
  fused_.reserve(most);
  for (RobotTracks& r : robots_) {
    r.fused.tracks.resize(kCapacity);
    r.arriving.tracks.resize(kCapacity);
  }
}

int TrackFusion::Publication::count() const {
  int n = 0;
  for (int c = 0; c < num_chunks; ++c)
    if ((received >> c) & 1u) n += counts[static_cast<std::size_t>(c)];
  return n;
}

TrackFusion::Take TrackFusion::take(const track_list_t& m, std::string* problem, Refusal* reason) {
  RobotTracks& r = robots_[static_cast<std::size_t>(m.robot_id - 1)];
  Publication& a = r.arriving;
  const auto refuse = [&](Refusal why, std::string text) {
    if (problem) *problem = std::move(text);
    if (reason) *reason = why;
    return Take::kRefused;
  };
  if (m.frame < robot_frame(m.robot_id) || (m.frame == r.fused.frame && a.frame != m.frame)) return Take::kStale;
  if (a.frame == m.frame) {
    if (m.num_chunks != a.num_chunks)
      return refuse(Refusal::kMalformed, contract::got("tracks' num_chunks differs from " + std::to_string(a.num_chunks) +
                                                           " of the publication's other chunks",
                                                       m.num_chunks));
    if ((a.received >> m.chunk) & 1u) return Take::kStale;
  } else {
    // A newer frame: the publication still arriving (if any) is taken as it came.
    if (a.frame >= 0) {
      std::swap(r.fused, a);
      measure_period(&r, a);
    }
    a.frame = m.frame;
    a.utime = m.utime;
    a.num_chunks = m.num_chunks;
    a.received = 0;
  }
  const int n = std::min<int>(m.num_tracks, contract::kMaxTracks);
  for (int k = 0; k < n; ++k) {
    const int id = m.tracks[static_cast<std::size_t>(k)].id;
    for (int c = 0; c < a.num_chunks; ++c) {
      if (!((a.received >> c) & 1u)) continue;
      for (int j = 0; j < a.counts[static_cast<std::size_t>(c)]; ++j)
        if (a.tracks[static_cast<std::size_t>(c * contract::kMaxTracks + j)].id == id)
          return refuse(Refusal::kDuplicateId, contract::got("track landmark id listed in two chunks", id));
    }
  }
  for (int k = 0; k < n; ++k) {
    const track_t& t = m.tracks[static_cast<std::size_t>(k)];
    TrackEstimate& e = a.tracks[static_cast<std::size_t>(m.chunk * contract::kMaxTracks + k)];
    e.id = t.id;
    e.x << t.x, t.y, t.vx, t.vy;
    e.P = read_cov_upper(t.cov);
    for (std::size_t i = 0; i < e.probabilities.size(); ++i) e.probabilities[i] = t.probabilities[i];
  }
  a.counts[static_cast<std::size_t>(m.chunk)] = n;
  a.received |= 1u << m.chunk;
  if (a.complete()) {
    std::swap(r.fused, a);
    measure_period(&r, a);
    a.frame = -1;
    a.num_chunks = 0;
    a.received = 0;
  }
  return Take::kTaken;
}

// The stamps are the robot's frames' (checked finite integers): a period outside
// (0, 10] s is not a frame rate (a replay restarted, a clock stepped) and is not
// taken.
void TrackFusion::measure_period(RobotTracks* r, const Publication& older) {
  const Publication& newer = r->fused;
  if (older.frame < 0 || newer.frame <= older.frame) return;
  const double period = (static_cast<double>(newer.utime) - static_cast<double>(older.utime)) * 1e-6 /
                        (newer.frame - older.frame);
  if (period > 0.0 && period <= 10.0) r->period_s = period;
}

double TrackFusion::robot_period_s(int robot_id) const {
  return robots_[static_cast<std::size_t>(robot_id - 1)].period_s;
}

void TrackFusion::forget(int robot_id) {
  RobotTracks& r = robots_[static_cast<std::size_t>(robot_id - 1)];
  r.period_s = 0.0;
  for (Publication* p : {&r.fused, &r.arriving}) {
    p->frame = -1;
    p->num_chunks = 0;
    p->received = 0;
  }
}

int TrackFusion::robot_frame(int robot_id) const {
  const RobotTracks& r = robots_[static_cast<std::size_t>(robot_id - 1)];
  return std::max(r.fused.frame, r.arriving.frame);
}

int TrackFusion::robot_tracks(int robot_id) const {
  return robots_[static_cast<std::size_t>(robot_id - 1)].fused.count();
}

const std::vector<FusedTrack>& TrackFusion::fuse(int frame) {
  order_.clear();
  for (int r = 0; r < contract::kMaxRobots; ++r) {
    const Publication& p = robots_[static_cast<std::size_t>(r)].fused;
    if (p.frame < 0 || frame - p.frame > max_age_frames_) continue;
    for (int c = 0; c < p.num_chunks; ++c) {
      if (!((p.received >> c) & 1u)) continue;
      for (int k = 0; k < p.counts[static_cast<std::size_t>(c)]; ++k) {
        const int slot = c * contract::kMaxTracks + k;
        order_.emplace_back(p.tracks[static_cast<std::size_t>(slot)].id, r * kCapacity + slot);
      }
    }
  }
  std::sort(order_.begin(), order_.end());  // by landmark, then robot
  fused_.clear();
  for (std::size_t i = 0; i < order_.size();) {
    const int id = order_[i].first;
    FusedTrack f;
    bool first = true;
    for (; i < order_.size() && order_[i].first == id; ++i) {
      const int r = order_[i].second / kCapacity, k = order_[i].second % kCapacity;
      const RobotTracks& rt = robots_[static_cast<std::size_t>(r)];
      // Predicted to the frame fused, by the frames between at the robot's period.
      const TrackEstimate e =
          predict_track(rt.fused.tracks[static_cast<std::size_t>(k)], (frame - rt.fused.frame) * rt.period_s);
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

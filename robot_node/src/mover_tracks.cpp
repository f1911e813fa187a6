// SPDX-License-Identifier: Apache-2.0
#include "elaslam/robot_node/mover_tracks.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace elaslam {

MoverTracks::MoverTracks(const TrackingOptions& options, int max_landmark_id) : options_(options) {
  if (options.max_tracks < 0 || options.max_tracks > 4096) {
    throw std::invalid_argument("robot.tracking.max_tracks must be in 0..4096, got " +
                                std::to_string(options.max_tracks));
  }
  if (!(std::isfinite(options.lost_after_s) && options.lost_after_s > 0.0)) {
    throw std::invalid_argument("robot.tracking.lost_after_s must be positive and finite");
  }
  const MoverTrack prototype(options.track);  // checks the track's options
  const int slots = options.enabled ? options.max_tracks : 0;
  pool_.assign(static_cast<std::size_t>(slots), prototype);
  last_seen_.assign(static_cast<std::size_t>(slots), 0.0);
  free_.reserve(static_cast<std::size_t>(slots));
  for (int k = slots - 1; k >= 0; --k) free_.push_back(k);
  slot_.assign(static_cast<std::size_t>(std::max(max_landmark_id, 0)), -1);
  ids_.reserve(static_cast<std::size_t>(slots));
}

bool MoverTracks::begin(int id, const TrackSighting& s, const Eigen::Vector2d& anchor, double t) {
  if (!options_.enabled || id < 0 || id >= static_cast<int>(slot_.size())) return false;
  int slot = slot_of(id);
  if (slot < 0) {
    if (free_.empty()) {
      ++counters_.full;
      return false;
    }
    slot = free_.back();
    free_.pop_back();
    slot_[static_cast<std::size_t>(id)] = slot;
    ids_.push_back(id);
  }
  pool_[static_cast<std::size_t>(slot)].start(s, anchor, t);
  last_seen_[static_cast<std::size_t>(slot)] = t;
  ++counters_.started;
  return true;
}

bool MoverTracks::see(int id, const TrackSighting& s, double t) {
  const int slot = slot_of(id);
  if (slot < 0) return false;
  MoverTrack& track = pool_[static_cast<std::size_t>(slot)];
  track.predict(t);
  const TrackUpdate u = track.update(s);
  if (u.restarted) ++counters_.restarts;
  if (u.outlier) ++counters_.outliers;
  last_seen_[static_cast<std::size_t>(slot)] = std::max(t, last_seen_[static_cast<std::size_t>(slot)]);
  ++counters_.updates;
  return true;
}

void MoverTracks::predict(int id, double t) {
  const int slot = slot_of(id);
  if (slot >= 0) pool_[static_cast<std::size_t>(slot)].predict(t);
}

void MoverTracks::release(int id) {
  const int slot = slot_of(id);
  pool_[static_cast<std::size_t>(slot)].stop();
  free_.push_back(slot);
  slot_[static_cast<std::size_t>(id)] = -1;
  ids_.erase(std::find(ids_.begin(), ids_.end(), id));
}

void MoverTracks::end(int id, bool returned) {
  if (slot_of(id) < 0) return;
  release(id);
  ++(returned ? counters_.returned : counters_.ended);
}

void MoverTracks::expire(double t) {
  for (std::size_t k = 0; k < ids_.size();) {
    const int id = ids_[k];
    if (t - last_seen_[static_cast<std::size_t>(slot_of(id))] > options_.lost_after_s) {
      release(id);  // erases ids_[k]: the next id moves to k
      ++counters_.lost;
    } else {
      ++k;
    }
  }
}

void MoverTracks::apply(const std::vector<TrackOp>& ops, const TrackSighting& base, double t) {
  if (!options_.enabled) return;
  TrackSighting s = base;
  for (const TrackOp& op : ops) {
    s.z = op.z;
    switch (op.kind) {
      case TrackOp::Kind::kBegin:
        begin(op.id, s, op.anchor, t);
        break;
      case TrackOp::Kind::kSee:
        if (!see(op.id, s, t) && op.may_begin) begin(op.id, s, op.anchor, t);
        break;
      case TrackOp::Kind::kEnd:
        end(op.id, /*returned=*/true);
        break;
    }
  }
  expire(t);
  // Every track's estimate is of the frame's time, seen in this frame or not.
  for (const int id : ids_) pool_[static_cast<std::size_t>(slot_of(id))].predict(t);
}

void MoverTracks::clear() {
  while (!ids_.empty()) end(ids_.back(), false);
}

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
#include "elaslam/main_robot/map_publisher.hpp"

#include <algorithm>

#include "elaslam/common/contract.hpp"
#include "elaslam/common/cov.hpp"

namespace elaslam {
namespace {

// A global map chunk's two kinds of entry (chunks.hpp, prepare_chunks).
void grow_static(global_map_t* m, int n) { contract::set_count(&m->landmarks, &m->num_landmarks, n); }
void grow_moving(global_map_t* m, int n) {
  contract::set_count(&m->moving_ids, &m->num_moving, n);
  m->moving_frames.resize(static_cast<std::size_t>(n));
  m->moving_by.resize(static_cast<std::size_t>(n));
}

}  // namespace

MapPublisher::MapPublisher(int max_landmark_id) {
  const auto max_id = static_cast<std::size_t>(max_landmark_id);
  static_ids_.reserve(max_id);
  moving_ids_.reserve(max_id);
  moving_sent_.reserve(3 * max_id);
  moving_now_.reserve(3 * max_id);
  // All ids counted as the larger kind of entry: a bound for any mix of the two.
  prepare_chunks(grow_static, grow_moving, contract::kMaxChunkBytes, max_landmark_id, 0, &chunk_sizes_, &chunks_);
  spans_.reserve(chunks_.size());
}

// GLOBAL_MAP: the fused map and the moving set. TEAM_MAP_<r>: per STATIC landmark,
// the fusion of the other robots' estimates (those r alone holds are left out), and
// no moving set (GLOBAL_MAP carries it). GLOBAL_MOVING: the moving set alone.
int MapPublisher::make(const GlobalMap& map, Kind kind, std::int64_t now_utime, int frame, std::int64_t incarnation,
                       int robot_id) {
  const bool moving_only = kind == Kind::kMovingSet;
  const int exclude_robot = kind == Kind::kTeamMap ? robot_id : 0;
  static_ids_.clear();
  moving_ids_.clear();
  // A team map's estimates leave out r's and those of the robots check_team left out.
  const int excluded = exclude_robot > 0 ? (1 << (exclude_robot - 1)) | static_cast<int>(map.left_out()) : 0;
  Eigen::Vector2d p;
  Eigen::Matrix2d C;
  for (int id = 0; id < map.max_landmark_id(); ++id) {
    const GlobalEntry& g = map.entry(id);
    // A team map holds only what another robot's usable estimate gives.
    if (g.status == GlobalStatus::kStatic && !moving_only &&
        (exclude_robot == 0 || map.fused_without(id, exclude_robot, &p, &C)))
      static_ids_.push_back(id);
    else if (g.status == GlobalStatus::kMoving && exclude_robot == 0) moving_ids_.push_back(id);
  }
  cut_chunks(static_ids_.data(), static_cast<int>(static_ids_.size()), moving_ids_.data(),
             static_cast<int>(moving_ids_.size()), chunk_sizes_, map.max_landmark_id(), &spans_);
  // Equal: the pool fits the largest map. Were it ever short, the map would go out
  // cut: a capacity fault.
  const int n = static_cast<int>(std::min(spans_.size(), chunks_.size()));
  if (!moving_only) capacity_fault_ = spans_.size() > chunks_.size();  // the moving set alone always fits
  for (int k = 0; k < n; ++k) {
    const ChunkSpan& sp = spans_[static_cast<std::size_t>(k)];
    global_map_t& c = chunks_[static_cast<std::size_t>(k)];
    c.utime = now_utime;
    c.frame = frame;
    c.incarnation = incarnation;
    c.version = map.version();
    c.chunk = static_cast<std::int16_t>(k);
    c.num_chunks = static_cast<std::int16_t>(n);
    c.id_begin = sp.id_begin;
    c.id_end = sp.id_end;
    grow_static(&c, sp.count_a);
    for (int i = 0; i < sp.count_a; ++i) {
      const int id = static_ids_[static_cast<std::size_t>(sp.first_a + i)];
      const GlobalEntry& g = map.entry(id);
      p = g.fused;
      C = g.fused_cov;
      if (exclude_robot > 0) map.fused_without(id, exclude_robot, &p, &C);  // true: it was selected so
      global_landmark_t& l = c.landmarks[static_cast<std::size_t>(i)];
      l.id = id;
      l.x = p.x();
      l.y = p.y();
      write_cov(l.cov, C);
      l.contributors = static_cast<std::int16_t>(g.contributors() & ~excluded);
      l.status = global_landmark_t::STATIC;
      l.status_frame = g.status_frame;
    }
    grow_moving(&c, sp.count_b);
    for (int i = 0; i < sp.count_b; ++i) {
      const auto j = static_cast<std::size_t>(i);
      const int id = moving_ids_[static_cast<std::size_t>(sp.first_b + i)];
      const GlobalEntry& g = map.entry(id);
      c.moving_ids[j] = id;
      c.moving_frames[j] = std::max(g.status_frame, 0);
      c.moving_by[j] = static_cast<std::int16_t>(g.moving_unconfirmed ? 0 : g.moving_by);
    }
  }
  return n;
}

bool MapPublisher::moving_set_due(int num_chunks, std::int64_t now_utime, double repeat_s) {
  moving_now_.clear();
  for (int k = 0; k < num_chunks; ++k) {
    const global_map_t& c = chunks_[static_cast<std::size_t>(k)];
    for (int i = 0; i < c.num_moving; ++i) {
      const auto j = static_cast<std::size_t>(i);
      moving_now_.insert(moving_now_.end(), {c.moving_ids[j], c.moving_frames[j], c.moving_by[j]});
    }
  }
  const auto repeat_us = static_cast<std::int64_t>(repeat_s * 1e6);
  const bool due = !any_moving_sent_ || repeat_us <= 0 || moving_now_ != moving_sent_ ||
                   now_utime - moving_sent_utime_ >= repeat_us || now_utime < moving_sent_utime_;
  if (!due) return false;
  moving_sent_.swap(moving_now_);
  moving_sent_utime_ = now_utime;
  any_moving_sent_ = true;
  return true;
}

}  // namespace elaslam

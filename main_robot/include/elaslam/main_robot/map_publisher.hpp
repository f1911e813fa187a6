// SPDX-License-Identifier: Apache-2.0
// The global map as datagrams: GLOBAL_MAP (the fused map and the moving set),
// GLOBAL_MOVING (the moving set alone: what a robot reads of the map) and TEAM_MAP_<r>
// (per static landmark the fusion of the other robots' estimates), each cut by
// landmark id into chunks that fit one datagram (common/chunks.hpp), in one pool sized
// at construction for the largest map: filling them allocates nothing. It reads the
// GlobalMap and never changes it; whether a moving set is due to go out is decided
// here too (main.moving_repeat_s).
#pragma once

#include <cstdint>
#include <vector>

#include "elaslam/common/chunks.hpp"
#include "elaslam/global_map_t.hpp"
#include "elaslam/main_robot/global_map.hpp"

namespace elaslam {

class MapPublisher {
 public:
  explicit MapPublisher(int max_landmark_id);

  enum class Kind { kGlobalMap, kMovingSet, kTeamMap };
  /// The chunks of `kind` (kTeamMap: robot `robot_id`'s, without its own and the left
  /// out robots' information), stamped with `frame`, `incarnation` and the map's
  /// version. Returns the chunk count; map_chunk(i) holds them until the next call.
  int make(const GlobalMap& map, Kind kind, std::int64_t now_utime, int frame, std::int64_t incarnation,
           int robot_id = 0);
  const global_map_t& map_chunk(int i) const { return chunks_[static_cast<std::size_t>(i)]; }
  /// The last GLOBAL_MAP or team map could not carry the whole map (the pool short:
  /// flagged in STATUS_MAIN, never silent).
  bool capacity_fault() const { return capacity_fault_; }

  /// Is the moving set just made due to go out at `now_utime`? True when its lists
  /// (ids, frames, finders) differ from the last set that was due, when that one is
  /// `repeat_s` old or older, or when `repeat_s` is 0.
  bool moving_set_due(int num_chunks, std::int64_t now_utime, double repeat_s);

 private:
  ChunkSizes chunk_sizes_;
  std::vector<int> static_ids_, moving_ids_;
  std::vector<int> moving_sent_, moving_now_;  // (id, frame, by) of the last due moving set and of the one just made
  std::int64_t moving_sent_utime_ = 0;
  bool any_moving_sent_ = false;
  bool capacity_fault_ = false;
  std::vector<ChunkSpan> spans_;
  std::vector<global_map_t> chunks_;
};

}  // namespace elaslam

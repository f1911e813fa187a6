// SPDX-License-Identifier: Apache-2.0
// Receiving messages with variable-length arrays without allocating: the node shell
// decodes every input into one message allocated at subscription (node_shell.hpp);
// reserve_arrays() gives its arrays room for the largest count the wire format can
// state (int16_t: 32,767), so LCM's decoder (which resizes the std::vector to the
// count) never allocates, also for a forged count, which validation then refuses.
// About 2 MB for a global map input, 3 MB for an events input, 0.7 MB for a sensor
// input, 3.3 MB for a tracks input (TRACKS_<r>, main_robot's).
#pragma once

#include <cstdint>

#include "elaslam/global_map_t.hpp"
#include "elaslam/lmap_events_t.hpp"
#include "elaslam/lmap_snapshot_t.hpp"
#include "elaslam/sensor_frame_t.hpp"
#include "elaslam/track_list_t.hpp"

namespace elaslam::transport {

constexpr std::size_t kMaxCount = INT16_MAX;  // the most an int16_t count field can say

inline void reserve_arrays(sensor_frame_t* m) { m->obs.reserve(kMaxCount); }
inline void reserve_arrays(lmap_snapshot_t* m) {
  m->landmarks.reserve(kMaxCount);
  m->moving_ids.reserve(kMaxCount);
  m->moving_frames.reserve(kMaxCount);
}
inline void reserve_arrays(lmap_events_t* m) { m->events.reserve(kMaxCount); }
inline void reserve_arrays(track_list_t* m) { m->tracks.reserve(kMaxCount); }
inline void reserve_arrays(global_map_t* m) {
  m->landmarks.reserve(kMaxCount);
  m->moving_ids.reserve(kMaxCount);
  m->moving_frames.reserve(kMaxCount);
  m->moving_by.reserve(kMaxCount);
}
/// Messages with fixed-size arrays only: nothing to do.
template <class Msg>
void reserve_arrays(Msg*) {}

}  // namespace elaslam::transport

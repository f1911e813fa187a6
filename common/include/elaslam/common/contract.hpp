// SPDX-License-Identifier: Apache-2.0
// The message contract's capacities (the array sizes of lcmtypes/*.lcm), in one
// place, checked against the generated types at compile time. Every bound on a
// count field and every error message about one is built from these constants.
#pragma once

#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>
#include <type_traits>

#include "elaslam/global_landmark_t.hpp"
#include "elaslam/global_map_t.hpp"
#include "elaslam/ground_truth_t.hpp"
#include "elaslam/lmap_snapshot_t.hpp"
#include "elaslam/run_info_t.hpp"
#include "elaslam/sensor_frame_t.hpp"

namespace elaslam::contract {

/// Observations per frame: a config value on both sides (scenario.sensor.max_observations,
/// robot.filter.max_observations, the second at least the first: checked at start-up),
/// this by default and at most kMaxObsPerFrameLimit (sensor_frame_t.obs is
/// variable-length; the gate's cost per frame grows as its square).
constexpr int kMaxObsPerFrame = 64;
constexpr int kMaxObsPerFrameLimit = 1024;
constexpr int kMaxCount = 32767;     // the most any int16_t count field can say
/// Robot ids 1..kMaxRobots: global_landmark_t.contributors holds one bit per robot in
/// an int16_t. A team's own members are configuration (limits.team); this is the
/// ceiling the messages can express.
constexpr int kMaxRobots = 16;
/// The world's landmarks in one ground_truth_t (its int16_t count).
constexpr int kMaxWorldLandmarks = kMaxCount;
/// The largest max_landmark_id a robot or main_robot accepts (ids 0 .. 2^20 - 1).
constexpr int kMaxLandmarkIdLimit = 1 << 20;

/// The largest message any channel carries, as a transport hands it over: GROUND_TRUTH
/// of kMaxWorldLandmarks landmarks encodes to under 0.7 MB, every other type is far
/// smaller. A size beyond this is not a message: LCM 1.3.1 reports -1 (4294967295)
/// for a datagram whose channel name runs past its end, and the transport refuses it
/// before anything reads the bytes (transport/lcm_transport.hpp, docs/security.md).
constexpr std::size_t kMaxMessageBytes = std::size_t{4} << 20;
/// The longest channel name LCM sends or receives (LCM_MAX_CHANNEL_NAME_LENGTH).
constexpr std::size_t kMaxChannelBytes = 63;

// Messages that repair state fit one datagram (lmap_snapshot_t, global_map_t chunks):
// at most this many bytes encoded (LCM's payload, fingerprint included). With LCM's
// header (8 bytes and the channel name), IP/UDP (28 bytes) and the message
// authentication trailer (54 bytes, docs/security.md) a chunk stays under a
// 1,500-byte MTU for channel names of up to 200 characters, and under the 1,400
// bytes of a typical tunnelled link for names of up to 100.
constexpr int kMaxChunkBytes = 1200;
/// Events per lmap_events_t (LMAP_EVENTS), so that one fits kMaxChunkBytes: its
/// header encodes to 32 bytes (fingerprint included), each landmark_event_t to 83
/// (test_lcmtypes checks both). A frame with more events sends several.
constexpr int kEventBatchHeaderBytes = 32, kEventBytes = 83;
constexpr int kMaxBatchEvents = (kMaxChunkBytes - kEventBatchHeaderBytes) / kEventBytes;
/// Candidates per candidate_list_t (CANDIDATES_<r>); a robot with more counts the rest
/// in num_omitted. Each landmark_estimate_t encodes to 52 bytes, so a full list stays
/// within kMaxChunkBytes, one datagram (test_lcmtypes checks it).
constexpr int kMaxCandidates = 20;
/// Tracks per chunk of track_list_t (TRACKS_<r>) and of global_tracks_t
/// (GLOBAL_TRACKS). The headers encode to 38 and 36 bytes, each track_t to 95 and
/// each global_track_t to 92 (test_lcmtypes checks them), so 12 is the most that fit
/// kMaxChunkBytes, one datagram: 38 + 12 * 95 = 1,178 and 36 + 12 * 92 = 1,140.
constexpr int kTrackListHeaderBytes = 38, kTrackBytes = 95;
constexpr int kGlobalTracksHeaderBytes = 36, kGlobalTrackBytes = 92;
constexpr int kMaxTracks = (kMaxChunkBytes - kTrackListHeaderBytes) / kTrackBytes;
constexpr int kMaxGlobalTracks = (kMaxChunkBytes - kGlobalTracksHeaderBytes) / kGlobalTrackBytes;
static_assert(kMaxTracks == 12 && kMaxGlobalTracks == 12, "the .lcm files' comments say 12");
/// Chunks per publication of TRACKS_<r> and of GLOBAL_TRACKS: enough for a robot's
/// whole default track pool (kDefaultTrackPool, robot.tracking.max_tracks' default),
/// 6 chunks of 12 = 72 tracks. A larger pool or more
/// fused tracks than that are counted in num_omitted; a receiver refuses a chunk
/// that claims more chunks.
constexpr int kDefaultTrackPool = 64;
constexpr int kMaxTrackChunks = (kDefaultTrackPool + kMaxTracks - 1) / kMaxTracks;
static_assert(kMaxTrackChunks == 6 && kMaxTrackChunks * kMaxGlobalTracks >= kDefaultTrackPool);

static_assert(std::is_same_v<decltype(global_landmark_t::contributors), std::int16_t> && kMaxRobots == 16,
              "one contributor bit per robot id");
static_assert(std::is_same_v<decltype(ground_truth_t::num_landmarks), std::int16_t>);

/// Set a variable-length array and its count together (the arrays of sensor_frame_t,
/// lmap_snapshot_t and global_map_t): resize (no allocation within the capacity
/// reserved by transport/message_arrays.hpp) and store the count.
template <class Vec, class Count>
void set_count(Vec* array, Count* count, int n) {
  array->resize(static_cast<std::size_t>(n));
  *count = static_cast<Count>(n);
}

/// True when a decoded or filled message's count field and its array agree (LCM's
/// decoder does not resize an array of primitives for a zero count).
template <class Vec>
bool count_fits(const Vec& array, int count) {
  return count >= 0 && static_cast<std::size_t>(count) <= array.size();
}

/// "<what> (got <value>)": a refusal that names the offending value.
template <class T>
std::string got(const std::string& what, T value) {
  std::ostringstream os;
  os << what << " (got " << value << ")";
  return os.str();
}

/// "<field> outside [<lo>, <hi>]" (e.g. a robot id against [1, kMaxRobots]).
inline std::string outside(const char* field, int lo, int hi) {
  return std::string(field) + " outside [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
}

/// "<field> outside [0, <capacity>]": the refusal of a count field, from the constant.
inline std::string count_outside(const char* field, int capacity) {
  return std::string(field) + " outside [0, " + std::to_string(capacity) + "]";
}

/// min(count, capacity), and never below 0: a loop bound over a message's array for
/// code that reads messages it has not validated (tools reading logs).
inline int bounded(int count, int capacity) { return count < 0 ? 0 : (count > capacity ? capacity : count); }

}  // namespace elaslam::contract

// SPDX-License-Identifier: Apache-2.0
// Every message type round-trips through encode/decode; truncated or corrupted
// buffers fail to decode cleanly (a negative return, no crash, no partial success).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <type_traits>
#include <cstring>
#include <random>
#include <vector>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/candidate_list_t.hpp"
#include "elaslam/global_tracks_t.hpp"
#include "elaslam/track_list_t.hpp"
#include "elaslam/dynamic_notice_t.hpp"
#include "elaslam/global_map_t.hpp"
#include "elaslam/ground_truth_t.hpp"
#include "elaslam/landmark_event_t.hpp"
#include "elaslam/lmap_events_t.hpp"
#include "elaslam/lmap_snapshot_t.hpp"
#include "elaslam/resync_request_t.hpp"
#include "elaslam/node_status_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/sensor_frame_t.hpp"

namespace elaslam {
namespace {

template <typename T>
class LcmTypeTest : public ::testing::Test {};

using AllTypes = ::testing::Types<sensor_frame_t, ground_truth_t, pose_estimate_t, landmark_event_t,
                                  lmap_snapshot_t, global_map_t, dynamic_notice_t, node_status_t, resync_request_t>;
TYPED_TEST_SUITE(LcmTypeTest, AllTypes);

// The shape of a test message: for the types with variable-length arrays, a few
// entries in each (fill) and where their int16 count fields sit in the encoding
// (counts), so that randomising every other byte keeps the message well-formed.
template <typename T>
struct Shape {
  static void fill(T*) {}
  static std::vector<std::size_t> counts(const T&) { return {}; }
};
template <>
struct Shape<sensor_frame_t> {
  static void fill(sensor_frame_t* m) { contract::set_count(&m->obs, &m->num_obs, 5); }
  static std::vector<std::size_t> counts(const sensor_frame_t& m) {
    return {static_cast<std::size_t>(m.getEncodedSize()) - 5 * 20 - 2};
  }
};
// lmap_snapshot_t and global_map_t: header, count a, entries a, count b, entries b.
template <typename T>
struct TwoArrays {
  static void fill(T* m) {
    contract::set_count(&m->landmarks, &m->num_landmarks, 3);
    contract::set_count(&m->moving_ids, &m->num_moving, 2);
    m->moving_frames.resize(2);
    if constexpr (std::is_same_v<T, global_map_t>) m->moving_by.resize(2);
  }
  static std::vector<std::size_t> counts(const T& m) {
    T empty{};
    T a{};
    contract::set_count(&a.landmarks, &a.num_landmarks, 1);
    const auto header = static_cast<std::size_t>(empty.getEncodedSize()) - 4;
    const auto a_bytes = static_cast<std::size_t>(a.getEncodedSize() - empty.getEncodedSize());
    return {header, header + 2 + static_cast<std::size_t>(m.num_landmarks) * a_bytes};
  }
};
template <>
struct Shape<lmap_snapshot_t> : TwoArrays<lmap_snapshot_t> {};
template <>
struct Shape<global_map_t> : TwoArrays<global_map_t> {};

// ground_truth_t: header, robot count, ids and poses, landmark count, landmarks.
template <>
struct Shape<ground_truth_t> {
  static void fill(ground_truth_t* m) {
    contract::set_count(&m->robot_ids, &m->num_robots, 3);
    m->robots.resize(3);
    contract::set_count(&m->landmarks, &m->num_landmarks, 5);
  }
  static std::vector<std::size_t> counts(const ground_truth_t& m) {
    ground_truth_t one{};
    contract::set_count(&one.robot_ids, &one.num_robots, 1);
    one.robots.resize(1);
    const auto header = static_cast<std::size_t>(ground_truth_t{}.getEncodedSize()) - 4;
    const auto robot_bytes = static_cast<std::size_t>(one.getEncodedSize() - ground_truth_t{}.getEncodedSize());
    return {header, header + 2 + static_cast<std::size_t>(m.num_robots) * robot_bytes};
  }
};

// A message with every byte of its payload random but its count fields: any such
// payload decodes, and re-encoding must give the same bytes.
template <typename T>
std::vector<uint8_t> random_encoding(std::mt19937_64& rng) {
  T msg{};
  Shape<T>::fill(&msg);
  std::vector<uint8_t> buf(static_cast<std::size_t>(msg.getEncodedSize()));
  EXPECT_EQ(msg.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  const std::vector<std::size_t> keep = Shape<T>::counts(msg);
  for (std::size_t i = 8; i < buf.size(); ++i) {
    const bool count = std::find(keep.begin(), keep.end(), i) != keep.end() ||
                       std::find(keep.begin(), keep.end(), i - 1) != keep.end();
    if (!count) buf[i] = static_cast<uint8_t>(rng());
  }
  return buf;
}

TYPED_TEST(LcmTypeTest, RoundTripsExactly) {
  std::mt19937_64 rng(42);
  for (int trial = 0; trial < 20; ++trial) {
    const std::vector<uint8_t> buf = random_encoding<TypeParam>(rng);
    TypeParam decoded{};
    ASSERT_EQ(decoded.decode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
    std::vector<uint8_t> again(buf.size());
    ASSERT_EQ(decoded.encode(again.data(), 0, static_cast<int>(again.size())), static_cast<int>(again.size()));
    ASSERT_EQ(again, buf);
  }
}

TYPED_TEST(LcmTypeTest, TruncatedBufferFailsCleanly) {
  std::mt19937_64 rng(7);
  const std::vector<uint8_t> buf = random_encoding<TypeParam>(rng);
  // Every prefix shorter than the message must be refused. Step through all of
  // them for small types and a spread of lengths for the big ones.
  const std::size_t step = buf.size() > 4096 ? 97 : 1;
  for (std::size_t len = 0; len < buf.size(); len += step) {
    TypeParam decoded{};
    ASSERT_LT(decoded.decode(buf.data(), 0, static_cast<int>(len)), 0) << "length " << len;
  }
  TypeParam decoded{};
  ASSERT_LT(decoded.decode(buf.data(), 0, static_cast<int>(buf.size() - 1)), 0);
}

TYPED_TEST(LcmTypeTest, CorruptedFingerprintFailsCleanly) {
  std::mt19937_64 rng(9);
  std::vector<uint8_t> buf = random_encoding<TypeParam>(rng);
  for (int byte = 0; byte < 8; ++byte) {
    std::vector<uint8_t> bad = buf;
    bad[static_cast<std::size_t>(byte)] ^= 0x5a;
    TypeParam decoded{};
    ASSERT_LT(decoded.decode(bad.data(), 0, static_cast<int>(bad.size())), 0) << "byte " << byte;
  }
}

// m encoded into *buf and decoded into *d, both succeeding.
template <typename T>
void round_trip(const T& m, T* d, std::vector<uint8_t>* buf) {
  buf->resize(static_cast<std::size_t>(m.getEncodedSize()));
  ASSERT_GT(m.encode(buf->data(), 0, static_cast<int>(buf->size())), 0);
  ASSERT_GT(d->decode(buf->data(), 0, static_cast<int>(buf->size())), 0);
}

// A Msg whose list (`list`, counted by `count`) is `header` bytes empty and `entry`
// bytes more per entry; `most` entries fit one snapshot-sized datagram and one more
// would not (`why` says so when it would).
template <typename Msg, typename Entry, typename Count>
void expect_chunk_fits(std::vector<Entry> Msg::*list, Count Msg::*count, int header, int entry, int most,
                       const char* why) {
  Msg m{};
  EXPECT_EQ(m.getEncodedSize(), header);
  contract::set_count(&(m.*list), &(m.*count), 1);
  EXPECT_EQ(m.getEncodedSize(), header + entry);
  contract::set_count(&(m.*list), &(m.*count), most);
  EXPECT_LE(m.getEncodedSize(), contract::kMaxChunkBytes);
  contract::set_count(&(m.*list), &(m.*count), most + 1);
  EXPECT_GT(m.getEncodedSize(), contract::kMaxChunkBytes) << why;
}

TEST(LcmTypes, SensorFrameFieldsSurvive) {
  sensor_frame_t m{};
  m.utime = 1700000000123456;
  m.frame = 17;
  m.robot_id = 2;
  m.odom_x = 1.5;
  m.odom_y = -2.25;
  m.odom_theta = 0.125;
  m.odom_var_trans_per_m = 1e-4;
  contract::set_count(&m.obs, &m.num_obs, 2);
  m.obs[0].landmark_id = 5;
  m.obs[0].range = 3.5;
  m.obs[0].bearing = -0.5;
  m.obs[1].landmark_id = 71;
  std::vector<uint8_t> buf;
  sensor_frame_t d{};
  ASSERT_NO_FATAL_FAILURE(round_trip(m, &d, &buf));
  EXPECT_EQ(d.utime, m.utime);
  EXPECT_EQ(d.frame, 17);
  EXPECT_EQ(d.robot_id, 2);
  EXPECT_EQ(d.odom_y, -2.25);
  EXPECT_EQ(d.num_obs, 2);
  EXPECT_EQ(d.obs[0].landmark_id, 5);
  EXPECT_EQ(d.obs[0].bearing, -0.5);
  EXPECT_EQ(d.obs[1].landmark_id, 71);
}

// Sized to content: a frame of 15 observations is a few hundred bytes, the most (64)
// fits one 1,500-byte datagram with LCM's header and IP/UDP's (docs/architecture.md).
TEST(LcmTypes, SensorFramesAreSizedToTheirContent) {
  sensor_frame_t m{};
  const int empty = m.getEncodedSize();
  contract::set_count(&m.obs, &m.num_obs, 15);
  EXPECT_EQ(m.getEncodedSize(), empty + 15 * 20);
  EXPECT_LT(m.getEncodedSize(), 400);
  contract::set_count(&m.obs, &m.num_obs, contract::kMaxObsPerFrame);
  const int wire = m.getEncodedSize() + 8 + static_cast<int>(sizeof("SENSOR_1")) + 28;
  EXPECT_LE(wire, 1500);
}

// CANDIDATES_<r>: 52 bytes per candidate; a full list (contract::kMaxCandidates) fits
// one snapshot-sized datagram.
TEST(LcmTypes, CandidateListsFitOneDatagram) {
  candidate_list_t m{};
  const int empty = m.getEncodedSize();
  contract::set_count(&m.candidates, &m.num_candidates, 1);
  EXPECT_EQ(m.getEncodedSize(), empty + 52);
  contract::set_count(&m.candidates, &m.num_candidates, contract::kMaxCandidates);
  EXPECT_LE(m.getEncodedSize(), contract::kMaxChunkBytes);
}

// TRACKS_<r> and GLOBAL_TRACKS chunks: the header (38 and 36 bytes with the chunk
// fields) and per-track sizes contract::kMaxTracks and kMaxGlobalTracks are worked
// out from; a full chunk fits one snapshot-sized datagram and one more track would
// not; the chunks of one publication hold a robot's whole default track pool; a
// chunk round-trips with its place and a track (the covariance's upper triangle in
// floats).
TEST(LcmTypes, TrackListsFitOneDatagram) {
  expect_chunk_fits(&track_list_t::tracks, &track_list_t::num_tracks, contract::kTrackListHeaderBytes,
                    contract::kTrackBytes, contract::kMaxTracks, "kMaxTracks is the most that fits");
  expect_chunk_fits(&global_tracks_t::tracks, &global_tracks_t::num_tracks, contract::kGlobalTracksHeaderBytes,
                    contract::kGlobalTrackBytes, contract::kMaxGlobalTracks, "kMaxGlobalTracks is the most that fit");
  EXPECT_EQ(contract::kTrackListHeaderBytes, 38);
  EXPECT_EQ(contract::kGlobalTracksHeaderBytes, 36);
  EXPECT_EQ(contract::kMaxTrackChunks, 6);
  EXPECT_GE(contract::kMaxTrackChunks * contract::kMaxTracks, contract::kDefaultTrackPool);
  EXPECT_LT((contract::kMaxTrackChunks - 1) * contract::kMaxTracks, contract::kDefaultTrackPool) << "no chunk more than needed";

  track_list_t m{};
  contract::set_count(&m.tracks, &m.num_tracks, 2);
  m.robot_id = 3;
  m.chunk = 4;
  m.num_chunks = 6;
  m.tracks[1].id = 41;
  m.tracks[1].vy = -0.25;
  m.tracks[1].cov[4] = 0.5f;  // yy
  m.tracks[1].probabilities[2] = 0.75f;
  m.tracks[1].likeliest = track_t::CONSTANT_VELOCITY;
  std::vector<uint8_t> buf;
  track_list_t d{};
  ASSERT_NO_FATAL_FAILURE(round_trip(m, &d, &buf));
  ASSERT_EQ(d.num_tracks, 2);
  EXPECT_EQ(d.robot_id, 3);
  EXPECT_EQ(d.chunk, 4);
  EXPECT_EQ(d.num_chunks, 6);
  EXPECT_EQ(d.tracks[1].id, 41);
  EXPECT_EQ(d.tracks[1].vy, -0.25);
  EXPECT_EQ(d.tracks[1].cov[4], 0.5f);
  EXPECT_EQ(d.tracks[1].probabilities[2], 0.75f);
  EXPECT_EQ(d.tracks[1].likeliest, track_t::CONSTANT_VELOCITY);
}

// LMAP_EVENTS: a 32-byte header (fingerprint included) and 83 bytes per event, the
// figures contract::kMaxBatchEvents is worked out from; a full message fits one
// snapshot-sized datagram and round-trips with its events' fields, and the sender
// binding's robot_id sits at bytes 20..21 as in landmark_event_t (auth_transport.cpp).
TEST(LcmTypes, EventBatchesFitOneDatagram) {
  expect_chunk_fits(&lmap_events_t::events, &lmap_events_t::num_events, contract::kEventBatchHeaderBytes,
                    contract::kEventBytes, contract::kMaxBatchEvents, "kMaxBatchEvents is the most that fits");
  lmap_events_t m{};
  contract::set_count(&m.events, &m.num_events, 2);
  m.robot_id = 0x0203;
  m.frame = 9;
  m.events[1].seq = 12;
  m.events[1].cov[1][0] = 0.25;
  std::vector<uint8_t> buf;
  lmap_events_t d{};
  ASSERT_NO_FATAL_FAILURE(round_trip(m, &d, &buf));
  EXPECT_EQ(buf[20], 0x02);
  EXPECT_EQ(buf[21], 0x03);
  ASSERT_EQ(d.num_events, 2);
  EXPECT_EQ(d.frame, 9);
  EXPECT_EQ(d.events[1].seq, 12);
  EXPECT_EQ(d.events[1].cov[1][0], 0.25);
}

// A negative count is not a message: LCM's decoder throws on it (std::vector::resize);
// the node shell and the log readers catch that and count a decode error.
TEST(LcmTypes, NegativeCountThrowsInDecode) {
  sensor_frame_t m{};
  contract::set_count(&m.obs, &m.num_obs, 1);
  std::vector<uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  ASSERT_GT(m.encode(buf.data(), 0, static_cast<int>(buf.size())), 0);
  const std::size_t count_at = buf.size() - 20 - 2;  // the int16 count before the last observation
  buf[count_at] = 0xff;
  buf[count_at + 1] = 0xff;
  sensor_frame_t d{};
  EXPECT_ANY_THROW(d.decode(buf.data(), 0, static_cast<int>(buf.size())));
}

TEST(LcmTypes, ChannelNames) {
  EXPECT_EQ(channels::sensor(3), "SENSOR_3");
  EXPECT_EQ(channels::pose(1), "POSE_1");
  EXPECT_EQ(channels::status_robot(2, "_B"), "STATUS_ROBOT_2_B");
  EXPECT_EQ(channels::lmap_event(), "LMAP_EVENT");
  EXPECT_EQ(channels::lmap_events("_B"), "LMAP_EVENTS_B");
  EXPECT_EQ(channels::global_map(), "GLOBAL_MAP");
}

}  // namespace
}  // namespace elaslam

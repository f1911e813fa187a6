// Every message type round-trips through encode/decode; truncated or corrupted
// buffers fail to decode cleanly (a negative return, no crash, no partial success).
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/dynamic_notice_t.hpp"
#include "elaslam/global_map_t.hpp"
#include "elaslam/ground_truth_t.hpp"
#include "elaslam/landmark_event_t.hpp"
#include "elaslam/lmap_snapshot_t.hpp"
#include "elaslam/node_status_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/sensor_frame_t.hpp"

namespace elaslam {
namespace {

template <typename T>
class LcmTypeTest : public ::testing::Test {};

using AllTypes = ::testing::Types<sensor_frame_t, ground_truth_t, pose_estimate_t, landmark_event_t,
                                  lmap_snapshot_t, global_map_t, dynamic_notice_t, node_status_t>;
TYPED_TEST_SUITE(LcmTypeTest, AllTypes);

// A message with every byte of its payload random: all our types are fixed-size,
// so any payload decodes, and re-encoding must give the same bytes.
template <typename T>
std::vector<uint8_t> random_encoding(std::mt19937_64& rng) {
  T msg{};
  std::vector<uint8_t> buf(static_cast<std::size_t>(msg.getEncodedSize()));
  EXPECT_EQ(msg.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  for (std::size_t i = 8; i < buf.size(); ++i) buf[i] = static_cast<uint8_t>(rng());
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

TEST(LcmTypes, SensorFrameFieldsSurvive) {
  sensor_frame_t m{};
  m.utime = 1700000000123456;
  m.frame = 17;
  m.robot_id = 2;
  m.odom_x = 1.5;
  m.odom_y = -2.25;
  m.odom_theta = 0.125;
  m.odom_var_trans_per_m = 1e-4;
  m.num_obs = 2;
  m.obs[0].landmark_id = 5;
  m.obs[0].range = 3.5;
  m.obs[0].bearing = -0.5;
  m.obs[63].landmark_id = 71;  // last fixed slot is encoded too
  std::vector<uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  ASSERT_GT(m.encode(buf.data(), 0, static_cast<int>(buf.size())), 0);
  sensor_frame_t d{};
  ASSERT_GT(d.decode(buf.data(), 0, static_cast<int>(buf.size())), 0);
  EXPECT_EQ(d.utime, m.utime);
  EXPECT_EQ(d.frame, 17);
  EXPECT_EQ(d.robot_id, 2);
  EXPECT_EQ(d.odom_y, -2.25);
  EXPECT_EQ(d.num_obs, 2);
  EXPECT_EQ(d.obs[0].landmark_id, 5);
  EXPECT_EQ(d.obs[0].bearing, -0.5);
  EXPECT_EQ(d.obs[63].landmark_id, 71);
}

TEST(LcmTypes, ArraySizesMatchTheContractConstants) {
  // The capacities in contract.hpp mirror the .lcm array sizes (also static_asserts there).
  EXPECT_EQ(sizeof(sensor_frame_t::obs) / sizeof(sensor_frame_t::obs[0]),
            static_cast<std::size_t>(contract::kMaxObsPerFrame));
  EXPECT_EQ(sizeof(ground_truth_t::robots) / sizeof(ground_truth_t::robots[0]),
            static_cast<std::size_t>(contract::kMaxRobots));
  EXPECT_EQ(sizeof(global_map_t::landmarks) / sizeof(global_map_t::landmarks[0]),
            static_cast<std::size_t>(contract::kMaxLandmarksPerMessage));
  EXPECT_EQ(sizeof(lmap_snapshot_t::landmarks) / sizeof(lmap_snapshot_t::landmarks[0]),
            static_cast<std::size_t>(contract::kMaxLandmarksPerMessage));
  // Messages stay within one UDP datagram (LCM.md section 6: <= 65,499 bytes).
  EXPECT_LT(global_map_t{}.getEncodedSize(), 65000);
  EXPECT_LT(lmap_snapshot_t{}.getEncodedSize(), 65000);
}

TEST(LcmTypes, ChannelNames) {
  EXPECT_EQ(channels::sensor(3), "SENSOR_3");
  EXPECT_EQ(channels::pose(1), "POSE_1");
  EXPECT_EQ(channels::status_robot(2, "_B"), "STATUS_ROBOT_2_B");
  EXPECT_EQ(channels::lmap_event(), "LMAP_EVENT");
  EXPECT_EQ(channels::global_map(), "GLOBAL_MAP");
}

}  // namespace
}  // namespace elaslam

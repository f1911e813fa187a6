// SPDX-License-Identifier: Apache-2.0
// A steady flow through the node shell and the in-process transport allocates
// nothing: messages are decoded into the input's one message, encoded into the
// shell's one buffer, queued in reused slots.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "../support/no_alloc.hpp"
#include "elaslam/transport/inprocess_transport.hpp"
#include "elaslam/transport/message_arrays.hpp"
#include "round_trip.hpp"

namespace elaslam::transport {
namespace {

TEST(ShellNoAlloc, ASensorToPoseRoundTripAllocatesNothingOnceWarm) {
  InProcessTransport bus;
  const long poses = test::sensor_pose_round_trip(bus, bus, bus);
  EXPECT_EQ(test::allocations_in_region(), 0);
  EXPECT_EQ(poses, 2000);
}

// main_robot's TRACKS_<r> input: its arrays hold the largest count the wire can state,
// so decoding a forged count (refused afterwards) allocates nothing either.
TEST(ShellNoAlloc, ATracksInputDecodesAnyCountWithoutAllocating) {
  track_list_t big{};
  big.num_tracks = static_cast<std::int16_t>(kMaxCount);
  big.tracks.resize(kMaxCount);
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(big.getEncodedSize()));
  ASSERT_GT(big.encode(buf.data(), 0, static_cast<int>(buf.size())), 0);
  track_list_t in{};
  reserve_arrays(&in);
  {
    test::NoAllocRegion region;
    ASSERT_GT(in.decode(buf.data(), 0, static_cast<int>(buf.size())), 0);
  }
  EXPECT_EQ(test::allocations_in_region(), 0);
  EXPECT_EQ(in.num_tracks, kMaxCount);
}

}  // namespace
}  // namespace elaslam::transport

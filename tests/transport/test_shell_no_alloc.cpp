// SPDX-License-Identifier: Apache-2.0
// A steady flow through the node shell and the in-process transport allocates
// nothing: messages are decoded into the input's one message, encoded into the
// shell's one buffer, queued in reused slots.
#include <gtest/gtest.h>

#include "../support/no_alloc.hpp"
#include "elaslam/transport/inprocess_transport.hpp"
#include "round_trip.hpp"

namespace elaslam::transport {
namespace {

TEST(ShellNoAlloc, ASensorToPoseRoundTripAllocatesNothingOnceWarm) {
  InProcessTransport bus;
  const long poses = test::sensor_pose_round_trip(bus, bus, bus);
  EXPECT_EQ(test::allocations_in_region(), 0);
  EXPECT_EQ(poses, 2000);
}

}  // namespace
}  // namespace elaslam::transport

// SPDX-License-Identifier: Apache-2.0
// The receive path of message authentication allocates nothing: open() verifies a
// message in place (the hash state on the stack, the payload the same bytes without
// the trailer), accepted or refused; and a steady flow of signed messages through
// the node shell and the authenticated transport allocates nothing once warm.
#include <gtest/gtest.h>

#include <vector>

#include "../support/no_alloc.hpp"
#include "../support/test_keys.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/sensor_frame_t.hpp"
#include "elaslam/transport/auth_transport.hpp"
#include "elaslam/transport/inprocess_transport.hpp"
#include "round_trip.hpp"

namespace elaslam::transport::auth {
namespace {

TEST(AuthNoAlloc, OpeningAcceptedAndRefusedMessagesAllocatesNothing) {
  Authenticator sim(test::team_setup(kSenderSimulator, 5));
  Authenticator robot(test::team_setup(1, 6));
  sensor_frame_t s{};
  s.robot_id = 1;
  s.obs.resize(15);
  s.num_obs = 15;
  const std::string channel = "SENSOR_1";
  const int n = s.getEncodedSize();
  // 2000 sealed frames, made before the region.
  std::vector<std::vector<std::uint8_t>> sealed;
  for (int k = 0; k < 2000; ++k) {
    s.frame = k;
    std::vector<std::uint8_t> buf(static_cast<std::size_t>(n) + kTrailerBytes);
    s.encode(buf.data(), 0, n);
    buf.resize(sim.seal(channel, buf.data(), static_cast<std::size_t>(n)));
    sealed.push_back(std::move(buf));
  }
  std::vector<std::uint8_t> forged = sealed[0];
  forged[20] ^= 1;
  long accepted = 0, refused = 0;
  {
    test::NoAllocRegion region;
    for (const auto& m : sealed) {
      std::size_t payload = 0;
      Sender who;
      accepted += robot.open(channel, m.data(), m.size(), &payload, &who) == Verdict::kAccepted;
      refused += robot.open(channel, m.data(), m.size(), &payload, &who) == Verdict::kReplayed;
      refused += robot.open(channel, forged.data(), forged.size(), &payload, &who) == Verdict::kForged;
      refused += robot.open(channel, m.data(), 10, &payload, &who) == Verdict::kUnauthenticated;
    }
  }
  EXPECT_EQ(test::allocations_in_region(), 0);
  EXPECT_EQ(accepted, 2000);
  EXPECT_EQ(refused, 3 * 2000);
}

TEST(AuthNoAlloc, ASensorToPoseRoundTripThroughAuthenticatedTransportsAllocatesNothingOnceWarm) {
  InProcessTransport bus;
  AuthenticatedTransport robot_t(bus, test::team_setup(1, 1), "robot", nullptr);
  AuthenticatedTransport sim_t(bus, test::team_setup(kSenderSimulator, 2), "sim", nullptr);
  const long poses = test::sensor_pose_round_trip(bus, robot_t, sim_t);
  EXPECT_EQ(test::allocations_in_region(), 0);
  EXPECT_EQ(poses, 2000);
  EXPECT_EQ(robot_t.counters().accepted, 2000);
  EXPECT_EQ(sim_t.counters().refused(), 0);
}

}  // namespace
}  // namespace elaslam::transport::auth

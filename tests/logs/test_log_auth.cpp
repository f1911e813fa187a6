// SPDX-License-Identifier: Apache-2.0
// Reading a keyed team's recording as its nodes read the wire (log_auth.hpp): what
// verifies loses its trailer and is decoded as recorded; forged, altered, replayed,
// unauthenticated, misattributed and other missions' events are refused and counted
// per channel and reason; channels that are not the team's pass untouched.
#include "elaslam/logs/log_auth.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "../support/test_keys.hpp"
#include "elaslam/common/channels.hpp"
#include "elaslam/pose_estimate_t.hpp"

namespace elaslam {
namespace {

namespace auth = transport::auth;

std::vector<std::uint8_t> encoded_pose(int robot, int frame) {
  pose_estimate_t m{};
  m.robot_id = static_cast<std::int16_t>(robot);
  m.frame = frame;
  m.x = 1.5;
  std::vector<std::uint8_t> b(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

// An event as the recorder records it: the signed datagram.
LogEvent sealed(auth::Authenticator* sender, const std::string& channel, std::vector<std::uint8_t> payload) {
  const std::size_t n = payload.size();
  payload.resize(n + auth::kTrailerBytes);
  payload.resize(sender->seal(channel, payload.data(), n));
  return LogEvent{0, channel, payload};
}

TEST(LogAuth, GenuineEventsVerifyAndDecodeAsSentTheRestIsRefusedPerReason) {
  const std::string sfx = "_T";
  auth::Authenticator robot1(test::team_setup(1, 1000, sfx));
  auth::AuthSetup other = test::team_setup(1, 1000, sfx);  // the same id, another key (its own roster lists it)
  other.roster = transport::Roster{};
  std::string why;
  other.key = test::test_key(222);
  ASSERT_TRUE(other.roster.add(1, other.key.public_key(), &why)) << why;
  auth::Authenticator stranger(std::move(other));
  auth::Authenticator earlier(test::team_setup(1, 900, sfx, true, test::kTestMission + 1));  // another mission
  LogAuth reader(test::team_setup(transport::kSenderTool, 0, sfx, false));

  const std::vector<std::uint8_t> payload = encoded_pose(1, 7);
  LogEvent ok = sealed(&robot1, channels::pose(1, sfx), payload);
  const LogEvent replay = ok;
  ASSERT_TRUE(reader.admit(&ok));
  EXPECT_EQ(ok.data, payload);  // the trailer is gone: LCM's decoder sees what was encoded
  pose_estimate_t m;
  ASSERT_GE(m.decode(ok.data.data(), 0, static_cast<int>(ok.data.size())), 0);
  EXPECT_EQ(m.frame, 7);

  LogEvent again = replay;
  EXPECT_FALSE(reader.admit(&again));  // the same datagram twice: a replay
  LogEvent forged = sealed(&stranger, channels::pose(1, sfx), encoded_pose(1, 8));
  EXPECT_FALSE(reader.admit(&forged));
  LogEvent altered = sealed(&robot1, channels::pose(1, sfx), encoded_pose(1, 9));
  altered.data[20] ^= 0x01;
  EXPECT_FALSE(reader.admit(&altered));
  LogEvent plain{0, channels::pose(1, sfx), encoded_pose(1, 10)};
  EXPECT_FALSE(reader.admit(&plain));
  LogEvent not_its = sealed(&robot1, channels::pose(2, sfx), encoded_pose(2, 11));  // robot 1 on robot 2's channel
  EXPECT_FALSE(reader.admit(&not_its));
  LogEvent old = sealed(&earlier, channels::pose(1, sfx), encoded_pose(1, 12));
  EXPECT_FALSE(reader.admit(&old));
  LogEvent self_test{0, "LCM_SELF_TEST", {1, 2, 3}};
  EXPECT_TRUE(reader.admit(&self_test));  // not the team's: as is
  EXPECT_EQ(self_test.data, (std::vector<std::uint8_t>{1, 2, 3}));

  EXPECT_EQ(reader.accepted(), 1);
  EXPECT_EQ(reader.refused(), 6);
  const auto& by = reader.refused_by_channel();
  ASSERT_EQ(by.count(channels::pose(1, sfx)), 1u);
  const auto& p1 = by.at(channels::pose(1, sfx));
  const auto n = [&](const std::map<std::string, std::int64_t>& m, auth::Verdict v) {
    return m.count(auth::key_of(v)) ? m.at(auth::key_of(v)) : 0;
  };
  EXPECT_EQ(n(p1, auth::Verdict::kReplayed), 1);
  EXPECT_EQ(n(p1, auth::Verdict::kUnknownKey), 1);  // another key
  EXPECT_EQ(n(p1, auth::Verdict::kForged), 1);      // altered bytes
  EXPECT_EQ(n(p1, auth::Verdict::kUnauthenticated), 1);
  EXPECT_EQ(n(p1, auth::Verdict::kOtherMission), 1);
  EXPECT_EQ(n(by.at(channels::pose(2, sfx)), auth::Verdict::kWrongSender), 1);
  const nlohmann::json j = reader.to_json("k");
  EXPECT_EQ(j["refused"], 6);
  EXPECT_EQ(j["mission"], transport::mission_text(test::kTestMission));
  EXPECT_EQ(j["refused_by"][channels::pose(2, sfx)]["wrong_sender"], 1);
  EXPECT_EQ(j["refused_by_reason"]["other_mission"], 1);
}

TEST(Channels, TeamChannelsAreRecognisedWithTheirSuffixOnly) {
  for (const std::string sfx : {"", "_SIM2"}) {
    EXPECT_TRUE(channels::is_team_channel(channels::sensor(3, sfx), sfx));
    EXPECT_TRUE(channels::is_team_channel(channels::status_robot(8, sfx), sfx));
    EXPECT_TRUE(channels::is_team_channel(channels::global_map(sfx), sfx));
    EXPECT_TRUE(channels::is_team_channel(channels::run_info(sfx), sfx));
    EXPECT_TRUE(channels::is_team_channel(channels::team_map(2, sfx), sfx));
    EXPECT_FALSE(channels::is_team_channel("LCM_SELF_TEST", sfx));
    EXPECT_FALSE(channels::is_team_channel("POSE_x" + sfx, sfx));
    EXPECT_FALSE(channels::is_team_channel(channels::global_map(sfx) + "X", sfx));
  }
  EXPECT_FALSE(channels::is_team_channel(channels::global_map("_A"), "_B"));
  EXPECT_FALSE(channels::is_team_channel(channels::pose(1, ""), "_B"));
}

}  // namespace
}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// The LCM transport over memq:// (one process, no network).
#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <vector>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/transport/grouped_lcm_transport.hpp"
#include "elaslam/transport/lcm_transport.hpp"

namespace elaslam::transport {
namespace {

void record(const RawMessage& m, void* context) {
  static_cast<std::vector<std::string>*>(context)->push_back(
      m.channel + ":" + std::string(reinterpret_cast<const char*>(m.data), m.size));
}

bool pub(Transport& t, const std::string& channel, const std::string& payload) {
  return t.publish(channel, payload.data(), payload.size());
}

TEST(LcmTransport, MemqDeliversInOrderWithPatterns) {
  LcmTransport t("memq://");
  ASSERT_TRUE(t.good());
  std::vector<std::string> log;
  ASSERT_GT(t.subscribe("STATUS_(ROBOT_[0-9]+|MAIN)", &record, &log, kUnboundedQueue), 0);
  EXPECT_TRUE(pub(t, "STATUS_ROBOT_2", "a"));
  EXPECT_TRUE(pub(t, "STATUS_SIM", "b"));
  EXPECT_TRUE(pub(t, "STATUS_MAIN", "c"));
  while (t.handle_timeout(0) > 0) {
  }
  EXPECT_EQ(log, (std::vector<std::string>{"STATUS_ROBOT_2:a", "STATUS_MAIN:c"}));
}

TEST(LcmTransport, HandleTimeoutWaitsAtMostItsTimeout) {
  LcmTransport t("memq://");
  std::vector<std::string> log;
  t.subscribe("A", &record, &log, 5);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(t.handle_timeout(30), 0);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(5));
}

TEST(LcmTransport, UnsubscribeStopsDelivery) {
  LcmTransport t("memq://");
  std::vector<std::string> a, b;
  const int ida = t.subscribe("A", &record, &a, kTransportDefaultQueue);
  t.subscribe("A", &record, &b, kTransportDefaultQueue);
  pub(t, "A", "1");
  while (t.handle_timeout(0) > 0) {
  }
  t.unsubscribe(ida);
  pub(t, "A", "2");
  while (t.handle_timeout(0) > 0) {
  }
  EXPECT_EQ(a, (std::vector<std::string>{"A:1"}));
  EXPECT_EQ(b, (std::vector<std::string>{"A:1", "A:2"}));
}

TEST(LcmTransport, ABadUrlGivesATransportThatSaysSo) {
  LcmTransport t("nosuchprovider://");
  EXPECT_FALSE(t.good());
  std::vector<std::string> log;
  EXPECT_EQ(t.subscribe("A", &record, &log, 5), 0);
  EXPECT_FALSE(pub(t, "A", "1"));
  EXPECT_LT(t.handle_timeout(0), 0);
}

// Channel groups (grouped_lcm_transport.hpp): which channel goes on which port. The
// live behaviour (isolation between ports) is system_channel_groups.

TEST(ChannelGroups, EveryChannelHasTheGroupOfItsReaders) {
  using namespace channels;
  static_assert(kMaxGroupRobotId == contract::kMaxRobots);
  for (const std::string& sfx : {std::string(), std::string("_SIM2")}) {
    EXPECT_EQ(channel_group(dynamic_notice(sfx), sfx), kGroupTeam);
    EXPECT_EQ(channel_group(lmap_resync(sfx), sfx), kGroupTeam);
    EXPECT_EQ(channel_group(status_main(sfx), sfx), kGroupTeam);
    EXPECT_EQ(channel_group(status_sim(sfx), sfx), kGroupTeam);
    EXPECT_EQ(channel_group(status_robot(7, sfx), sfx), kGroupTeam);
    EXPECT_EQ(channel_group(run_info(sfx), sfx), kGroupTeam);
    EXPECT_EQ(channel_group(lmap_event(sfx), sfx), kGroupOutputs);
    EXPECT_EQ(channel_group(lmap_snapshot(sfx), sfx), kGroupOutputs);
    EXPECT_EQ(channel_group(pose(1, sfx), sfx), kGroupPoses);
    EXPECT_EQ(channel_group(pose(16, sfx), sfx), kGroupPoses);
    EXPECT_EQ(channel_group(global_map(sfx), sfx), kGroupMap);
    EXPECT_EQ(channel_group(ground_truth(sfx), sfx), kGroupObservers);
    EXPECT_EQ(channel_group(candidates(3, sfx), sfx), kGroupObservers);
    for (int r = 1; r <= kMaxGroupRobotId; ++r) {
      EXPECT_EQ(channel_group(sensor(r, sfx), sfx), kGroupRobot + r);
      EXPECT_EQ(channel_group(team_map(r, sfx), sfx), kGroupRobot + r);
    }
    EXPECT_EQ(channel_group(sensor(17, sfx), sfx), kGroupTeam);  // no node accepts robot 17
    EXPECT_EQ(channel_group("SOMETHING_ELSE" + sfx, sfx), kGroupTeam);
  }
  EXPECT_EQ(channels::channel_group("SENSOR_1", "_SIM2"), kGroupTeam);  // another team's name: not ours
  EXPECT_EQ(kGroupRobot + kMaxGroupRobotId, kChannelGroups - 1);
}

TEST(ChannelGroups, GroupUrlMovesOnlyThePort) {
  std::string why;
  EXPECT_EQ(group_url("udpm://239.255.76.67:7700?ttl=0&recv_buf_size=8388608", 5, &why),
            "udpm://239.255.76.67:7705?ttl=0&recv_buf_size=8388608");
  EXPECT_EQ(why, "");
  EXPECT_EQ(group_url("", 0, &why), "udpm://239.255.76.67:7667?ttl=0");  // LCM's default
  EXPECT_EQ(group_url("udpm://239.255.76.68?ttl=1", 2, &why), "udpm://239.255.76.68:7669?ttl=1");
  EXPECT_EQ(group_url("udpm://239.255.76.67:7667", 20, &why), "udpm://239.255.76.67:7687");
  // Refused, each with the reason.
  EXPECT_EQ(group_url("memq://", 0, &why), "");
  EXPECT_NE(why.find("udpm://"), std::string::npos) << why;
  EXPECT_EQ(group_url("udpm://239.255.76.67:65530", 0, &why), "");
  EXPECT_NE(why.find("past 65535"), std::string::npos) << why;
  EXPECT_EQ(group_url("udpm://239.255.76.67:7x7", 0, &why), "");
  EXPECT_NE(why.find("not a port"), std::string::npos) << why;
  EXPECT_EQ(group_url("udpm://:7667", 0, &why), "");
  EXPECT_NE(why.find("no multicast address"), std::string::npos) << why;
}

TEST(ChannelGroups, APatternJoinsTheGroupsOfTheChannelsItMatches) {
  using namespace channels;
  const auto bit = [](int g) { return 1u << g; };
  EXPECT_EQ(groups_of_pattern(sensor(2), ""), bit(kGroupRobot + 2));
  EXPECT_EQ(groups_of_pattern(any_pose(), ""), bit(kGroupPoses));
  EXPECT_EQ(groups_of_pattern(any_pose("_B"), "_B"), bit(kGroupPoses));
  EXPECT_EQ(groups_of_pattern(global_map(), ""), bit(kGroupMap));
  EXPECT_EQ(groups_of_pattern("STATUS_(ROBOT_[0-9]+|MAIN)", ""), bit(kGroupTeam));
  EXPECT_EQ(groups_of_pattern("(LMAP_EVENT|GLOBAL_MAP)", ""), bit(kGroupOutputs) | bit(kGroupMap));
  std::uint32_t all = 0;
  for (int g = 0; g < kChannelGroups; ++g) all |= bit(g);
  EXPECT_EQ(groups_of_pattern(".*", ""), all);  // a recorder: every group
  EXPECT_EQ(groups_of_pattern(any_sensor(), ""), all & ~0x1fu);  // every robot's group, nothing else
  // Names the system does not have go where unknown channels are published.
  EXPECT_EQ(groups_of_pattern("EXAMPLE", ""), bit(kGroupTeam));
  EXPECT_EQ(groups_of_pattern("((", ""), bit(kGroupTeam));  // not a std::regex: LCM decides
}

TEST(ChannelGroups, ATransportThatCannotHaveGroupsSaysWhy) {
  GroupedLcmTransport memq("memq://", "");
  EXPECT_FALSE(memq.good());
  EXPECT_NE(memq.error().find("udpm://"), std::string::npos) << memq.error();
  std::vector<std::string> log;
  EXPECT_EQ(memq.subscribe("A", &record, &log, 5), 0);
  EXPECT_FALSE(pub(memq, "A", "1"));
  EXPECT_LT(memq.handle_timeout(0), 0);
  EXPECT_TRUE(memq.channel_groups());
  EXPECT_FALSE(LcmTransport("memq://").channel_groups());
}

}  // namespace
}  // namespace elaslam::transport

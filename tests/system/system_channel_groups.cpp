// SPDX-License-Identifier: Apache-2.0
// Channel groups over real udpm:// (grouped_lcm_transport.hpp), in a private network
// namespace (tools/netns_run.sh sets LCM_DEFAULT_URL): each group's channels go out on
// its own port and only there, a subscriber hears what it subscribed to from every
// group it needs, order holds within a group, and a recorder (".*") hears everything.
// Plain LcmTransports bound to single ports are the probes: what a port carries is
// what every process that joins it is woken for.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "elaslam/common/channels.hpp"
#include "elaslam/transport/grouped_lcm_transport.hpp"
#include "elaslam/transport/lcm_transport.hpp"

namespace elaslam::transport {
namespace {

using Log = std::vector<std::string>;

void record(const RawMessage& m, void* context) {
  if (m.channel == "LCM_SELF_TEST") return;  // LCM's own, sent on a port at its first subscription
  static_cast<Log*>(context)->push_back(m.channel + ":" + std::string(reinterpret_cast<const char*>(m.data), m.size));
}

std::string base_url() {
  const char* env = std::getenv("LCM_DEFAULT_URL");
  return env != nullptr ? env : "";
}

std::string port_url(int group) {
  std::string why;
  return group_url(base_url(), group, &why);
}

/// Handle whatever arrives on every transport until none has had anything for 200 ms.
void pump(const std::vector<Transport*>& ts) {
  auto quiet_since = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - quiet_since < std::chrono::milliseconds(200)) {
    bool any = false;
    for (Transport* t : ts) any |= t->handle_timeout(5) > 0;
    if (any) quiet_since = std::chrono::steady_clock::now();
  }
}

class ChannelGroupsLive : public ::testing::Test {
 protected:
  void SetUp() override {
    if (base_url().empty()) GTEST_SKIP() << "no LCM_DEFAULT_URL: run inside tools/netns_run.sh";
    ASSERT_TRUE(sender_.good()) << sender_.error();
  }
  GroupedLcmTransport sender_{base_url(), ""};
};

TEST_F(ChannelGroupsLive, EachChannelGoesOutOnItsGroupsPortOnly) {
  using namespace channels;
  // Probes on single ports: the team group, the robots' outputs, the POSEs, robot 2's own.
  LcmTransport team(port_url(kGroupTeam)), outputs(port_url(kGroupOutputs)), poses(port_url(kGroupPoses)),
      robot2(port_url(kGroupRobot + 2));
  Log at_team, at_outputs, at_poses, at_robot2;
  ASSERT_GT(team.subscribe(".*", &record, &at_team, kUnboundedQueue), 0);
  ASSERT_GT(outputs.subscribe(".*", &record, &at_outputs, kUnboundedQueue), 0);
  ASSERT_GT(poses.subscribe(".*", &record, &at_poses, kUnboundedQueue), 0);
  ASSERT_GT(robot2.subscribe(".*", &record, &at_robot2, kUnboundedQueue), 0);
  // Robot 2 as a node reads it: its SENSOR, the notices.
  GroupedLcmTransport node(base_url(), "");
  Log at_node;
  ASSERT_GT(node.subscribe(sensor(2), &record, &at_node, kUnboundedQueue), 0);
  ASSERT_GT(node.subscribe(dynamic_notice(), &record, &at_node, kUnboundedQueue), 0);

  for (const std::string& ch : {sensor(1), sensor(2), pose(2), dynamic_notice(), global_map(), ground_truth(),
                               team_map(2), lmap_events(), lmap_snapshot(), pose(3), std::string("UNKNOWN")})
    ASSERT_TRUE(sender_.publish(ch, "x", 1)) << ch;
  pump({&team, &outputs, &poses, &robot2, &node});

  EXPECT_EQ(at_team, (Log{"DYNAMIC_NOTICE:x", "UNKNOWN:x"}));
  EXPECT_EQ(at_outputs, (Log{"LMAP_EVENTS:x", "LMAP_SNAPSHOT:x"}));
  EXPECT_EQ(at_poses, (Log{"POSE_2:x", "POSE_3:x"}));
  EXPECT_EQ(at_robot2, (Log{"SENSOR_2:x", "TEAM_MAP_2:x"}));
  std::sort(at_node.begin(), at_node.end());  // two ports: no order between them
  EXPECT_EQ(at_node, (Log{"DYNAMIC_NOTICE:x", "SENSOR_2:x"}));
}

TEST_F(ChannelGroupsLive, ARecorderHearsEveryGroupAndOrderHoldsWithinOne) {
  GroupedLcmTransport recorder(base_url(), "");
  Log all;
  ASSERT_GT(recorder.subscribe(".*", &record, &all, kUnboundedQueue), 0);
  std::map<std::string, int> expected;
  for (int i = 0; i < 50; ++i)
    for (int g = 0; g < channels::kChannelGroups; ++g) {
      // One channel of each group: the team's, outputs, map, observers, poses, robots 1-16.
      const std::string ch = g == channels::kGroupTeam        ? channels::status_main()
                             : g == channels::kGroupOutputs   ? channels::lmap_events()
                             : g == channels::kGroupMap       ? channels::global_map()
                             : g == channels::kGroupObservers ? channels::ground_truth()
                             : g == channels::kGroupPoses     ? channels::pose(3)
                                                              : channels::sensor(g - channels::kGroupRobot);
      ASSERT_EQ(channels::channel_group(ch), g) << ch;
      const std::string payload = std::to_string(i);
      ASSERT_TRUE(sender_.publish(ch, payload.data(), payload.size()));
      ++expected[ch];
    }
  pump({&recorder});
  ASSERT_EQ(all.size(), 50u * channels::kChannelGroups);
  std::map<std::string, int> next;  // per channel: the payloads come 0, 1, 2, ...
  for (const std::string& m : all) {
    const std::string ch = m.substr(0, m.find(':'));
    EXPECT_EQ(m.substr(m.find(':') + 1), std::to_string(next[ch]++)) << m;
  }
  EXPECT_EQ(next, expected);
}

TEST_F(ChannelGroupsLive, UnsubscribedGroupsStaySilent) {
  GroupedLcmTransport node(base_url(), "");
  Log got;
  const int id = node.subscribe(channels::any_pose(), &record, &got, kUnboundedQueue);
  ASSERT_GT(id, 0);
  sender_.publish(channels::pose(1), "a", 1);
  pump({&node});
  EXPECT_EQ(got, (Log{"POSE_1:a"}));
  node.unsubscribe(id);
  sender_.publish(channels::pose(1), "b", 1);
  sender_.publish(channels::sensor(1), "c", 1);
  EXPECT_EQ(node.handle_timeout(100), 0);  // nothing joined: it waits and returns none
  EXPECT_EQ(got, (Log{"POSE_1:a"}));
}

}  // namespace
}  // namespace elaslam::transport

// SPDX-License-Identifier: Apache-2.0
// robot_node's summary at exit (robot_ports.hpp, final_summary): the counters, the
// frame stages' p50/p99/max, and the team-map line only when the robot fuses the
// team's map.
#include <gtest/gtest.h>

#include <string>

#include "elaslam/robot_node/robot_ports.hpp"
#include "scene.hpp"

namespace elaslam {
namespace {

TEST(NodeSummary, ANewNodesCountersAndStages) {
  const RobotNode node(test::robot_options(Mode::kEla), 2);
  FrameStages st;
  st.frame.add(5);
  st.frame.add(7);
  st.pose.add(3);
  EXPECT_EQ(final_summary(node, st),
            "robot_node 2: frames=0 gaps=0 duplicates=0 out_of_order=0 rejected=0 decode_errors=0 filter_faults=0 "
            "events=0 notices_applied=0 notices_stale=0 landmarks=0 evictions=0 restored=0 frame_us p50=0 p99=0 "
            "max=0\n"
            "robot_node 2: stages_us p50/p99/max receive=0/0/0 frame=5/7/7 outputs=0/0/0 pose=3/3/3\n");
}

TEST(NodeSummary, TheTeamMapLineWhenTheRobotFusesIt) {
  RobotOptions o = test::robot_options(Mode::kEla);
  o.team_map_fuse = true;
  const RobotNode node(o, 4);
  const std::string s = final_summary(node, FrameStages{});
  const std::string team = "robot_node 4: team_map chunks=0 stale=0 offered=0 fused=0 gated=0 refused=0 mean_nis=0.00 "
                           "lost=0 relocalised=0\n";
  ASSERT_GE(s.size(), team.size());
  EXPECT_EQ(s.substr(s.size() - team.size()), team);
  EXPECT_EQ(final_summary(RobotNode(test::robot_options(Mode::kEla), 4), FrameStages{}).find("team_map"),
            std::string::npos);
}

}  // namespace
}  // namespace elaslam

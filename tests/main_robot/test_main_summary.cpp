// SPDX-License-Identifier: Apache-2.0
// main_robot's summary at exit (main_node.hpp, final_summary): every counter, the
// map's static and moving counts, its version.
#include <gtest/gtest.h>

#include <string>

#include "../support/messages.hpp"
#include "elaslam/main_robot/main_node.hpp"

namespace elaslam {
namespace {

TEST(MainSummary, ANewNode) {
  GlobalMapOptions o;
  o.max_landmark_id = 32;
  const MainNode node(o);
  EXPECT_EQ(final_summary(node),
            "main_robot: events=0 snapshots=0 duplicates=0 gaps=0 rejected=0 decode_errors=0 notices=0 static=0 "
            "moving=0 version=0 maps=0 map_chunks=0 moving_sets=0 stale_poses=0 runs_started=0 occupied=0 "
            "team_map_left_out=0 state_damaged=0\n");
}

TEST(MainSummary, EventsAStaticLandmarkARefusalAndDecodeErrors) {
  GlobalMapOptions o;
  o.max_landmark_id = 32;
  MainNode node(o);
  std::string why;
  ASSERT_TRUE(node.on_event(test::event_msg(1, 1, landmark_event_t::ADD, 7), &why)) << why;
  EXPECT_FALSE(node.on_event(test::event_msg(1, 2, landmark_event_t::ADD, 99)));  // id beyond max_landmark_id
  node.count_decode_error();
  node.count_decode_error();
  const std::string s = final_summary(node);
  EXPECT_EQ(s.rfind("main_robot: events=1 ", 0), 0u) << s;
  EXPECT_NE(s.find(" rejected=1 decode_errors=2 notices=0 static=1 moving=0 "), std::string::npos) << s;
}

}  // namespace
}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// The channel table of common/include/elaslam/common/channels.hpp as JSON, for
// tests/tools/channel_tables_check.py, which compares the scripts' hand-written
// copies (tools/lcm_groups.sh, tools/foxglove_bridge.py, tools/decode_log.py) with it:
// the names and per-robot prefixes, the group constants, and the group of every
// channel of robots 1 .. kMaxGroupRobotId + 1 (the last one beyond the groups).
#include <cstdio>
#include <iterator>
#include <string>
#include <string_view>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/contract.hpp"

namespace {

void list(const char* key, const std::string_view* begin, const std::string_view* end) {
  std::printf("  \"%s\": [", key);
  for (const std::string_view* n = begin; n != end; ++n)
    std::printf("%s\"%.*s\"", n == begin ? "" : ", ", static_cast<int>(n->size()), n->data());
  std::printf("],\n");
}

}  // namespace

int main() {
  namespace ch = elaslam::channels;
  std::printf("{\n");
  list("team_names", std::begin(ch::kTeamNames), std::end(ch::kTeamNames));
  list("robot_prefixes", std::begin(ch::kRobotPrefixes), std::end(ch::kRobotPrefixes));
  std::printf("  \"group_team\": %d, \"group_outputs\": %d, \"group_map\": %d, \"group_observers\": %d,\n",
              ch::kGroupTeam, ch::kGroupOutputs, ch::kGroupMap, ch::kGroupObservers);
  std::printf("  \"group_poses\": %d, \"group_robot\": %d, \"max_group_robot_id\": %d, \"channel_groups\": %d,\n",
              ch::kGroupPoses, ch::kGroupRobot, ch::kMaxGroupRobotId, ch::kChannelGroups);
  std::printf("  \"max_robots\": %d,\n", elaslam::contract::kMaxRobots);
  std::printf("  \"groups\": {");
  const char* sep = "\n    ";
  for (std::string_view n : ch::kTeamNames) {
    const std::string name(n);
    std::printf("%s\"%s\": %d", sep, name.c_str(), ch::channel_group(name));
    sep = ",\n    ";
  }
  for (int r = 1; r <= ch::kMaxGroupRobotId + 1; ++r)
    for (std::string_view p : ch::kRobotPrefixes) {
      const std::string name = std::string(p) + std::to_string(r);
      std::printf("%s\"%s\": %d", sep, name.c_str(), ch::channel_group(name));
    }
  std::printf("\n  }\n}\n");
  return 0;
}

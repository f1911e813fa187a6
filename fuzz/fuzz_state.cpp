// libFuzzer target: the state loaders, robot_node's (--state: load_robot_state) and
// main_robot's (--state: GlobalMap::from_json). The first byte picks the loader and
// whether the robot state is sealed again (mod 4: 0 raw, 1 sealed, 2 main's, 3
// sealed into a robot with the team's map on): a state file carries an FNV-1a checksum
// of its "state" object, so most mutations stop there; the sealed variant parses
// the text as JSON, recomputes the checksum and loads that, so the fuzzer reaches
// the field validation behind it. A refused state must leave the node as it was
// (checked: its state text is unchanged) and nothing may crash.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <nlohmann/json.hpp>

#include "elaslam/common/config.hpp"
#include "elaslam/main_robot/global_map.hpp"
#include "elaslam/robot_node/robot_node.hpp"
#include "elaslam/robot_node/robot_options.hpp"
#include "elaslam/robot_node/robot_state.hpp"
#include "fuzz_input.hpp"
#include "fuzz_options.hpp"

namespace {

using namespace elaslam;

using fuzz::main_options;
using fuzz::robot_options;

/// The text with its checksum made right again (the text itself when it is not a
/// JSON object with a "state").
std::string sealed(const std::string& text) {
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object() || !j.contains("state")) return text;
  nlohmann::json out = j;
  out["fnv1a64"] = robot_state_checksum(j["state"].dump());
  return out.dump();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  std::string why;
  switch (data[0] % 4) {
    case 0:
    case 1:
    case 3: {  // 3: sealed, into a node with robot.team_map.fuse on (the aided filter's keys)
      RobotOptions o = robot_options();
      o.team_map_fuse = data[0] % 4 == 3;
      RobotNode node(o, 1);
      const std::string before = save_robot_state(node);
      const bool ok = load_robot_state(data[0] % 4 == 0 ? text : sealed(text), &node, &why);
      if (!ok && save_robot_state(node) != before) {
        std::fprintf(stderr, "fuzz_state: a refused robot state changed the node (%s)\n", why.c_str());
        std::abort();
      }
      break;
    }
    default: {
      GlobalMap map(main_options());
      const std::string before = map.to_json();
      if (!map.from_json(text, &why) && map.to_json() != before) {
        std::fprintf(stderr, "fuzz_state: a refused main state changed the map (%s)\n", why.c_str());
        std::abort();
      }
      break;
    }
  }
  return 0;
}

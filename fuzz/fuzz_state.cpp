// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: the state loaders, robot_node's (--state: load_robot_state) and
// main_robot's (--state: open_map_state, map_state.hpp). The first byte picks the
// loader and whether the robot state is sealed again (mod 4: 0 raw, 1 sealed, 2
// main's, 3 sealed into a robot with the team's map on): a state file carries an
// FNV-1a checksum of its "state" object, so most mutations stop there; the sealed
// variant parses the text as JSON, recomputes the checksum and loads that, so the
// fuzzer reaches the field validation behind it. Main's file carries a BLAKE2b MAC
// (state_seal.hpp): its text is loaded as is and sealed again (unkeyed, as a hand
// edit would be) to reach the body's checks. A refused state must leave the node as
// it was (checked: its state text is unchanged) and nothing may crash.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <nlohmann/json.hpp>

#include "elaslam/common/config.hpp"
#include "elaslam/common/state_seal.hpp"
#include "elaslam/main_robot/map_state.hpp"
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

/// Main's state text with its seal made right again: the body (the text after a seal
/// header line, else all of it; without a closing "}\n") sealed unkeyed.
std::string main_sealed(const std::string& text) {
  std::string body = text;
  const auto nl = text.find('\n');
  if (text.rfind("{\"format\":\"", 0) == 0 && nl != std::string::npos) body = text.substr(nl + 1);
  if (body.size() >= 2 && body.compare(body.size() - 2, 2, "}\n") == 0) body.resize(body.size() - 2);
  return seal_state(kMapStateFormat, kMapStateVersion, body, nullptr);
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
      for (const std::string& t : {text, main_sealed(text)}) {
        GlobalMap map(main_options());
        const std::string before = map.to_json();
        if (!open_map_state(t, nullptr, &map, &why) && map.to_json() != before) {
          std::fprintf(stderr, "fuzz_state: a refused main state changed the map (%s)\n", why.c_str());
          std::abort();
        }
      }
      break;
    }
  }
  return 0;
}

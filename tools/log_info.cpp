// SPDX-License-Identifier: Apache-2.0
// log_info: what a recorded LCM log holds, like `ros2 bag info`: size, events, time
// span, per channel count / bytes / rate / type / undecodable events, the run it
// recorded (RUN_INFO), the frames it covers and, per robot, what happened to every
// frame: POSE logged, robot not started yet, frame dropped by the robot, or POSE
// processed but lost by the recorder (docs/tools.md "log_info").
//   log_info LOG [--json] [--config FILE] [--roster FILE] [--mission M]
// Exit status: 0 on success, 2 on a bad argument or a file that cannot be read or is
// not an LCM log (the reason on stderr).
#include <cstdio>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>

#include <CLI/CLI.hpp>

#include "elaslam/common/cli.hpp"
#include "elaslam/logs/log_auth.hpp"
#include "elaslam/logs/log_summary.hpp"

namespace {

int log_info_main(int argc, char** argv) {
  std::string path;
  bool json = false;
  std::string mission, config, roster;
  CLI::App app{"elaslam log_info: summary of a recorded LCM log (channels, run info, frames per robot)"};
  elaslam::cli::add_version_flag(app, "log_info");
  app.add_option("LOG", path, "LCM log (lcm-logger, mrclam_import)")->required();
  app.add_flag("--json", json, "print the summary as JSON (units in the keys) instead of text");
  app.add_option("--config", config, "the team's config file: with its team.public_keys and mission every event is "
                                     "verified as the nodes do, what they would refuse counted and skipped");
  app.add_option("--roster", roster, "the team's roster file (elaslam-keys team), over the config's");
  app.add_option("--mission", mission, "the mission to verify the events of (default: the roster's)");
  std::string suffix;
  app.add_option("--channel-suffix", suffix, "the team's channel suffix (which sender owns which channel)");
  if (const int rc = elaslam::cli::parse(app, argc, argv); rc >= 0) return rc;
  std::string used_key;
  std::unique_ptr<elaslam::LogAuth> auth;
  if (!elaslam::open_log_auth(roster, mission, config, suffix, "log_info", &auth, &used_key))
    return elaslam::cli::kExitBadInput;
  try {
    const elaslam::LogSummary s = elaslam::summarize_log(path, auth.get(), used_key);
    if (json)
      std::cout << elaslam::to_json(s).dump(2) << "\n";
    else
      elaslam::print_log_summary(std::cout, s);
  } catch (const std::runtime_error& e) {
    std::fprintf(stderr, "log_info: %s\n", e.what());
    return elaslam::cli::kExitBadInput;
  }
  return std::cout.good() ? 0 : elaslam::cli::kExitFailure;
}

}  // namespace

int main(int argc, char** argv) {
  return elaslam::cli::guarded_main("log_info", [&] { return log_info_main(argc, argv); });
}

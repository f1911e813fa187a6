// SPDX-License-Identifier: Apache-2.0
// monitor: one line that follows a live team (frame k/N, poses received, moving
// landmarks found so far, nodes' health), for a terminal or a log.
//   monitor [--config FILE] [--key-file FILE] [--lcm-url URL] [--channel-suffix S] [--interval S]
// On a terminal the line is rewritten in place about 5 times a second; otherwise a
// line is printed every --interval seconds. SIGINT / SIGTERM end it (exit 0) with
// the final line. Reads RUN_INFO, SENSOR_*, POSE_*, GLOBAL_MAP, DYNAMIC_NOTICE and
// STATUS_ROBOT_* through the node shell: a bad message is counted, never fatal. The
// line is transport/team_progress.hpp's.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <CLI/CLI.hpp>

#include "elaslam/common/cli.hpp"
#include "elaslam/common/config.hpp"
#include "elaslam/transport/auth_transport.hpp"
#include "elaslam/transport/node_shell.hpp"
#include "elaslam/transport/process.hpp"
#include "elaslam/transport/team_progress.hpp"

namespace {

int monitor_main(int argc, char** argv) {
  using namespace elaslam;
  transport::TransportArgs targs;
  double interval_s = 5.0;
  CLI::App app{"elaslam monitor: one progress line for a live team (frame, poses, moving landmarks, health)"};
  cli::add_version_flag(app, "monitor");
  std::string config;
  cli::add_config_option(app, &config, "its team: section (the team key)");
  transport::add_transport_options(app, &targs);
  app.add_option("--interval", interval_s, "seconds between lines when not on a terminal")
      ->capture_default_str()
      ->check(cli::range(0.1, 3600.0));
  if (const int rc = cli::parse(app, argc, argv); rc >= 0) return rc;
  // The team key (--key-file, else the config's team.key_file): a keyed team's messages
  // are verified here too. No configuration found (and none asked for): no key.
  std::string config_path;
  try {
    config_path = cli::find_config(config).path;
  } catch (const config::ConfigError& e) {
    if (!config.empty() || std::getenv(cli::kConfigEnv) != nullptr) {
      std::fprintf(stderr, "monitor: %s\n", e.what());
      return 2;
    }
  }
  int open_rc = 1;
  const auto lcm = transport::open_lcm(targs, config_path, transport::kSenderTool, false, 0, "monitor", &open_rc, nullptr);
  if (!lcm) return open_rc;
  // No log: the line is the monitor's output; bad messages show in it as "undecodable".
  transport::NodeShell shell(*lcm, transport::ShellOptions("monitor", targs.channel_suffix, nullptr));
  transport::TeamProgress progress;
  progress.subscribe(shell);
  transport::install_stop_handlers();
  const bool tty = isatty(STDERR_FILENO) == 1;
  const auto period = tty ? std::chrono::milliseconds(200)
                          : std::chrono::milliseconds(static_cast<long long>(interval_s * 1000.0));
  std::string last;
  shell.every(period, [&] {
    const std::string l = progress.line(shell);
    if (tty) {
      std::fprintf(stderr, "\r\033[K%s", l.c_str());  // rewrite the line in place
    } else if (l != last) {
      std::fprintf(stderr, "%s\n", l.c_str());
    }
    last = l;
  }, period);
  if (shell.spin(50) == transport::NodeShell::Exit::kTransportError) {
    std::fprintf(stderr, "monitor: LCM handle error\n");  // the shell has no log here
    return 1;
  }
  std::fprintf(stderr, tty ? "\r\033[K%s\n" : "%s\n", progress.line(shell).c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return elaslam::cli::guarded_main("monitor", [&] { return monitor_main(argc, argv); });
}

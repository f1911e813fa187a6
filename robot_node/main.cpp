// SPDX-License-Identifier: Apache-2.0
// robot_node: one robot's EKF-SLAM with the ELA gate, as its own process on LCM.
//   robot_node [--config FILE] --robot R [--mode M] [--state PATH] [--lcm-url URL] [--channel-suffix S]
// The config: --config, else $ELASLAM_CONFIG, else /etc/elaslam/elaslam.yaml, else
// the installed default (common/cli.hpp).
// Subscribes SENSOR_<R>, DYNAMIC_NOTICE; publishes POSE_<R>, LMAP_EVENTS (or LMAP_EVENT),
// LMAP_SNAPSHOT, STATUS_ROBOT_<R>. A thin shell: RobotNode on the node shell
// (RobotPorts, robot_ports.hpp), exactly as the in-process team run runs it.
// With --state the node's whole state (robot_state.hpp) is saved atomically after
// processed frames at most every node.state_save_interval_s and at exit, and
// resumed at start; a corrupt file is moved aside to PATH.corrupt (StateKeeper,
// state_keeper.hpp; docs/deployment.md).
#include <chrono>
#include <cstdio>
#include <string>

#include <CLI/CLI.hpp>

#include "elaslam/common/cli.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/common/log.hpp"
#include "elaslam/robot_node/robot_ports.hpp"
#include "elaslam/robot_node/state_keeper.hpp"
#include "elaslam/transport/incarnation.hpp"
#include "elaslam/transport/node_shell.hpp"
#include "elaslam/transport/process.hpp"
#include "elaslam/transport/service_notify.hpp"

namespace elaslam {
namespace {

struct Args {
  std::string config;
  int robot = 0;
  std::string mode;
  std::string state;
  transport::TransportArgs transport;
  RobotQueues queues;
  double status_period_s = 1.0;
  bool verbose = false;
  bool check = false;
};

/// The configuration file with --mode over it; false (said why) when it is not valid.
bool load(const Args& a, cli::ConfigChoice* cfg, RobotOptions* o, std::string* effective) {
  try {
    *cfg = cli::find_config(a.config);
    *o = load_robot_options(cfg->path, effective);
  } catch (const config::ConfigError& e) {
    log::print(stderr, log::Priority::kErr, "robot_node: %s\n", e.what());
    return false;
  }
  if (!a.mode.empty() && !parse_mode(a.mode, &o->mode)) {
    log::print(stderr, log::Priority::kErr,
               "robot_node: --mode '%s' is not one of ekf, gated, ela, consensus\n", a.mode.c_str());
    return false;
  }
  if (const std::string advice = config_advice(*o); !advice.empty())
    log::print(stderr, log::Priority::kWarning, "robot_node %d: warning: %s\n", a.robot, advice.c_str());
  if (!o->limits.in_team(a.robot)) {  // its own team would refuse every message it sends
    log::print(stderr, log::Priority::kErr, "robot_node: --robot %d is not in robot.limits.team (%s) of %s\n", a.robot,
               team_text(o->limits.team_mask).c_str(), cfg->path.c_str());
    return false;
  }
  return true;
}

int run(const Args& a) {
  cli::ConfigChoice cfg;
  RobotOptions o;
  std::string effective;
  if (!load(a, &cfg, &o, &effective)) return 2;
  if (a.check) {  // e.g. after editing /etc/elaslam/elaslam.yaml, before restarting the service
    std::printf("robot_node %d: %s (%s): valid, mode %s\n", a.robot, cfg.path.c_str(), cfg.origin.c_str(),
                to_string(o.mode));
    if (a.verbose) std::printf("%s\n", effective.c_str());
    std::fflush(stdout);
    return transport::check_transport(a.transport, cfg.path, "robot_node " + std::to_string(a.robot),
                                      static_cast<std::int16_t>(a.robot), true);
  }
  transport::install_stop_handlers();  // before LCM and the start line (process.hpp)
  const std::string name = "robot_node " + std::to_string(a.robot);
  std::string note;
  const std::int64_t incarnation = transport::start_incarnation(a.state, &note);
  int open_rc = 1;  // authenticated when the team's keys are configured (transport/process.hpp)
  transport::AuthInfo auth;  // its mission goes in the state file
  const auto lcm = transport::open_lcm(a.transport, cfg.path, static_cast<std::int16_t>(a.robot), true, incarnation,
                                       name, &open_rc, stderr, &auth);
  if (!lcm) return open_rc;
  transport::ServiceNotifier service;  // systemd's Type=notify and watchdog (service_notify.hpp)
  transport::ShellOptions shell_options(name, a.transport.channel_suffix);
  shell_options.service = &service;
  transport::NodeShell shell(*lcm, shell_options);
  RobotNode node(o, a.robot);
  const bool resumed = resume_state(a.state, incarnation, auth.mission, &node);
  StateKeeper keeper(a.state, o, &node, resumed, incarnation, auth.mission);
  RobotPorts<transport::NodeShell> ports(shell, node);
  if (!ports.open(a.queues)) {
    shell.say("cannot subscribe", log::Priority::kErr);
    return 1;
  }
  std::fprintf(stderr, "%s: %s, config %s (%s), mode=%s lcm=%s, incarnation %lld (%s)\n", name.c_str(),
               cli::version_line("robot_node").c_str(), cfg.path.c_str(), cfg.origin.c_str(), to_string(o.mode),
               transport::describe_url(a.transport.lcm_url).c_str(), static_cast<long long>(incarnation), note.c_str());
  if (a.verbose) std::fprintf(stderr, "%s\n", effective.c_str());
  shell.every(std::chrono::milliseconds(static_cast<int>(a.status_period_s * 1000)), [&] { ports.publish_status(); });
  shell.every(transport::NodeShell::Clock::duration::zero(), [&] { keeper.turn(); });
  const bool transport_failed = shell.spin(100) == transport::NodeShell::Exit::kTransportError;
  if (!a.state.empty()) save_state(a.state, node, auth.mission);  // SIGINT / SIGTERM (and a failed transport): the latest state
  if (!transport_failed) ports.publish_status();
  std::fputs(final_summary(node, ports.stages()).c_str(), stderr);
  return transport_failed ? 1 : 0;
}

}  // namespace
}  // namespace elaslam

int main(int argc, char** argv) {
  return elaslam::cli::guarded_main("robot_node", [&] {
    namespace cli = elaslam::cli;
    elaslam::Args a;
    CLI::App app{"elaslam robot_node: one robot's EKF-SLAM with the ELA gate, on LCM"};
    cli::add_version_flag(app, "robot_node");
    cli::add_config_option(app, &a.config, "its robot: section");
    app.add_option("--robot", a.robot, "this robot's id: 1 to 16, and in robot.limits.team")
        ->required()
        ->check(cli::range(1, elaslam::contract::kMaxRobots));
    app.add_option("--mode", a.mode, "override robot.mode: ekf, gated, ela, consensus");
    app.add_option("--state", a.state, "file to keep this robot's state in (resumed at start, saved atomically)");
    elaslam::transport::add_transport_options(app, &a.transport);
    app.add_option("--sensor-queue", a.queues.sensor, "SENSOR_<R> subscription queue capacity")->check(cli::range(1, 100000));
    app.add_option("--notice-queue", a.queues.notice, "DYNAMIC_NOTICE queue capacity")->check(cli::range(1, 100000));
    app.add_option("--status-period", a.status_period_s, "seconds between STATUS_ROBOT messages")
        ->check(cli::range(0.05, 60.0));
    app.add_flag("--verbose", a.verbose, "print the effective configuration");
    app.add_flag("--check", a.check, "check the configuration, print where it came from and exit (0: valid)");
    if (const int rc = cli::parse(app, argc, argv); rc >= 0) return rc;
    return elaslam::run(a);
  });
}

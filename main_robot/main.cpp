// SPDX-License-Identifier: Apache-2.0
// main_robot: the team's global map, as its own process on LCM.
//   main_robot [--config FILE] [--state PATH] [--lcm-url URL] [--channel-suffix S]
// The config: --config, else $ELASLAM_CONFIG, else /etc/elaslam/elaslam.yaml, else
// the installed default (common/cli.hpp).
// Subscribes LMAP_EVENT(S), LMAP_SNAPSHOT, POSE_<r>; publishes GLOBAL_MAP, DYNAMIC_NOTICE,
// STATUS_MAIN. A thin shell: MainNode on the node shell (MainPorts, main_ports.hpp),
// exactly as the in-process team run runs it. The map is saved to --state, sealed and
// atomically (map_state.hpp), on change at a bounded rate and at shutdown, and
// reloaded at start; a file it refuses is moved aside to PATH.corrupt and main starts
// with an empty map (exit 2 stays for configuration errors: systemd does not restart it).
#include <chrono>
#include <cstdio>
#include <string>

#include <CLI/CLI.hpp>

#include "elaslam/common/cli.hpp"
#include "elaslam/common/log.hpp"
#include "elaslam/main_robot/main_ports.hpp"
#include "elaslam/main_robot/map_state.hpp"
#include "elaslam/transport/auth_transport.hpp"
#include "elaslam/transport/incarnation.hpp"
#include "elaslam/transport/node_shell.hpp"
#include "elaslam/transport/process.hpp"

namespace elaslam {
namespace {

struct Args {
  std::string config;
  std::string state;
  transport::TransportArgs transport;
  MainQueues queues;
  bool check = false;
};

GlobalMapOptions load_options(const std::string& path) {
  config::Document doc = config::Document::from_file(path);
  GlobalMapOptions o = config::read_component<GlobalMapOptions>(doc, "main");
  if (auto problems = check_shared_config(path); !problems.empty()) throw config::ConfigError(path, std::move(problems));
  return o;
}

int run(const Args& a) {
  GlobalMapOptions o;
  cli::ConfigChoice cfg;
  try {
    cfg = cli::find_config(a.config);
    o = load_options(cfg.path);
  } catch (const config::ConfigError& e) {
    log::print(stderr, log::Priority::kErr, "main_robot: %s\n", e.what());
    return 2;
  }
  if (a.check) {  // e.g. after editing /etc/elaslam/elaslam.yaml, before restarting the service
    std::printf("main_robot: %s (%s): valid\n", cfg.path.c_str(), cfg.origin.c_str());
    std::fflush(stdout);
    return transport::check_transport(a.transport, cfg.path, "main_robot", transport::kSenderMain, true);
  }
  transport::install_stop_handlers();  // before LCM and the start line (process.hpp)
  std::string note;
  const std::int64_t incarnation = transport::start_incarnation(a.state, &note);  // a later start: a larger one
  int open_rc = 1;  // authenticated when the team's keys are configured (transport/process.hpp)
  transport::AuthInfo auth;  // the state file sealed with the node's key of this mission, when it signs
  const auto lcm = transport::open_lcm(a.transport, cfg.path, transport::kSenderMain, true, incarnation, "main_robot",
                                       &open_rc, stderr, &auth);
  if (!lcm) return open_rc;
  transport::ServiceNotifier service;  // systemd's Type=notify and watchdog (service_notify.hpp)
  transport::ShellOptions shell_options("main_robot", a.transport.channel_suffix);
  shell_options.service = &service;
  transport::NodeShell shell(*lcm, shell_options);
  MainNode node(o);
  node.set_incarnation(incarnation);
  MainPorts<transport::NodeShell> ports(shell, node);
  // Keyed with the node's own key of this mission: an edited file, or one of another
  // mission, does not verify (docs/security.md "main_robot's state file").
  const StateKey* state_key = auth.signs ? &auth.file_key : nullptr;
  if (!a.state.empty()) {
    const MapStateLoad loaded = load_map_state(a.state, state_key, &node.map());
    log::print(stderr, loaded.outcome == MapStateOutcome::kFreshAfterDamage ? log::Priority::kWarning : log::Priority::kInfo,
               "main_robot: %s\n", loaded.line.c_str());
    if (loaded.outcome == MapStateOutcome::kFreshAfterDamage) node.count_state_damaged();
  }
  const auto save_state = [&] {  // a failure: FAULT_SAVE_FAILED in STATUS, said at the first of a series
    std::string why;
    node.note_save(save_map_state(a.state, node.map(), state_key, &why), a.state + ": " + why);
    if (const std::string alert = node.take_alert(); !alert.empty())
      log::print(stderr, log::Priority::kWarning, "main_robot: %s\n", alert.c_str());
  };
  if (!ports.open(a.queues)) {
    shell.say("cannot subscribe", log::Priority::kErr);
    return 1;
  }
  std::fprintf(stderr, "main_robot: %s, config %s (%s), lcm=%s\n", cli::version_line("main_robot").c_str(),
               cfg.path.c_str(), cfg.origin.c_str(), transport::describe_url(a.transport.lcm_url).c_str());
  using Clock = transport::NodeShell::Clock;
  const auto map_period_us = static_cast<std::int64_t>(1e6 / o.publish_rate_hz);
  shell.every(std::chrono::microseconds(map_period_us), [&] { ports.publish_map_if_quiet(map_period_us); });
  shell.every(std::chrono::seconds(1), [&] { ports.publish_status(); });
  const auto save_period = std::chrono::milliseconds(static_cast<std::int64_t>(o.state_save_interval_s * 1000));
  auto next_save = Clock::now();
  std::int64_t saved_version = node.map().version();
  shell.every(Clock::duration::zero(), [&] {  // each turn: saved on change, at most once a save_period
    const auto now = Clock::now();
    if (a.state.empty() || now < next_save || node.map().version() == saved_version) return;
    save_state();
    saved_version = node.map().version();
    next_save = now + save_period;
  });
  shell.spin(5);  // a transport failure is logged; the map is still published and saved
  ports.publish_map();
  ports.publish_status();
  if (!a.state.empty()) save_state();
  std::fputs(final_summary(node).c_str(), stderr);
  return 0;
}

}  // namespace
}  // namespace elaslam

int main(int argc, char** argv) {
  return elaslam::cli::guarded_main("main_robot", [&] {
    namespace cli = elaslam::cli;
    elaslam::Args a;
    CLI::App app{"elaslam main_robot: the team's global map, on LCM"};
    cli::add_version_flag(app, "main_robot");
    cli::add_config_option(app, &a.config, "its main: section");
    app.add_option("--state", a.state, "file to persist the global map in (reloaded at start)");
    elaslam::transport::add_transport_options(app, &a.transport);
    app.add_option("--event-queue", a.queues.event, "LMAP_EVENT subscription queue capacity")
        ->check(cli::range(1, 1000000));
    app.add_option("--events-queue", a.queues.events, "LMAP_EVENTS subscription queue capacity")
        ->check(cli::range(1, 1000000));
    app.add_flag("--check", a.check, "check the configuration, print where it came from and exit (0: valid)");
    if (const int rc = cli::parse(app, argc, argv); rc >= 0) return rc;
    return elaslam::run(a);
  });
}

// SPDX-License-Identifier: Apache-2.0
// simulator: the world of the paper's experiment as an LCM node (docs/design.md sections
// 1 and 6). Publishes SENSOR_<r> for every robot and GROUND_TRUTH at F frames/s on
// absolute deadlines, STATUS_SIM and RUN_INFO (what the run is: scenario, seed,
// dynamism, speed, rate, effective config) before the first frame and about once a
// second; with --lockstep it waits after each frame for every robot's POSE_<r> of
// that frame (bounded by a timeout). A thin shell: the scenario and the command line
// here, the node in the library (sim_node.hpp: scheduler, lockstep).
//
// Exit codes: 0 done (also after SIGINT/SIGTERM), 1 runtime failure (LCM),
// 2 bad command line or configuration.
#include <cstdio>
#include <iostream>
#include <string>

#include <CLI/CLI.hpp>

#include "elaslam/common/cli.hpp"
#include "elaslam/common/config.hpp"
#include "elaslam/simulator/scenario.hpp"
#include "elaslam/simulator/sim_node.hpp"
#include "elaslam/transport/auth_transport.hpp"
#include "elaslam/transport/node_shell.hpp"
#include "elaslam/transport/incarnation.hpp"
#include "elaslam/transport/incarnation.hpp"
#include "elaslam/transport/process.hpp"

namespace {

using elaslam::sim::ScenarioOptions;

struct Args {
  std::string config;  // as given (--config), "" when not
  elaslam::cli::ConfigChoice config_choice;
  elaslam::transport::TransportArgs transport;
  elaslam::sim::SimRunOptions run;
  double rate_hz = 0.0;
  int frames = 0;
  double dynamism_percent = 0.0;
  double speed_mps = 0.0;
  int seed = 0;
  bool list_robots = false;
  bool check = false;
  CLI::Option *rate = nullptr, *frames_opt = nullptr, *dynamism = nullptr, *speed = nullptr, *seed_opt = nullptr;
};

void add_options(CLI::App& app, Args* a) {
  namespace lim = elaslam::sim::limits;
  using elaslam::cli::range;
  elaslam::cli::add_version_flag(app, "simulator");
  elaslam::cli::add_config_option(app, &a->config, "its scenario: section");
  app.add_option("--team-mode", a->run.team_mode, "the robots' mode, recorded in RUN_INFO (the simulator has none)")
      ->check(CLI::IsMember({"ekf", "gated", "ela", "consensus"}));
  a->rate = app.add_option("--rate", a->rate_hz, "override scenario.rate_hz [frames/s]")
                ->check(range(lim::kRateMinHz, lim::kRateMaxHz));
  a->frames_opt = app.add_option("--frames", a->frames, "override scenario.frames")->check(range(1, lim::kFramesMax));
  a->dynamism = app.add_option("--dynamism", a->dynamism_percent, "override scenario.dynamism_percent [%]")
                    ->check(range(0.0, lim::kDynamismMaxPercent));
  a->speed = app.add_option("--speed", a->speed_mps, "override scenario.landmark_speed_mps [m/s]")
                 ->check(range(0.0, lim::kLandmarkSpeedMaxMps));
  a->seed_opt = app.add_option("--seed", a->seed, "override scenario.seed")->check(range(0, lim::kSeedMax));
  app.add_flag("--lockstep", a->run.lockstep, "after each frame wait for every robot's POSE_<r> of that frame");
  app.add_option("--lockstep-timeout-ms", a->run.lockstep_timeout_ms, "lockstep wait bound per frame [ms]")
      ->capture_default_str()
      ->check(range(1, 3600000));
  elaslam::transport::add_transport_options(app, &a->transport);
  app.add_option("--wait-for-nodes", a->run.wait_for_nodes,
                 "before frame 0, wait until this many nodes announced themselves on STATUS_* (robots + main)")
      ->check(range(0, 64));
  app.add_option("--wait-timeout-ms", a->run.wait_timeout_ms, "bound of --wait-for-nodes [ms]")->check(range(1, 600000));
  app.add_flag("--list-robots", a->list_robots, "print the scenario's robot ids (one line) and exit");
  app.add_flag("--check", a->check, "check the configuration with the overrides, print the scenario and exit (0: valid)");
  app.add_option("--start-delay-ms", a->run.start_delay_ms, "wait before frame 0 so subscribers can join [ms]")
      ->capture_default_str()
      ->check(range(0, 3600000));
}

/// Load the scenario and apply the command-line overrides; false (said why) on error.
bool load(Args* a, ScenarioOptions* o) {
  try {
    a->config_choice = elaslam::cli::find_config(a->config);
    a->run.config_path = a->config_choice.path;
    *o = elaslam::sim::load_scenario(a->run.config_path, &a->run.effective_yaml);
  } catch (const elaslam::config::ConfigError& e) {
    std::cerr << "simulator: " << e.what() << "\n";
    return false;
  }
  if (a->rate->count() > 0) o->rate_hz = a->rate_hz;
  if (a->frames_opt->count() > 0) o->frames = a->frames;
  if (a->dynamism->count() > 0) o->dynamism_percent = a->dynamism_percent;
  if (a->speed->count() > 0) o->landmark_speed_mps = a->speed_mps;
  if (a->seed_opt->count() > 0) o->seed = a->seed;
  const auto problems = elaslam::sim::check_scenario(*o);
  for (const auto& p : problems)
    std::cerr << "simulator: " << a->run.config_path << " with command-line overrides: scenario." << p.key << ": "
              << p.what << "\n";
  return problems.empty();
}

int run(const Args& a, const ScenarioOptions& o) {
  namespace transport = elaslam::transport;
  int open_rc = 1;  // authenticated when the team's keys are configured (transport/process.hpp)
  const auto lcm = transport::open_lcm(a.transport, a.run.config_path, transport::kSenderSimulator, true,
                                       transport::start_incarnation(""), "simulator", &open_rc);
  if (!lcm) return open_rc;
  const std::string& suffix = a.transport.channel_suffix;
  std::cerr << elaslam::cli::version_line("simulator") << ", config " << a.run.config_path << " ("
            << a.config_choice.origin << ")\n"
            << elaslam::sim::describe(o) << "simulator: lcm " << transport::describe_url(a.transport.lcm_url)
            << (suffix.empty() ? "" : ", channel suffix " + suffix)
            << (a.run.lockstep ? ", lockstep (timeout " + std::to_string(a.run.lockstep_timeout_ms) + " ms)"
                               : ", free running")
            << ", start delay " << a.run.start_delay_ms << " ms\n";
  transport::ServiceNotifier service;  // systemd's Type=notify and watchdog (service_notify.hpp)
  transport::ShellOptions shell_options("simulator", suffix);
  shell_options.service = &service;
  transport::NodeShell shell(*lcm, shell_options);
  return elaslam::sim::run_simulator(shell, o, a.run);
}

int simulator_main(int argc, char** argv) {
  Args args;
  CLI::App app{"elaslam simulator: publishes SENSOR_<r> and GROUND_TRUTH for the configured scenario"};
  add_options(app, &args);
  if (const int rc = elaslam::cli::parse(app, argc, argv); rc >= 0) return rc;
  ScenarioOptions options;
  if (!load(&args, &options)) return elaslam::cli::kExitBadInput;
  if (args.check) {
    std::cout << "simulator: " << args.run.config_path << " (" << args.config_choice.origin << "): valid\n"
              << elaslam::sim::describe(options) << std::flush;
    return elaslam::transport::check_transport(args.transport, args.run.config_path, "simulator",
                                               elaslam::transport::kSenderSimulator, true);
  }
  if (args.list_robots) {
    for (std::size_t i = 0; i < options.robots.size(); ++i) std::printf("%s%d", i ? " " : "", options.robots[i].id);
    std::printf("\n");
    return 0;
  }
  elaslam::transport::install_stop_handlers();
  return run(args, options);
}

}  // namespace

int main(int argc, char** argv) {
  return elaslam::cli::guarded_main("simulator", [&] { return simulator_main(argc, argv); });
}

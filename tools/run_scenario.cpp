// SPDX-License-Identifier: Apache-2.0
// run_scenario: one in-process run of the whole team (simulator + robots + main),
// its metrics against ground truth, and its output files.
//   run_scenario [--config FILE] [--mode M] [--dynamism P] [--speed V] [--seed S]
//                [--rate F] [--frames N] [--baseline M] [--oracle] [--check] [--out DIR]
// --baseline M also runs mode M on the same scenario and seed and prints the two
// side by side (metrics.json gets it under "baseline").
#include <chrono>
#include <cstdio>
#include <iostream>

#include <CLI/CLI.hpp>

#include "elaslam/common/cli.hpp"
#include "elaslam/eval/report.hpp"
#include "elaslam/team/baseline.hpp"
#include "elaslam/team/team_run.hpp"

namespace {

using namespace elaslam;

struct Args {
  std::string config_path, mode, baseline, out_dir;
  double dynamism = 0.0, speed = 0.0, rate = 0.0;
  int seed = 0, frames = 0;
  bool oracle = false, check = false;
  RunOverrides overrides;  // the options given (their count), filled by parse_args
};

/// -1 to go on, else the exit code.
int parse_args(int argc, char** argv, Args* a) {
  namespace lim = sim::limits;
  CLI::App app{"elaslam run_scenario: one in-process team run and its metrics"};
  cli::add_version_flag(app, "run_scenario");
  cli::add_config_option(app, &a->config_path, "its scenario:, robot: and main: sections");
  app.add_option("--mode", a->mode, "ekf, gated, ela or consensus (default: robot.mode)")
      ->check(CLI::IsMember({"ekf", "gated", "ela", "consensus"}));
  auto* dyn = app.add_option("--dynamism", a->dynamism, "percent of landmarks that move")
                  ->check(cli::range(0.0, lim::kDynamismMaxPercent));
  auto* speed =
      app.add_option("--speed", a->speed, "landmark speed [m/s]")->check(cli::range(0.0, lim::kLandmarkSpeedMaxMps));
  auto* seed = app.add_option("--seed", a->seed, "master seed")->check(cli::range(0, lim::kSeedMax));
  auto* rate = app.add_option("--rate", a->rate, "frames per second (scenario.rate_hz; motion per frame changes with it)")
                   ->check(cli::range(lim::kRateMinHz, lim::kRateMaxHz));
  auto* frames =
      app.add_option("--frames", a->frames, "frames to run (scenario.frames)")->check(cli::range(1, lim::kFramesMax));
  app.add_option("--baseline", a->baseline, "also run this mode on the same scenario and seed, and compare")
      ->check(CLI::IsMember({"ekf", "gated", "ela", "consensus"}));
  app.add_option("--out", a->out_dir, "directory for metrics.json, frames.csv, trajectories/");
  app.add_flag("--oracle", a->oracle,
               "evaluation bound: observations of truly moving landmarks are removed before the robots see them");
  app.add_flag("--check", a->check, "check the configuration with the overrides and exit (0: valid); runs nothing");
  if (const int rc = cli::parse(app, argc, argv); rc >= 0) return rc;
  RunOverrides& ov = a->overrides;
  Mode m;
  if (!a->mode.empty() && parse_mode(a->mode, &m)) ov.mode = m;
  if (dyn->count()) ov.dynamism_percent = a->dynamism;
  if (speed->count()) ov.landmark_speed_mps = a->speed;
  if (seed->count()) ov.seed = a->seed;
  if (rate->count()) ov.rate_hz = a->rate;
  if (frames->count()) ov.frames = a->frames;
  return -1;
}

int run_scenario_main(int argc, char** argv) {
  Args a;
  if (const int rc = parse_args(argc, argv, &a); rc >= 0) return rc;
  // A bad config (ConfigError) or override (std::invalid_argument) exits 2 with the
  // reason, through guarded_main.
  a.config_path = cli::find_config(a.config_path).path;
  TeamConfig cfg = apply_overrides(load_team_config(a.config_path), a.overrides);
  cfg.oracle = a.oracle;
  if (a.check) {
    std::cout << "run_scenario: " << a.config_path << ": valid\n";
    return 0;
  }
  const auto t0 = std::chrono::steady_clock::now();
  const RunResult r = run_team(cfg);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();

  const std::string command = cli::command_line(argc, argv);
  const RunInfo info{to_string(cfg.robot.mode), cfg.scenario.dynamism_percent, cfg.scenario.landmark_speed_mps,
                     cfg.scenario.seed,         a.config_path,                  cfg.effective_yaml,
                     command};
  print_summary(std::cout, info, r);
  std::cout << "  run time: " << ms << " ms (" << r.bus_messages << " messages on the in-process bus)\n";
  nlohmann::json metrics = metrics_json(info, r);
  if (!a.baseline.empty())  // the same scenario and seed with the baseline's mode
    metrics["baseline"] = run_baseline(cfg, a.config_path, a.baseline, info, r, &std::cout);
  if (!a.out_dir.empty()) {
    try {
      write_outputs(a.out_dir, metrics, r);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "run_scenario: %s\n", e.what());
      return cli::kExitFailure;
    }
    std::cout << "  wrote " << a.out_dir << "/metrics.json, frames.csv, map.csv, trajectories/\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return cli::guarded_main("run_scenario", [&] { return run_scenario_main(argc, argv); });
}

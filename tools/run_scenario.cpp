// run_scenario: one in-process run of the whole team (simulator + robots + main),
// its metrics against ground truth, and its output files.
//   run_scenario [--config FILE] [--mode M] [--dynamism P] [--speed V] [--seed S]
//                [--rate F] [--frames N] [--baseline M] [--oracle] [--out DIR]
// --baseline M also runs mode M on the same scenario and seed and prints the two
// side by side (metrics.json gets it under "baseline").
#include <chrono>
#include <cstdio>
#include <iostream>

#include <CLI/CLI.hpp>

#include "elaslam/common/cli.hpp"
#include "elaslam/team/report.hpp"
#include "elaslam/team/team_run.hpp"

namespace {

using namespace elaslam;

struct Args {
  std::string config_path, mode, baseline, out_dir;
  double dynamism = -1.0, speed = -1.0, rate = -1.0;
  long long seed = -1;
  int frames = -1;
  bool oracle = false;
};

/// -1 to go on, else the exit code.
int parse_args(int argc, char** argv, Args* a) {
  CLI::App app{"elaslam run_scenario: one in-process team run and its metrics"};
  cli::add_version_flag(app, "run_scenario");
  cli::add_config_option(app, &a->config_path, "its scenario:, robot: and main: sections");
  app.add_option("--mode", a->mode, "ekf, gated, ela or consensus (default: robot.mode)")
      ->check(CLI::IsMember({"ekf", "gated", "ela", "consensus"}));
  app.add_option("--dynamism", a->dynamism, "percent of landmarks that move")->check(CLI::Range(0.0, 100.0));
  app.add_option("--speed", a->speed, "landmark speed [m/s]")->check(CLI::Range(0.0, 100.0));
  app.add_option("--seed", a->seed, "master seed")->check(CLI::Range(0LL, 2147483647LL));
  app.add_option("--rate", a->rate, "frames per second (scenario.rate_hz; motion per frame changes with it)")
      ->check(CLI::Range(1e-3, 100000.0));
  app.add_option("--frames", a->frames, "frames to run (scenario.frames)")->check(CLI::Range(1, 100000000));
  app.add_option("--baseline", a->baseline, "also run this mode on the same scenario and seed, and compare")
      ->check(CLI::IsMember({"ekf", "gated", "ela", "consensus"}));
  app.add_option("--out", a->out_dir, "directory for metrics.json, frames.csv, trajectories/");
  app.add_flag("--oracle", a->oracle,
               "evaluation bound: observations of truly moving landmarks are removed before the robots see them");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  return -1;
}

/// The config with the overrides; false (the reason printed) when it cannot run.
bool configure(Args* a, TeamConfig* cfg) {
  try {
    a->config_path = cli::find_config(a->config_path).path;
    *cfg = load_team_config(a->config_path);
    RunOverrides ov;
    Mode m;
    if (!a->mode.empty() && parse_mode(a->mode, &m)) ov.mode = m;
    if (a->dynamism >= 0.0) ov.dynamism_percent = a->dynamism;
    if (a->speed >= 0.0) ov.landmark_speed_mps = a->speed;
    if (a->seed >= 0) ov.seed = static_cast<int>(a->seed);
    if (a->rate > 0.0) ov.rate_hz = a->rate;
    if (a->frames > 0) ov.frames = a->frames;
    *cfg = apply_overrides(*cfg, ov);
  } catch (const config::ConfigError& e) {
    std::fprintf(stderr, "run_scenario: %s\n", e.what());
    return false;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "run_scenario: %s\n", e.what());
    return false;
  }
  cfg->oracle = a->oracle;
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Args a;
  if (const int rc = parse_args(argc, argv, &a); rc >= 0) return rc;
  TeamConfig cfg;
  if (!configure(&a, &cfg)) return 2;
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
      return 1;
    }
    std::cout << "  wrote " << a.out_dir << "/metrics.json, frames.csv, map.csv, trajectories/\n";
  }
  return 0;
}

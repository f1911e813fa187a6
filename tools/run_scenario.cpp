// run_scenario: one in-process run of the whole team (simulator + robots + main),
// its metrics against ground truth, and its output files.
//   run_scenario --config FILE [--mode M] [--dynamism P] [--speed V] [--seed S] [--out DIR]
#include <chrono>
#include <cstdio>
#include <iostream>

#include <CLI/CLI.hpp>

#include "elaslam/team/report.hpp"
#include "elaslam/team/team_run.hpp"

int main(int argc, char** argv) {
  using namespace elaslam;
  std::string config_path = "config/paper.yaml", mode, out_dir;
  double dynamism = -1.0, speed = -1.0;
  long long seed = -1;
  CLI::App app{"elaslam run_scenario: one in-process team run and its metrics"};
  app.add_option("--config", config_path, "YAML config (scenario, robot, main sections)")->check(CLI::ExistingFile);
  app.add_option("--mode", mode, "ekf, gated, ela or consensus (default: robot.mode)")
      ->check(CLI::IsMember({"ekf", "gated", "ela", "consensus"}));
  app.add_option("--dynamism", dynamism, "percent of landmarks that move")->check(CLI::Range(0.0, 100.0));
  app.add_option("--speed", speed, "landmark speed [m/s]")->check(CLI::Range(0.0, 100.0));
  app.add_option("--seed", seed, "master seed")->check(CLI::Range(0LL, 2147483647LL));
  app.add_option("--out", out_dir, "directory for metrics.json, frames.csv, trajectories/");
  bool oracle = false;
  app.add_flag("--oracle", oracle,
               "evaluation bound: observations of truly moving landmarks are removed before the robots see them");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  TeamConfig cfg;
  try {
    cfg = load_team_config(config_path);
  } catch (const config::ConfigError& e) {
    std::fprintf(stderr, "run_scenario: %s\n", e.what());
    return 2;
  }
  RunOverrides ov;
  Mode m;
  if (!mode.empty() && parse_mode(mode, &m)) ov.mode = m;
  if (dynamism >= 0.0) ov.dynamism_percent = dynamism;
  if (speed >= 0.0) ov.landmark_speed_mps = speed;
  if (seed >= 0) ov.seed = static_cast<int>(seed);
  cfg = apply_overrides(cfg, ov);
  cfg.oracle = oracle;

  const auto t0 = std::chrono::steady_clock::now();
  const RunResult r = run_team(cfg);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();

  RunInfo info{to_string(cfg.robot.mode), cfg.scenario.dynamism_percent, cfg.scenario.landmark_speed_mps,
               cfg.scenario.seed, config_path, cfg.effective_yaml};
  print_summary(std::cout, info, r);
  std::cout << "  run time: " << ms << " ms (" << r.bus_messages << " messages on the in-process bus)\n";
  if (!out_dir.empty()) {
    try {
      write_outputs(out_dir, metrics_json(info, r), r);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "run_scenario: %s\n", e.what());
      return 1;
    }
    std::cout << "  wrote " << out_dir << "/metrics.json, frames.csv, map.csv, trajectories/\n";
  }
  return 0;
}

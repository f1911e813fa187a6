// SPDX-License-Identifier: Apache-2.0
// sweep: the paper's experiment grid (section 4, Tables 1-4, Figs 5-8) through the
// in-process team run, in parallel, with our modes beside the paper's.
//   sweep --config FILE [--modes ekf,gated,ela,consensus] [--dynamism 5,20,35,50,65,80]
//         [--speed 0.1,0.3,0.5,0.7,0.9] [--runs 10] [--seed-base S] [--jobs J] --out DIR [--no-plots] [--check]
// Run r of every cell and mode uses seed seed_base + r: every mode sees the same
// worlds, so differences between modes are the methods', not the draws'. Results
// are stored by job index, so the files are identical whatever J. The grid, its
// runs and its files are team/sweep.hpp's.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>

#include <CLI/CLI.hpp>

#include "elaslam/common/cli.hpp"
#include "elaslam/eval/report.hpp"
#include "elaslam/team/sweep.hpp"

namespace elaslam {
namespace {

void progress(std::size_t done, std::size_t total, double elapsed_s) {
  const double left = done ? elapsed_s / static_cast<double>(done) * static_cast<double>(total - done) : 0.0;
  if (isatty(STDERR_FILENO)) {
    const int width = 40, filled = static_cast<int>(width * done / total);
    std::fprintf(stderr, "\r[%s%s] %zu/%zu runs, %.0f s left ", std::string(static_cast<std::size_t>(filled), '#').c_str(),
                 std::string(static_cast<std::size_t>(width - filled), '.').c_str(), done, total, left);
    if (done == total) std::fprintf(stderr, "\n");
  } else if (done == total || (done * 10 / total) != ((done - 1) * 10 / total)) {
    std::fprintf(stderr, "sweep: %zu/%zu runs, %.0f s left\n", done, total, left);
  }
}

struct Args {
  std::string config_path, out_dir, modes_text = "ekf,gated,ela,consensus";
  std::string dyn_text = "5,20,35,50,65,80", speed_text = "0.1,0.3,0.5,0.7,0.9";
  int runs = 10, seed_base = 1, jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  bool no_plots = false, oracle = false, check = false;
};

/// -1 to go on, else the exit code.
int parse_args(int argc, char** argv, Args* a) {
  CLI::App app{"elaslam sweep: the paper's experiment grid, in parallel"};
  cli::add_version_flag(app, "sweep");
  cli::add_config_option(app, &a->config_path, "its scenario:, robot: and main: sections");
  app.add_option("--modes", a->modes_text, "comma-separated modes");
  app.add_option("--dynamism", a->dyn_text, "comma-separated dynamism levels [%]");
  app.add_option("--speed", a->speed_text, "comma-separated landmark speeds [m/s]");
  app.add_option("--runs", a->runs, "runs per cell")->check(cli::range(1, 100000));
  app.add_option("--seed-base", a->seed_base, "seed of run 0 (run r: seed_base + r)")->check(cli::range(0, 1 << 30));
  app.add_option("--jobs", a->jobs, "threads (default: all cores)")->check(cli::range(1, 1024));
  app.add_option("--out", a->out_dir, "output directory")->required();
  app.add_flag("--no-plots", a->no_plots, "do not call tools/plot_sweep.py");
  app.add_flag("--oracle", a->oracle,
               "evaluation bound: observations of truly moving landmarks are removed before the robots see them");
  app.add_flag("--check", a->check, "check the configuration and the grid and exit (0: valid); runs nothing");
  return cli::parse(app, argc, argv);
}

// One map like the paper's Fig 4 (map_run says which run), with its output files.
void write_map(const Args& a, const SweepGrid& grid, const TeamConfig& base, const std::string& command) {
  const RunOverrides o = map_run(grid, a.seed_base);
  const TeamConfig c = apply_overrides(base, o);
  const RunResult r = run_team(c);
  RunInfo info{to_string(*o.mode), c.scenario.dynamism_percent, c.scenario.landmark_speed_mps, a.seed_base,
               a.config_path, c.effective_yaml, command};
  write_outputs(a.out_dir + "/maps/" + to_string(*o.mode), metrics_json(info, r), r);
}

void plot(const std::string& out_dir) {
  const std::string script = cli::python_tool("plot_sweep.py");
  std::fflush(stdout);
  if (!std::filesystem::exists(script)) {
    std::fprintf(stderr, "sweep: no %s: no plots\n", script.c_str());
    return;
  }
  const std::string cmd = "'" + script + "' '" + out_dir + "'";
  if (std::system(cmd.c_str()) != 0) std::fprintf(stderr, "sweep: plotting failed (%s)\n", cmd.c_str());
}

int sweep_main(int argc, char** argv) {
  Args a;
  if (const int rc = parse_args(argc, argv, &a); rc >= 0) return rc;
  // A bad list, config or grid throws (std::invalid_argument, ConfigError): exit 2
  // with the reason, through guarded_main.
  SweepGrid grid = make_grid(a.modes_text, a.dyn_text, a.speed_text, a.runs);
  a.config_path = cli::find_config(a.config_path).path;
  TeamConfig base = load_team_config(a.config_path);
  base.oracle = a.oracle;
  grid.oracle = a.oracle;
  check_grid(base, grid);  // every cell's scenario must run (a speed too fast for the rate)
  if (a.check) {
    std::printf("sweep: %s: valid\n", a.config_path.c_str());
    return 0;
  }
  for (const auto& r : base.scenario.robots) grid.robot_ids.push_back(r.id);
  const std::vector<SweepJob> job_list = make_jobs(grid, a.seed_base);
  std::fprintf(stderr, "sweep: %zu runs (%zu modes x %zu x %zu cells x %d runs) on %d threads\n", job_list.size(),
               grid.modes.size(), grid.dynamism.size(), grid.speed.size(), a.runs, a.jobs);
  const auto t0 = std::chrono::steady_clock::now();
  const auto seconds = [&t0] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  std::vector<SweepResult> results;
  run_sweep(base, job_list, a.jobs, &results, [&](std::size_t d, std::size_t n) { progress(d, n, seconds()); });
  const double wall = seconds();
  try {
    write_sweep(a.out_dir, grid, job_list, results);
    write_map(a, grid, base, cli::command_line(argc, argv));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sweep: %s\n", e.what());
    return cli::kExitFailure;
  }
  std::printf("sweep: %zu runs in %.1f s (%.1f runs/s); tables: %s/tables.md\n", job_list.size(), wall,
              static_cast<double>(job_list.size()) / wall, a.out_dir.c_str());
  if (!a.no_plots) plot(a.out_dir);
  return 0;
}

}  // namespace
}  // namespace elaslam

int main(int argc, char** argv) {
  return elaslam::cli::guarded_main("sweep", [&] { return elaslam::sweep_main(argc, argv); });
}

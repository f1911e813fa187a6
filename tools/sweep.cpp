// SPDX-License-Identifier: Apache-2.0
// sweep: the paper's experiment grid (section 4, Tables 1-4, Figs 5-8) through the
// in-process team run, in parallel, with our modes beside the paper's.
//   sweep --config FILE [--modes ekf,gated,ela,consensus] [--dynamism 5,20,35,50,65,80]
//         [--speed 0.1,0.3,0.5,0.7,0.9] [--runs 10] [--seed-base S] [--jobs J] --out DIR [--no-plots] [--check]
// Run r of every cell and mode uses seed seed_base + r: every mode sees the same
// worlds, so differences between modes are the methods', not the draws'. Results
// are stored by job index, so the files are identical whatever J.
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <exception>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <sstream>
#include <thread>

#include <CLI/CLI.hpp>

#include "elaslam/common/cli.hpp"
#include "elaslam/eval/report.hpp"
#include "elaslam/team/team_run.hpp"
#include "sweep_tables.hpp"

namespace elaslam {
namespace {

/// A comma-separated list of numbers, each finite and in [lo, hi]; throws
/// std::invalid_argument naming the option (`what`) and the item.
std::vector<double> parse_list(const std::string& text, const char* what, double lo, double hi) {
  std::vector<double> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    std::size_t pos = 0;
    double x = 0.0;
    try {
      x = std::stod(item, &pos);
    } catch (const std::out_of_range&) {  // beyond a double: as good as inf
      x = HUGE_VAL;
      pos = item.size();
    } catch (const std::exception&) {
      pos = 0;
    }
    const std::string where = std::string(what) + ": '" + item + "'";
    if (pos == 0 || pos != item.size()) throw std::invalid_argument(where + " is not a number");
    if (!std::isfinite(x)) throw std::invalid_argument(where + " is not a finite number");
    if (!(x >= lo && x <= hi)) {
      std::ostringstream range;
      range << "[" << lo << ", " << hi << "]";
      throw std::invalid_argument(where + " is out of range: expected a number in " + range.str());
    }
    v.push_back(x);
  }
  if (v.empty()) throw std::invalid_argument(std::string(what) + ": empty list");
  return v;
}

std::vector<Mode> parse_modes(const std::string& text) {
  std::vector<Mode> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    Mode m;
    if (!parse_mode(item, &m)) throw std::invalid_argument("--modes: '" + item + "' is not ekf, gated, ela or consensus");
    v.push_back(m);
  }
  if (v.empty()) throw std::invalid_argument("--modes: empty list");
  return v;
}

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

// Run every job on `jobs` threads; results land at their job's index.
void run_all(const TeamConfig& base, const std::vector<SweepJob>& jobs, int threads, std::vector<SweepResult>* out) {
  out->assign(jobs.size(), SweepResult{});
  std::atomic<std::size_t> next{0}, done{0};
  std::mutex report;
  const auto t0 = std::chrono::steady_clock::now();
  std::exception_ptr failure;  // the first exception of any worker, rethrown after the join
  auto worker = [&] {
    try {
      for (std::size_t i = next++; i < jobs.size(); i = next++) {
        const SweepJob& j = jobs[i];
        RunOverrides o;
        o.mode = j.mode;
        o.dynamism_percent = j.dynamism;
        o.landmark_speed_mps = j.speed;
        o.seed = j.seed;
        const RunResult r = run_team(apply_overrides(base, o));
        (*out)[i] = summarise(r);
        const std::size_t d = ++done;
        std::lock_guard<std::mutex> lock(report);
        progress(d, jobs.size(), std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      }
    } catch (...) {  // escaping a thread would std::terminate the process
      std::lock_guard<std::mutex> lock(report);
      if (!failure) failure = std::current_exception();
      next = jobs.size();
    }
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
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

// One map like the paper's Fig 4: the middle cell's first run, in ela when the grid
// has it, else in its first mode.
void write_map(const Args& a, const SweepGrid& grid, const TeamConfig& base, const std::string& command) {
  Mode map_mode = grid.modes.front();
  for (Mode m : grid.modes)
    if (m == Mode::kEla) map_mode = m;
  RunOverrides o;
  o.mode = map_mode;
  o.dynamism_percent = grid.dynamism[grid.dynamism.size() / 2];
  o.landmark_speed_mps = grid.speed[grid.speed.size() / 2];
  o.seed = a.seed_base;
  const TeamConfig c = apply_overrides(base, o);
  const RunResult r = run_team(c);
  RunInfo info{to_string(map_mode), c.scenario.dynamism_percent, c.scenario.landmark_speed_mps, a.seed_base,
               a.config_path, c.effective_yaml, command};
  write_outputs(a.out_dir + "/maps/" + to_string(map_mode), metrics_json(info, r), r);
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
  SweepGrid grid;
  grid.modes = parse_modes(a.modes_text);
  grid.dynamism = parse_list(a.dyn_text, "--dynamism", 0.0, sim::limits::kDynamismMaxPercent);
  grid.speed = parse_list(a.speed_text, "--speed", 0.0, sim::limits::kLandmarkSpeedMaxMps);
  grid.runs = a.runs;
  a.config_path = cli::find_config(a.config_path).path;
  TeamConfig base = load_team_config(a.config_path);
  base.oracle = a.oracle;
  grid.oracle = a.oracle;
  for (double d : grid.dynamism)  // every cell's scenario must run (a speed too fast for the rate)
    for (double v : grid.speed) {
      RunOverrides o;
      o.dynamism_percent = d;
      o.landmark_speed_mps = v;
      apply_overrides(base, o);
    }
  if (a.check) {
    std::printf("sweep: %s: valid\n", a.config_path.c_str());
    return 0;
  }
  grid.robot_ids.clear();
  for (const auto& r : base.scenario.robots) grid.robot_ids.push_back(r.id);
  const std::vector<SweepJob> job_list = make_jobs(grid, a.seed_base);
  std::fprintf(stderr, "sweep: %zu runs (%zu modes x %zu x %zu cells x %d runs) on %d threads\n", job_list.size(),
               grid.modes.size(), grid.dynamism.size(), grid.speed.size(), a.runs, a.jobs);
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<SweepResult> results;
  run_all(base, job_list, a.jobs, &results);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
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

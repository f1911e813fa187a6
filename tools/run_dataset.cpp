// SPDX-License-Identifier: Apache-2.0
// run_dataset: the team on a recorded UTIAS MRCLAM dataset instead of the
// simulator (in-process, like run_scenario), its metrics against Vicon ground
// truth and its output files.
//   run_dataset --dataset DIR [--config FILE] [--mode M] [--with-robot-barcodes]
//               [--robots 1,2,3] [--rate F] [--start S] [--duration T] [--check] --out DIR
//   run_dataset --dataset DIR --report [--modes ekf,gated,ela,consensus] --out DIR
// --report runs dead reckoning and every mode without and with the robots'
// barcodes (in parallel) and writes DIR/report.md, DIR/report.json and each run's
// files under DIR/<mode>/ and DIR/<mode>_barcodes/. The runs and their files are
// team/dataset_report.hpp's.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <thread>

#include <CLI/CLI.hpp>

#include "elaslam/common/cli.hpp"
#include "elaslam/dataset/cli_overrides.hpp"
#include "elaslam/team/dataset_report.hpp"

namespace {

using namespace elaslam;

struct Args {
  std::string dataset_dir, config_path, mode, out_dir, modes_text = "ekf,gated,ela,consensus";
  bool barcodes = false, report = false, no_plots = false, check = false;
  mrclam::DatasetOverrides overrides;  // --rate, --start, --duration, --robots
  int jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
};

/// -1 to go on, else the exit code.
int parse_args(int argc, char** argv, Args* a) {
  CLI::App app{"elaslam run_dataset: the team on a recorded MRCLAM dataset, against Vicon ground truth"};
  app.add_option("--dataset", a->dataset_dir, "MRCLAM dataset directory (e.g. data/mrclam/dataset6)")
      ->required()->check(CLI::ExistingDirectory);
  cli::add_version_flag(app, "run_dataset");
  cli::add_config_option(app, &a->config_path, "its dataset:, robot: and main: sections", "mrclam.yaml");
  app.add_option("--mode", a->mode, "ekf, gated, ela or consensus (default: robot.mode)")
      ->check(CLI::IsMember({"ekf", "gated", "ela", "consensus"}));
  app.add_flag("--with-robot-barcodes", a->barcodes, "keep other robots' barcodes (moving landmarks)");
  mrclam::add_options(app, &a->overrides);
  app.add_flag("--report", a->report, "every mode without and with robot barcodes, and report.md");
  app.add_option("--modes", a->modes_text, "modes for --report");
  app.add_option("--jobs", a->jobs, "parallel runs for --report")->check(cli::range(1, 256));
  app.add_option("--out", a->out_dir, "output directory")->required();
  app.add_flag("--no-plots", a->no_plots, "do not call tools/plot_dataset.py (paths.png per run)");
  app.add_flag("--check", a->check, "check the configuration with the overrides and exit (0: valid); reads no data");
  if (const int rc = cli::parse(app, argc, argv); rc >= 0) return rc;
  return -1;
}

/// The config with the command line's dataset overrides, and the modes to run.
/// False (the reason printed) on a bad argument; a bad config throws ConfigError.
bool configure(Args* a, DatasetConfig* cfg, std::vector<std::string>* modes) {
  a->config_path = cli::find_config(a->config_path, "mrclam.yaml").path;
  *cfg = load_dataset_config(a->config_path);
  RobotOptions detecting = cfg->robot;  // the advice concerns ela and consensus alike, run or not
  detecting.mode = Mode::kEla;
  if (const std::string advice = config_advice(detecting); !advice.empty())
    std::fprintf(stderr, "run_dataset: warning: %s\n", advice.c_str());
  std::string why;
  if (!mrclam::apply(a->overrides, &cfg->dataset, &why)) {
    std::fprintf(stderr, "run_dataset: --robots: %s\n", why.c_str());
    return false;
  }
  if (!a->report) {
    modes->push_back(a->mode.empty() ? to_string(cfg->robot.mode) : a->mode);
    return true;
  }
  if (parse_mode_list(a->modes_text, modes, &why)) return true;
  std::fprintf(stderr, "run_dataset: --modes: %s\n", why.c_str());
  return false;
}

// A plot per run: every robot's true and estimated path with the landmarks.
void plot(const std::vector<std::string>& dirs) {
  const std::string script = cli::python_tool("plot_dataset.py");
  std::fflush(stdout);
  if (!std::filesystem::exists(script)) {
    std::fprintf(stderr, "run_dataset: no %s: no plots\n", script.c_str());
    return;
  }
  for (const auto& dir : dirs) {
    const std::string cmd = "'" + script + "' '" + dir + "' > /dev/null";
    if (std::system(cmd.c_str()) != 0) std::fprintf(stderr, "run_dataset: plotting failed (%s)\n", cmd.c_str());
  }
  std::printf("plots: <run dir>/paths.png\n");
}

int run_dataset_main(int argc, char** argv) {
  Args a;
  if (const int rc = parse_args(argc, argv, &a); rc >= 0) return rc;
  DatasetConfig cfg;
  std::vector<std::string> modes;
  if (!configure(&a, &cfg, &modes)) return cli::kExitBadInput;
  if (a.check) {
    std::cout << "run_dataset: " << a.config_path << ": valid\n";
    return 0;
  }
  DatasetSources src;
  if (const int rc = mrclam::run_step("run_dataset", [&] {
        src = load_sources(a.dataset_dir, cfg.dataset, a.report || !a.barcodes, a.report || a.barcodes);
        return cli::kExitOk;
      });
      rc != cli::kExitOk)
    return rc;
  const std::vector<DeadReckoning> dr = dead_reckoning(src.any());
  std::vector<DatasetRun> runs = dataset_runs(modes, a.report, a.barcodes);
  run_dataset_runs(cfg, src, a.jobs, &runs);
  DatasetOutputs out{a.dataset_dir, a.config_path, a.out_dir, "", a.report};
  // The report's command, with the program as the README names it.
  for (int i = 0; i < argc; ++i) out.command += (i ? " " : "") + std::string(i == 0 ? "build/bin/run_dataset" : argv[i]);
  std::vector<std::string> dirs;
  try {
    dirs = write_dataset_runs(out, cfg, src, dr, runs, std::cout);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "run_dataset: %s\n", e.what());
    return cli::kExitFailure;
  }
  if (!a.no_plots) plot(dirs);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return cli::guarded_main("run_dataset", [&] { return run_dataset_main(argc, argv); });
}

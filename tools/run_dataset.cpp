// SPDX-License-Identifier: Apache-2.0
// run_dataset: the team on a recorded UTIAS MRCLAM dataset instead of the
// simulator (in-process, like run_scenario), its metrics against Vicon ground
// truth and its output files.
//   run_dataset --dataset DIR [--config FILE] [--mode M] [--with-robot-barcodes]
//               [--robots 1,2,3] [--rate F] [--start S] [--duration T] [--check] --out DIR
//   run_dataset --dataset DIR --report [--modes ekf,gated,ela,consensus] --out DIR
// --report runs dead reckoning and every mode without and with the robots'
// barcodes (in parallel) and writes DIR/report.md, DIR/report.json and each run's
// files under DIR/<mode>/ and DIR/<mode>_barcodes/.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <mutex>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <thread>
#include <utility>

#include <CLI/CLI.hpp>

#include "elaslam/common/cli.hpp"
#include "elaslam/dataset/cli_overrides.hpp"
#include "elaslam/eval/report.hpp"
#include "elaslam/team/dataset_run.hpp"

namespace {

using namespace elaslam;

struct DatasetRun {
  std::string mode;
  bool barcodes = false;
  RunResult result;
  long robot_corrections = 0;  // observations of robot subjects that corrected a pose
};

long robot_corrections(const RunResult& r) {
  long n = 0;
  for (int id = 1; id <= mrclam::kMaxRobotSubject; ++id)
    if (id < static_cast<int>(r.corrections_by_landmark.size())) n += r.corrections_by_landmark[static_cast<std::size_t>(id)];
  return n;
}

nlohmann::json dataset_json(const mrclam::FrameSource& src, const mrclam::Options& o, const std::string& dir,
                            const std::vector<DeadReckoning>& dr) {
  nlohmann::json j;
  j["dir"] = dir;
  j["rate_hz"] = o.rate_hz;
  j["with_robot_barcodes"] = o.with_robot_barcodes;
  j["frames"] = src.num_frames();
  j["start_utime"] = src.frame_utime(0);
  nlohmann::json robots = nlohmann::json::array();
  for (std::size_t i = 0; i < src.stats().robots.size(); ++i) {
    const auto& s = src.stats().robots[i];
    robots.push_back({{"id", s.id},
                      {"measurements", s.measurements},
                      {"used", s.used},
                      {"misreads", s.misreads},
                      {"robot_barcodes", s.robot_barcodes},
                      {"duplicates", s.duplicates},
                      {"odometry_gaps", s.odometry_gaps},
                      {"dead_reckoning_error_mean", dr[i].error_mean},
                      {"dead_reckoning_error_rms", dr[i].error_rms}});
  }
  j["robots"] = robots;
  return j;
}

std::string f3(double v) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(3) << v;
  return s.str();
}

// report.md's odometer calibration (robot.odometry_calibration on): each robot's
// final estimate per run, and the least-squares fit of Vicon's increments on the
// odometer's over the same frames (mrclam::fit_odometry; mrclam_stats prints it too).
void write_calibration(std::ofstream& out, const mrclam::FrameSource& src, const std::vector<DatasetRun>& runs) {
  const bool any = std::any_of(runs.begin(), runs.end(), [](const DatasetRun& r) {
    return std::any_of(r.result.metrics.robots.begin(), r.result.metrics.robots.end(),
                       [](const RobotMetrics& m) { return m.calibration_estimated; });
  });
  if (!any) return;
  const auto pm = [](double v, double s, int digits) {
    std::ostringstream o;
    o << std::fixed << std::setprecision(digits) << v << " ± " << s;
    return o.str();
  };
  out << "\nOdometer calibration (robot.odometry_calibration): true increment = speed scale x reported "
         "translation, turn scale x reported turn + bias x dt. Each robot's own filter at the end of the run "
         "(estimate ± sigma), and the offline least-squares fit against Vicon over the same frames (windows of 5 s: "
         "mrclam_stats --calibration-window).\n\n"
         "| run | robot | turn scale | speed scale | turn bias [rad/s] |\n|---|---|---|---|---|\n";
  // Windows of 5 s: mrclam::fit_odometry says why.
  const int window = std::max(1, static_cast<int>(std::lround(5.0 / src.dt_s())));
  const int n = src.num_frames();
  for (const auto& [name, first] : {std::pair<const char*, int>{"offline fit (Vicon), the run", 0},
                                    std::pair<const char*, int>{"offline fit (Vicon), its second half", n / 2}})
    for (std::size_t i = 0; i < src.robot_ids().size(); ++i) {
      const mrclam::OdometryFit f = mrclam::fit_odometry(src, static_cast<int>(i), first, -1, window);
      out << "| " << name << " | " << src.robot_ids()[i] << " | " << std::fixed << std::setprecision(4)
          << f.turn_scale << " (" << f.turn_scale_without_bias << " without bias) | " << f.speed_scale << " | "
          << std::setprecision(5) << f.turn_bias_rad_s << " |\n";
    }
  for (const auto& run : runs)
    for (const auto& rm : run.result.metrics.robots) {
      if (!rm.calibration_estimated) continue;
      out << "| " << run.mode << (run.barcodes ? ", robot barcodes kept" : "") << " | " << rm.id << " | "
          << pm(rm.turn_scale, rm.turn_scale_sigma, 4) << " | " << pm(rm.speed_scale, rm.speed_scale_sigma, 4)
          << " | " << pm(rm.turn_bias_rad_s, rm.turn_bias_sigma_rad_s, 5) << " |\n";
    }
}

// report.md: per robot RMS and mean position error of dead reckoning and of every
// (mode, barcodes) run, the five-robot means, the global map error, and how many
// robot-barcode observations each run let correct a pose.
void write_report(const std::string& path, const mrclam::FrameSource& src, const std::vector<DeadReckoning>& dr,
                  const std::vector<DatasetRun>& runs, const std::string& command) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << "# MRCLAM run report\n\nCommand: `" << command << "`\n\n" << src.num_frames() << " frames at "
      << 1.0 / src.dt_s() << " Hz (" << f3(src.num_frames() * src.dt_s()) << " s), robots";
  for (int id : src.robot_ids()) out << ' ' << id;
  out << ".\n\nPosition error against Vicon per robot, RMS / mean over the frames [m]; the last column is the mean over "
         "robots of each robot's RMS (the reference figures' statistic).\n\n| run |";
  for (int id : src.robot_ids()) out << " robot " << id << " |";
  out << " mean of RMS | global map error [m] | robot-barcode corrections |\n|---|";
  for (std::size_t i = 0; i < src.robot_ids().size() + 3; ++i) out << "---|";
  out << '\n';
  double dr_mean = 0.0;
  out << "| dead reckoning |";
  for (const auto& d : dr) {
    out << ' ' << f3(d.error_rms) << " / " << f3(d.error_mean) << " |";
    dr_mean += d.error_rms / static_cast<double>(dr.size());
  }
  out << ' ' << f3(dr_mean) << " | - | - |\n";
  for (const auto& run : runs) {
    const RunMetrics& m = run.result.metrics;
    double mean = 0.0;
    out << "| " << run.mode << (run.barcodes ? ", robot barcodes kept" : "") << " |";
    for (const auto& rm : m.robots) {
      out << ' ' << f3(rm.error_rms) << " / " << f3(rm.error_mean) << " |";
      mean += rm.error_rms / static_cast<double>(m.robots.size());
    }
    out << " **" << f3(mean) << "** | " << f3(m.landmark_error_mean) << " | "
        << (run.barcodes ? std::to_string(run.robot_corrections) : std::string("-")) << " |\n";
  }
  out << "\nRobot-barcode corrections: observations of another robot's barcode that corrected a robot's pose "
         "(summed over robots; candidates' landmark-only updates not counted). Sightings available: ";
  long avail = 0;
  for (const auto& s : src.stats().robots) avail += s.robot_barcodes;
  out << avail << ".\n";
  write_calibration(out, src, runs);
}

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
  mrclam::Options& o = cfg->dataset;
  std::string why;
  if (!mrclam::apply(a->overrides, &o, &why)) {
    std::fprintf(stderr, "run_dataset: --robots: %s\n", why.c_str());
    return false;
  }
  if (!a->report) {
    modes->push_back(a->mode.empty() ? to_string(cfg->robot.mode) : a->mode);
    return true;
  }
  std::stringstream ss(a->modes_text);
  for (std::string m; std::getline(ss, m, ',');) {
    Mode parsed;
    if (!parse_mode(m, &parsed)) {
      std::fprintf(stderr, "run_dataset: --modes: unknown mode '%s' (ekf, gated, ela, consensus)\n", m.c_str());
      return false;
    }
    modes->push_back(m);
  }
  return true;
}

/// The recording, loaded once, and a frame source per barcode setting.
struct Sources {
  std::unique_ptr<mrclam::Dataset> data;
  std::unique_ptr<mrclam::FrameSource> without, with;
  const mrclam::FrameSource& any() const { return without ? *without : *with; }
};

void run_all(const DatasetConfig& cfg, const Sources& src, int jobs, std::vector<DatasetRun>* runs) {
  std::atomic<std::size_t> next{0};
  std::mutex failed;
  std::exception_ptr failure;  // the first exception of any worker, rethrown after the join
  auto worker = [&] {
    try {
      for (std::size_t i; (i = next++) < runs->size();) {
        DatasetRun& run = (*runs)[i];
        RobotOptions ro = cfg.robot;
        parse_mode(run.mode, &ro.mode);
        DatasetFrames frames(run.barcodes ? *src.with : *src.without);
        run.result = run_team(ro, cfg.main, frames);
        run.robot_corrections = robot_corrections(run.result);
      }
    } catch (...) {  // escaping a thread would std::terminate the process
      std::lock_guard<std::mutex> lock(failed);
      if (!failure) failure = std::current_exception();
      next = runs->size();
    }
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < std::min<int>(jobs, static_cast<int>(runs->size())); ++t) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
}

/// Every run's output files (a directory per run with --report), the summaries, and
/// report.md / report.json. Returns the run directories.
std::vector<std::string> write_runs(const Args& a, const DatasetConfig& cfg, const Sources& src,
                                    const std::vector<DeadReckoning>& dr, const std::vector<DatasetRun>& runs,
                                    const std::string& command) {
  std::vector<std::string> dirs;
  nlohmann::json all = nlohmann::json::array();
  for (const auto& run : runs) {
    mrclam::Options so = cfg.dataset;
    so.with_robot_barcodes = run.barcodes;
    RunInfo info{run.mode, 0.0, 0.0, 0, a.config_path, cfg.effective_yaml, command};
    info.simulated = false;
    info.data = "MRCLAM " + std::filesystem::path(a.dataset_dir).lexically_normal().filename().string() +
                (run.barcodes ? ", robot barcodes kept" : ", robot barcodes removed");
    nlohmann::json j = metrics_json(info, run.result);
    j["dataset"] = dataset_json(run.barcodes ? *src.with : *src.without, so, a.dataset_dir, dr);
    j["robot_barcode_corrections"] = run.robot_corrections;
    j["landmarks_where_a_robot_was"] = run.result.occupied;  // main.body_radius_m
    j["team_map_rounds_left_out"] = run.result.team_map_left_out;  // by robot, main.team_map_check_probability
    const std::string dir = a.report ? a.out_dir + "/" + run.mode + (run.barcodes ? "_barcodes" : "") : a.out_dir;
    write_outputs(dir, j, run.result);
    dirs.push_back(dir);
    all.push_back(j);
    std::cout << "== " << run.mode << (run.barcodes ? ", robot barcodes kept" : ", robot barcodes removed") << '\n';
    print_summary(std::cout, info, run.result);
    std::cout << "  dead reckoning RMS:";
    for (const auto& d : dr) std::cout << " robot " << d.id << ' ' << f3(d.error_rms);
    std::cout << "\n  robot-barcode observations that corrected a pose: " << run.robot_corrections << "\n";
    std::cout << "  landmarks taken as moving where a robot was (main.body_radius_m): " << run.result.occupied << "\n";
    std::cout << "  rounds of team maps each robot was left out of (main.team_map_check_probability):";
    for (std::size_t i = 0; i < run.result.robot_ids.size(); ++i)
      std::cout << " robot " << run.result.robot_ids[i] << ' ' << run.result.team_map_left_out[i];
    std::cout << '\n';
  }
  if (a.report) {
    write_report(a.out_dir + "/report.md", src.any(), dr, runs, command);
    std::ofstream(a.out_dir + "/report.json") << all.dump(1) << '\n';
    std::cout << "wrote " << a.out_dir << "/report.md\n";
  }
  return dirs;
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
  Sources src;
  try {
    src.data = std::make_unique<mrclam::Dataset>(mrclam::Dataset::load(a.dataset_dir, cfg.dataset.robots));
    mrclam::Options without = cfg.dataset, with = cfg.dataset;
    without.with_robot_barcodes = false;
    with.with_robot_barcodes = true;
    if (a.report || !a.barcodes) src.without = std::make_unique<mrclam::FrameSource>(*src.data, without);
    if (a.report || a.barcodes) src.with = std::make_unique<mrclam::FrameSource>(*src.data, with);
  } catch (const mrclam::DatasetError& e) {
    std::fprintf(stderr, "run_dataset: %s\n", e.what());
    return cli::kExitFailure;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "run_dataset: %s\n", e.what());
    return cli::kExitBadInput;
  }
  const std::vector<DeadReckoning> dr = dead_reckoning(src.any());
  std::vector<DatasetRun> runs;
  for (const auto& m : modes) {
    if (a.report || !a.barcodes) runs.push_back({m, false, {}, 0});
    if (a.report || a.barcodes) runs.push_back({m, true, {}, 0});
  }
  run_all(cfg, src, a.jobs, &runs);
  std::string command;  // the report's command, with the program as the README names it
  for (int i = 0; i < argc; ++i) command += (i ? " " : "") + std::string(i == 0 ? "build/bin/run_dataset" : argv[i]);
  std::vector<std::string> dirs;
  try {
    dirs = write_runs(a, cfg, src, dr, runs, command);
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

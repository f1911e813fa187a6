// SPDX-License-Identifier: Apache-2.0
// mrclam_stats: sensor and odometry noise of a UTIAS MRCLAM recording, measured
// against its Vicon ground truth, to choose the noise values of config/mrclam.yaml.
//   mrclam_stats --dataset DIR [--robots 1,2,3,4,5] [--rate F] [--json FILE]
//
// Range/bearing: every measurement of a static landmark (subjects 6-20) against the
// Vicon pose interpolated at its time; per robot and overall: count, median, robust
// sigma, the std within 5 robust sigmas and the fraction outside. Odometry: each
// robot alone over its own full window at --rate: scale, noise per metre driven.
// Odometer calibration (the filter's robot.odometry_calibration): per robot, least
// squares of Vicon's increments on the odometer's (mrclam::fit_odometry), over the
// whole run and each half, on the frames as the filter gets them (--config's
// dataset section: the odometry delay matters). The statistics are
// dataset/noise_stats.hpp's, the tables and the JSON dataset/stats_report.hpp's.
#include <cstdio>
#include <fstream>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "elaslam/common/cli.hpp"
#include "elaslam/dataset/mrclam.hpp"
#include "elaslam/dataset/stats_report.hpp"

namespace {

using namespace elaslam;

struct Args {
  std::string robots = "1,2,3,4,5", json_path;
  bool check = false;
  mrclam::StatsOptions stats;  // its frame_options: --config's dataset section, read before any data
};

/// -1 to go on, else the exit code.
int parse_args(int argc, char** argv, Args* a) {
  mrclam::StatsOptions& s = a->stats;
  CLI::App app{"elaslam mrclam_stats: sensor and odometry noise of an MRCLAM recording against Vicon"};
  cli::add_version_flag(app, "mrclam_stats");
  app.add_option("--dataset", s.dataset_dir, "dataset directory")->required()->check(CLI::ExistingDirectory);
  app.add_option("--robots", a->robots, "robots, e.g. 1,2,3,4,5")->capture_default_str();
  app.add_option("--rate", s.rate, "frame rate for the odometry analysis [Hz]")
      ->capture_default_str()
      ->check(cli::range(mrclam::limits::kRateMinHz, mrclam::limits::kRateMaxHz));
  app.add_option("--json", a->json_path, "also write the numbers as JSON");
  app.add_option("--calibration-window", s.calibration_window_s,
                 "odometer calibration: fit over windows of this many seconds [s] (mrclam::fit_odometry)")
      ->capture_default_str()
      ->check(cli::range(0.0, 600.0));
  app.add_option("--detect-range", s.detect_range, "detection statistics: in view within this range [m]")
      ->capture_default_str()->check(cli::range(0.1, 100.0));
  app.add_option("--detect-half-angle", s.detect_half_deg, "... and this half-angle of the heading [deg]")
      ->capture_default_str()->check(cli::range(1.0, 180.0));
  app.add_option("--config", s.config_path,
                 "also measure the residuals of the frames as the filter receives them, imported with this "
                 "config's dataset section (calibration, motion compensation, odometry delay)");
  app.add_flag("--check", a->check, "check the command line and --config and exit (0: valid); reads no data");
  if (const int rc = cli::parse(app, argc, argv); rc >= 0) return rc;
  std::string why;
  if (!mrclam::parse_robot_list(a->robots, &s.ids, &why)) {
    std::fprintf(stderr, "mrclam_stats: --robots: %s\n", why.c_str());
    return cli::kExitBadInput;
  }
  return -1;
}

int stats_main(int argc, char** argv) {
  Args a;
  if (const int rc = parse_args(argc, argv, &a); rc >= 0) return rc;
  const std::string& config_path = a.stats.config_path;
  // --config before the data: a bad one is refused (ConfigError: exit 2 through
  // guarded_main) before minutes of analysis.
  if (!config_path.empty()) a.stats.frame_options = mrclam::load_options(config_path);
  if (a.check) {
    std::printf("mrclam_stats: valid%s%s\n", config_path.empty() ? "" : ", --config ", config_path.c_str());
    return 0;
  }
  nlohmann::json out;
  if (const int rc = mrclam::run_step("mrclam_stats", [&] {
        const mrclam::Dataset d = mrclam::Dataset::load(a.stats.dataset_dir, a.stats.ids);
        out = mrclam::noise_report(d, a.stats, stdout);
        return cli::kExitOk;
      });
      rc != cli::kExitOk)
    return rc;
  if (!a.json_path.empty()) {
    std::ofstream f(a.json_path);
    f << out.dump(2) << "\n";
    if (!f) {
      std::fprintf(stderr, "mrclam_stats: cannot write %s\n", a.json_path.c_str());
      return cli::kExitFailure;
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return cli::guarded_main("mrclam_stats", [&] { return stats_main(argc, argv); });
}

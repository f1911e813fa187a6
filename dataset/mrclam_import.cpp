// SPDX-License-Identifier: Apache-2.0
// mrclam_import: one UTIAS MRCLAM recording as an LCM log of the system's messages
// (GROUND_TRUTH, then SENSOR_<id> per robot, every frame; event time = frame utime).
//   mrclam_import --dataset DIR [--config FILE] [--rate F] [--robots 1,2,3,4,5]
//                 [--with-robot-barcodes] [--start S] [--duration T] [--check] --out FILE.lcmlog
// Exit codes: 0 done, 1 bad data or an output error, 2 bad arguments or config.
// The messages and the summary table are dataset/import_log.hpp's.
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <vector>

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include "elaslam/common/cli.hpp"
#include "elaslam/dataset/cli_overrides.hpp"
#include "elaslam/dataset/import_log.hpp"
#include "elaslam/dataset/mrclam.hpp"

namespace {

using namespace elaslam;

struct Args {
  std::string dataset_dir, config_path, out_path;
  mrclam::DatasetOverrides overrides;  // --rate, --start, --duration, --robots
  bool with_robot_barcodes = false, check = false;
};

/// -1 to go on, else the exit code.
int parse_args(int argc, char** argv, Args* a) {
  CLI::App app{"elaslam mrclam_import: a UTIAS MRCLAM recording as an LCM log (SENSOR_<id>, GROUND_TRUTH)"};
  app.add_option("--dataset", a->dataset_dir, "dataset directory (RobotN_*.dat, Barcodes.dat, ...)")
      ->required()
      ->check(CLI::ExistingDirectory);
  cli::add_version_flag(app, "mrclam_import");
  cli::add_config_option(app, &a->config_path, "its dataset: section", "mrclam.yaml");
  mrclam::add_options(app, &a->overrides);
  app.add_flag("--with-robot-barcodes", a->with_robot_barcodes, "keep other robots' barcodes as moving landmarks");
  app.add_option("--out", a->out_path, "output LCM log")->required();
  app.add_flag("--check", a->check, "check the configuration with the overrides and exit (0: valid); reads no data");
  if (const int rc = cli::parse(app, argc, argv); rc >= 0) return rc;
  return -1;
}

/// The config's dataset section with the command line's overrides; false (the
/// reason printed) on a bad argument. A bad config throws ConfigError.
bool options(Args* a, mrclam::Options* o, std::string* effective_yaml) {
  a->config_path = cli::find_config(a->config_path, "mrclam.yaml").path;
  *o = mrclam::load_options(a->config_path, effective_yaml);
  if (a->with_robot_barcodes) o->with_robot_barcodes = true;
  std::string why;
  if (!mrclam::apply(a->overrides, o, &why)) {
    std::fprintf(stderr, "mrclam_import: --robots: %s\n", why.c_str());
    return false;
  }
  return true;
}

/// Every frame into the log (mrclam::write_import_log); false, said why, when a write failed.
bool write_log(const mrclam::FrameSource& src, const run_info_t& info, double rate_hz, lcm::LogFile* log,
               const std::string& out_path) {
  const auto write = [log](const std::string& channel, std::int64_t utime, const std::uint8_t* data, int size) {
    lcm::LogEvent ev{};
    ev.timestamp = utime;
    ev.channel = channel;
    ev.datalen = size;
    ev.data = const_cast<std::uint8_t*>(data);  // LogEvent has no const view; writeEvent only reads it
    return log->writeEvent(&ev) == 0;
  };
  int frame = 0;
  if (mrclam::write_import_log(src, info, rate_hz, write, &frame)) return true;
  std::fprintf(stderr, "mrclam_import: writing %s failed at frame %d (disk full?)\n", out_path.c_str(), frame);
  return false;
}

int import_main(int argc, char** argv) {
  Args a;
  if (const int rc = parse_args(argc, argv, &a); rc >= 0) return rc;
  mrclam::Options o;
  std::string effective_yaml;
  if (!options(&a, &o, &effective_yaml)) return cli::kExitBadInput;
  if (a.check) {
    std::cout << "mrclam_import: " << a.config_path << ": valid\n";
    return 0;
  }
  return mrclam::run_step("mrclam_import", [&] {
    const mrclam::Dataset d = mrclam::Dataset::load(a.dataset_dir, o.robots);
    const mrclam::FrameSource src(d, o);
    // Its directory is made when missing (runs/ on a fresh clone), as run_dataset does.
    if (const auto dir = std::filesystem::path(a.out_path).parent_path(); !dir.empty()) {
      std::error_code ec;
      std::filesystem::create_directories(dir, ec);
    }
    lcm::LogFile log(a.out_path, "w");
    if (!log.good()) {
      std::fprintf(stderr, "mrclam_import: cannot open %s for writing\n", a.out_path.c_str());
      return cli::kExitFailure;
    }
    if (!write_log(src, mrclam::import_run_info(src, o, a.dataset_dir, effective_yaml), o.rate_hz, &log, a.out_path)) return cli::kExitFailure;
    std::cout << "mrclam_import: " << a.dataset_dir << " -> " << a.out_path << "\n";
    mrclam::print_import_stats(std::cout, src.stats(), o.rate_hz);
    return cli::kExitOk;
  });
}

}  // namespace

int main(int argc, char** argv) {
  return cli::guarded_main("mrclam_import", [&] { return import_main(argc, argv); });
}

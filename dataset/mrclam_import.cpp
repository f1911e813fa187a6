// SPDX-License-Identifier: Apache-2.0
// mrclam_import: one UTIAS MRCLAM recording as an LCM log of the system's messages
// (GROUND_TRUTH, then SENSOR_<id> per robot, every frame; event time = frame utime).
//   mrclam_import --dataset DIR [--config FILE] [--rate F] [--robots 1,2,3,4,5]
//                 [--with-robot-barcodes] [--start S] [--duration T] [--check] --out FILE.lcmlog
// Exit codes: 0 done, 1 bad data or an output error, 2 bad arguments or config.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <vector>

#include <CLI/CLI.hpp>
#include <yaml-cpp/yaml.h>
#include <lcm/lcm-cpp.hpp>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/cli.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/dataset/cli_overrides.hpp"
#include "elaslam/dataset/mrclam.hpp"
#include "elaslam/run_info_t.hpp"

namespace {

using namespace elaslam;

void print_stats(std::ostream& os, const mrclam::Stats& s, double rate_hz) {
  char line[256];
  std::snprintf(line, sizeof line, "%-6s %12s %8s %9s %10s %11s %9s %12s\n", "robot", "measurements", "used",
                "misreads", "robot_bc", "duplicates", "odo_gaps", "max_gap[s]");
  os << line;
  for (const auto& r : s.robots) {
    std::snprintf(line, sizeof line, "%-6d %12ld %8ld %9ld %10ld %11ld %9ld %12.3f\n", r.id, r.measurements, r.used,
                  r.misreads, r.robot_barcodes, r.duplicates, r.odometry_gaps, r.max_odometry_gap_s);
    os << line;
  }
  std::snprintf(line, sizeof line, "frames: %d at %.3g Hz, %.3f s (Unix %.3f .. %.3f)\n", s.frames, rate_hz,
                s.end_time - s.start_time, s.start_time, s.end_time);
  os << line;
}

template <typename Msg>
bool write(lcm::LogFile* log, const std::string& channel, std::int64_t utime, const Msg& m,
           std::vector<std::uint8_t>* buf) {
  buf->resize(static_cast<std::size_t>(m.getEncodedSize()));
  if (m.encode(buf->data(), 0, static_cast<int>(buf->size())) < 0) return false;
  lcm::LogEvent ev{};
  ev.timestamp = utime;
  ev.channel = channel;
  ev.datalen = static_cast<std::int32_t>(buf->size());
  ev.data = buf->data();
  return log->writeEvent(&ev) == 0;
}

/// RUN_INFO of an imported recording: no seed, dynamism or speed (real data); the
/// effective dataset section with the command line's overrides.
run_info_t run_info(const mrclam::FrameSource& src, const mrclam::Options& o, const std::string& dataset_dir,
                    const std::string& effective_yaml) {
  run_info_t m{};
  m.frame = -1;
  m.schema_version = run_info_t::SCHEMA_VERSION;
  m.source = "mrclam_import";
  m.version = cli::version_line("mrclam_import");
  m.scenario = dataset_dir;
  m.seed = -1;
  m.dynamism_percent = -1.0;
  m.landmark_speed_mps = -1.0;
  m.rate_hz = o.rate_hz;
  m.frames = src.num_frames();
  contract::set_count(&m.robot_ids, &m.num_robots, static_cast<int>(src.robot_ids().size()));  // <= kMaxRobots (FrameSource)
  for (std::size_t i = 0; i < src.robot_ids().size(); ++i) m.robot_ids[i] = static_cast<std::int16_t>(src.robot_ids()[i]);
  m.config_yaml = config::edit_yaml(effective_yaml, [&o](YAML::Node& root) {  // the overrides, recorded
    YAML::Node d = root["dataset"];
    d["rate_hz"] = o.rate_hz;
    d["start_s"] = o.start_s;
    d["duration_s"] = o.duration_s;
    d["with_robot_barcodes"] = o.with_robot_barcodes;
    std::string robots;
    for (int id : o.robots) robots += (robots.empty() ? "" : ",") + std::to_string(id);
    d["robots"] = robots;
  });
  return m;
}

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

/// Every frame into the log: RUN_INFO about once a second of log time (before the
/// frame's messages, as the simulator does), GROUND_TRUTH, SENSOR_<r>. False when a
/// write failed (the frame named).
bool write_log(const mrclam::FrameSource& src, const run_info_t& info0, double rate_hz, lcm::LogFile* log,
               const std::string& out_path) {
  ground_truth_t gt{};
  std::vector<sensor_frame_t> sensors;
  std::vector<std::uint8_t> buf;
  std::vector<std::string> sensor_channels;
  for (int id : src.robot_ids()) sensor_channels.push_back(channels::sensor(id));
  run_info_t info = info0;
  const int info_period = std::max(1, static_cast<int>(rate_hz));
  for (int k = 0; k < src.num_frames(); ++k) {
    src.frame(k, &gt, &sensors);
    bool ok = true;
    if (k % info_period == 0) {
      info.utime = gt.utime;
      info.frame = k - 1;
      ok = write(log, channels::run_info(), info.utime, info, &buf);
    }
    ok = ok && write(log, channels::ground_truth(), gt.utime, gt, &buf);
    for (std::size_t i = 0; i < sensors.size(); ++i)
      ok = ok && write(log, sensor_channels[i], sensors[i].utime, sensors[i], &buf);
    if (!ok) {
      std::fprintf(stderr, "mrclam_import: writing %s failed at frame %d (disk full?)\n", out_path.c_str(), k);
      return false;
    }
  }
  return true;
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
  try {
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
    if (!write_log(src, run_info(src, o, a.dataset_dir, effective_yaml), o.rate_hz, &log, a.out_path)) return cli::kExitFailure;
    std::cout << "mrclam_import: " << a.dataset_dir << " -> " << a.out_path << "\n";
    print_stats(std::cout, src.stats(), o.rate_hz);
  } catch (const mrclam::DatasetError& e) {
    std::fprintf(stderr, "mrclam_import: %s\n", e.what());
    return cli::kExitFailure;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "mrclam_import: %s\n", e.what());
    return cli::kExitBadInput;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return cli::guarded_main("mrclam_import", [&] { return import_main(argc, argv); });
}

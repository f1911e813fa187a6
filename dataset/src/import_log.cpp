// SPDX-License-Identifier: Apache-2.0
#include "elaslam/dataset/import_log.hpp"

#include <algorithm>
#include <cstdio>
#include <ostream>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/cli.hpp"
#include "elaslam/common/config.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/common/run_info.hpp"

namespace elaslam::mrclam {
namespace {

template <typename Msg>
bool write_msg(const LogWriter& write, const std::string& channel, std::int64_t utime, const Msg& m,
               std::vector<std::uint8_t>* buf) {
  buf->resize(static_cast<std::size_t>(m.getEncodedSize()));
  if (m.encode(buf->data(), 0, static_cast<int>(buf->size())) < 0) return false;
  return write(channel, utime, buf->data(), static_cast<int>(buf->size()));
}

}  // namespace

run_info_t import_run_info(const FrameSource& src, const Options& o, const std::string& dataset_dir,
                           const std::string& effective_yaml) {
  run_info_t m = run_info_start("mrclam_import", src.robot_ids());  // <= kMaxRobots (FrameSource)
  m.scenario = dataset_dir;
  m.seed = -1;
  m.dynamism_percent = -1.0;
  m.landmark_speed_mps = -1.0;
  m.rate_hz = o.rate_hz;
  m.frames = src.num_frames();
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

bool write_import_log(const FrameSource& src, const run_info_t& info0, double rate_hz, const LogWriter& write,
                      int* failed_frame) {
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
      ok = write_msg(write, channels::run_info(), info.utime, info, &buf);
    }
    ok = ok && write_msg(write, channels::ground_truth(), gt.utime, gt, &buf);
    for (std::size_t i = 0; i < sensors.size(); ++i)
      ok = ok && write_msg(write, sensor_channels[i], sensors[i].utime, sensors[i], &buf);
    if (!ok) {
      *failed_frame = k;
      return false;
    }
  }
  return true;
}

void print_import_stats(std::ostream& os, const Stats& s, double rate_hz) {
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

}  // namespace elaslam::mrclam

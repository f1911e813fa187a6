// SPDX-License-Identifier: Apache-2.0
// monitor: one line that follows a live team (frame k/N, poses received, moving
// landmarks found so far, nodes' health), for a terminal or a log.
//   monitor [--config FILE] [--key-file FILE] [--lcm-url URL] [--channel-suffix S] [--interval S]
// On a terminal the line is rewritten in place about 5 times a second; otherwise a
// line is printed every --interval seconds. SIGINT / SIGTERM end it (exit 0) with
// the final line. Reads RUN_INFO, SENSOR_*, POSE_*, GLOBAL_MAP, DYNAMIC_NOTICE and
// STATUS_ROBOT_* through the node shell: a bad message is counted, never fatal.
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <set>
#include <string>

#include <CLI/CLI.hpp>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/cli.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/dynamic_notice_t.hpp"
#include "elaslam/global_map_t.hpp"
#include "elaslam/node_status_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/run_info_t.hpp"
#include "elaslam/sensor_frame_t.hpp"
#include "elaslam/common/config.hpp"
#include "elaslam/transport/auth_transport.hpp"
#include "elaslam/common/faults.hpp"
#include "elaslam/transport/node_shell.hpp"
#include "elaslam/transport/process.hpp"

namespace elaslam {
namespace {

/// What the line shows, filled by the handlers.
class Progress {
 public:
  explicit Progress(transport::NodeShell& shell) : shell_(shell) {}

  void subscribe() {
    // Bounded queues: the monitor may fall behind, it must never grow without bound.
    const std::string& sfx = shell_.suffix();
    on<run_info_t>(channels::run_info(sfx), 10, [this](const run_info_t& m) {
      if (m.frames > 0) frames_ = m.frames;
    });
    on<sensor_frame_t>(channels::any_sensor(sfx), 200, [this](const sensor_frame_t& m) {
      if (m.frame > frame_) frame_ = m.frame;
    });
    on<pose_estimate_t>(channels::any_pose(sfx), 200, [this](const pose_estimate_t& m) {
      ++poses_;
      pose_robots_.insert(m.robot_id);
    });
    on<global_map_t>(channels::global_map(sfx), 20, [this](const global_map_t& m) {
      for (int i = 0; i < contract::bounded(m.num_moving, static_cast<int>(m.moving_ids.size())); ++i)
        moving_.insert(m.moving_ids[i]);
    });
    on<dynamic_notice_t>(channels::dynamic_notice(sfx), 200, [this](const dynamic_notice_t& m) {
      ++notices_;
      moving_.insert(m.landmark_id);
    });
    on<node_status_t>(channels::any_status_robot(sfx), 50, [this](const node_status_t& m) {
      dropped_by_robot_[m.node_id] = m.frames_dropped;
      // The odometer's calibration, when the robot estimates it (robot.odometry_calibration).
      if (m.odom_turn_scale_sigma > 0.0f || m.odom_speed_scale_sigma > 0.0f || m.odom_turn_bias_sigma_rad_s > 0.0f)
        calibration_[m.node_id] = {m.odom_turn_scale, m.odom_speed_scale};
      dropped_ = 0;
      for (const auto& [id, n] : dropped_by_robot_) dropped_ += n;
      note_health("robot " + std::to_string(m.node_id), m);
    });
    on<node_status_t>(channels::status_main(sfx), 10, [this](const node_status_t& m) { note_health("main", m); });
  }

  std::string line() const {
    char buf[512];
    const std::string of = frames_ > 0 ? "/" + std::to_string(frames_) : "";
    // Frames are numbered from 0: after frame k, k + 1 are done ("frame 150/150").
    std::snprintf(buf, sizeof buf, "frame %d%s | poses %lld from %zu robot%s | moving landmarks found %zu | notices %lld",
                  frame_ + 1, of.c_str(), poses_, pose_robots_.size(), pose_robots_.size() == 1 ? "" : "s",
                  moving_.size(), notices_);
    std::string out = buf;
    const long long bad = shell_.counters().inputs.decode_errors;
    if (dropped_ > 0) out += " | robots report " + std::to_string(dropped_) + " dropped frames";
    if (bad > 0) out += " | undecodable " + std::to_string(bad);
    if (const long long refused = shell_.counters().auth_refused; refused > 0)
      out += " | refused (authentication) " + std::to_string(refused);
    long long refused = 0;
    std::string faults;  // "FAULT robot 2: frames lost, main silent"
    for (const auto& [node, h] : health_) {
      refused += h.refused;
      std::string names;
      for (const std::string& n : fault_names(h.faults)) names += (names.empty() ? "" : ", ") + n;
      if (!names.empty()) faults += " | FAULT " + node + ": " + names;
    }
    if (refused > 0) out += " | messages refused " + std::to_string(refused);
    if (!calibration_.empty()) {
      out += " | odometer turn/speed scale:";
      for (const auto& [id, c] : calibration_) {
        char s[64];
        std::snprintf(s, sizeof s, " robot %d %.3f/%.3f", id, static_cast<double>(c[0]), static_cast<double>(c[1]));
        out += s;
      }
    }
    out += faults;
    if (frame_ < 0) out = "waiting for the first frame" + std::string(frames_ > 0 ? " of " + std::to_string(frames_) : "");
    return out;
  }

 private:
  // Refusals (every reason of node_status_t.refused) and the fault flags, per node.
  struct Health {
    long long refused = 0;
    std::int32_t faults = 0;  // node_status_t.fault_flags of its last STATUS
  };
  void note_health(const std::string& node, const node_status_t& m) {
    Health& h = health_[node];
    h.refused = 0;
    for (std::int64_t n : m.refused) h.refused += n;
    h.faults = m.fault_flags;
  }

  template <typename Msg, typename Fn>
  void on(const std::string& channel, int queue, Fn fn) {
    shell_.subscribe<Msg>(channel, [fn](const Msg& m, const std::string&) { fn(m); }, queue);
  }

  transport::NodeShell& shell_;
  int frame_ = -1, frames_ = 0;
  long long poses_ = 0, notices_ = 0, dropped_ = 0;
  std::set<int> pose_robots_, moving_;
  std::map<int, long long> dropped_by_robot_;
  std::map<int, std::array<float, 2>> calibration_;  // robot -> odometer turn and speed scale (STATUS)
  std::map<std::string, Health> health_;
};

}  // namespace
}  // namespace elaslam

namespace {

int monitor_main(int argc, char** argv) {
  using namespace elaslam;
  transport::TransportArgs targs;
  double interval_s = 5.0;
  CLI::App app{"elaslam monitor: one progress line for a live team (frame, poses, moving landmarks, health)"};
  cli::add_version_flag(app, "monitor");
  std::string config;
  cli::add_config_option(app, &config, "its team: section (the team key)");
  transport::add_transport_options(app, &targs);
  app.add_option("--interval", interval_s, "seconds between lines when not on a terminal")
      ->capture_default_str()
      ->check(cli::range(0.1, 3600.0));
  if (const int rc = cli::parse(app, argc, argv); rc >= 0) return rc;
  // The team key (--key-file, else the config's team.key_file): a keyed team's messages
  // are verified here too. No configuration found (and none asked for): no key.
  std::string config_path;
  try {
    config_path = cli::find_config(config).path;
  } catch (const config::ConfigError& e) {
    if (!config.empty() || std::getenv(cli::kConfigEnv) != nullptr) {
      std::fprintf(stderr, "monitor: %s\n", e.what());
      return 2;
    }
  }
  int open_rc = 1;
  const auto lcm = transport::open_lcm(targs, config_path, transport::kSenderTool, false, 0, "monitor", &open_rc, nullptr);
  if (!lcm) return open_rc;
  // No log: the line is the monitor's output; bad messages show in it as "undecodable".
  transport::NodeShell shell(*lcm, transport::ShellOptions("monitor", targs.channel_suffix, nullptr));
  Progress progress(shell);
  progress.subscribe();
  transport::install_stop_handlers();
  const bool tty = isatty(STDERR_FILENO) == 1;
  const auto period = tty ? std::chrono::milliseconds(200)
                          : std::chrono::milliseconds(static_cast<long long>(interval_s * 1000.0));
  std::string last;
  shell.every(period, [&] {
    const std::string l = progress.line();
    if (tty) {
      std::fprintf(stderr, "\r\033[K%s", l.c_str());  // rewrite the line in place
    } else if (l != last) {
      std::fprintf(stderr, "%s\n", l.c_str());
    }
    last = l;
  }, period);
  if (shell.spin(50) == transport::NodeShell::Exit::kTransportError) {
    std::fprintf(stderr, "monitor: LCM handle error\n");  // the shell has no log here
    return 1;
  }
  std::fprintf(stderr, tty ? "\r\033[K%s\n" : "%s\n", progress.line().c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return elaslam::cli::guarded_main("monitor", [&] { return monitor_main(argc, argv); });
}

// robot_node: one robot's EKF-SLAM with the ELA gate, as its own process on LCM.
//   robot_node [--config FILE] --robot R [--mode M] [--lcm-url URL]
// The config: --config, else $ELASLAM_CONFIG, else /etc/elaslam/elaslam.yaml, else
// the installed default (common/cli.hpp).
// Subscribes SENSOR_<R>, DYNAMIC_NOTICE; publishes POSE_<R>, LMAP_EVENT,
// LMAP_SNAPSHOT, STATUS_ROBOT_<R>. A thin shell around RobotNode (no logic here).
#include <cstdio>
#include <iostream>
#include <vector>

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/cli.hpp"
#include "elaslam/common/lcm_util.hpp"
#include "elaslam/robot_node/robot_node.hpp"

namespace elaslam {
namespace {

struct Args {
  std::string config;
  int robot = 0;
  std::string mode;
  std::string lcm_url;
  std::string suffix;
  int sensor_queue = 200;
  int notice_queue = 1000;
  double status_period_s = 1.0;
  bool verbose = false;
  bool check = false;
};

class Shell {
 public:
  Shell(const Args& a, const RobotOptions& o, lcm::LCM* lc) : args_(a), node_(o, a.robot), lc_(lc) {
    buf_.reserve(1 << 16);
  }

  bool subscribe() {
    auto* s = subscribe_raw<Shell, &Shell::on_sensor>(*lc_, channels::sensor(args_.robot, args_.suffix), this);
    auto* n = subscribe_raw<Shell, &Shell::on_notice>(*lc_, channels::dynamic_notice(args_.suffix), this);
    if (!s || !n) return false;
    // LCM's default queue of 30 drops silently (LCM.md): size both on purpose. Losses
    // of sensor frames show up as frame gaps, of notices as seq gaps.
    s->setQueueCapacity(args_.sensor_queue);
    n->setQueueCapacity(args_.notice_queue);
    return true;
  }

  void on_sensor(const lcm::ReceiveBuffer* rb, const std::string& /*chan*/) {
    sensor_frame_t msg;
    if (msg.decode(rb->data, 0, static_cast<int>(rb->data_size)) < 0) {
      node_.count_decode_error();
      warn("cannot decode a sensor_frame_t");
      return;
    }
    std::string why;
    const auto v = node_.on_sensor(msg, now_utime(), &why);
    if (v == RobotNode::Verdict::kInvalid) warn("sensor frame refused: " + why);
    if (v != RobotNode::Verdict::kProcessed) return;
    const std::int64_t now = now_utime();
    for (auto ev : node_.event_msgs()) {
      ev.utime = now;
      publish_msg(*lc_, channels::lmap_event(args_.suffix), ev, &buf_);
    }
    if (node_.snapshot_ready()) publish_msg(*lc_, channels::lmap_snapshot(args_.suffix), node_.snapshot_msg(), &buf_);
    pose_estimate_t pose = node_.pose_msg();
    pose.utime = now_utime();
    publish_msg(*lc_, channels::pose(args_.robot, args_.suffix), pose, &buf_);
  }

  void on_notice(const lcm::ReceiveBuffer* rb, const std::string& /*chan*/) {
    dynamic_notice_t msg;
    if (msg.decode(rb->data, 0, static_cast<int>(rb->data_size)) < 0) {
      node_.count_decode_error();
      warn("cannot decode a dynamic_notice_t");
      return;
    }
    if (last_notice_seq_ > 0 && msg.seq > last_notice_seq_ + 1) node_.count_queue_drops(msg.seq - last_notice_seq_ - 1);
    if (msg.seq > last_notice_seq_) last_notice_seq_ = msg.seq;
    std::string why;
    if (!node_.on_notice(msg, &why)) warn("dynamic notice refused: " + why);
  }

  void publish_status() {
    publish_msg(*lc_, channels::status_robot(args_.robot, args_.suffix), node_.status_msg(now_utime()), &buf_);
  }

  void final_line() const {
    const auto& c = node_.counters();
    std::fprintf(stderr,
                 "robot_node %d: frames=%lld gaps=%lld duplicates=%lld out_of_order=%lld rejected=%lld "
                 "decode_errors=%lld filter_faults=%lld events=%lld notices_applied=%lld landmarks=%d "
                 "frame_us p50=%lld p99=%lld max=%lld\n",
                 args_.robot, (long long)c.frames, (long long)c.frames_gap, (long long)c.frames_duplicate,
                 (long long)c.frames_out_of_order, (long long)c.rejected_inputs, (long long)c.decode_errors,
                 (long long)c.filter_faults, (long long)c.events_sent, (long long)c.notices_applied,
                 node_.robot().filter().num_landmarks(), (long long)node_.processing().quantile(0.5),
                 (long long)node_.processing().quantile(0.99), (long long)node_.processing().max());
  }

 private:
  void warn(const std::string& what) {
    // Rate-limited: a flood of bad messages must not flood the log.
    if (++warnings_ <= 20 || warnings_ % 1000 == 0)
      std::fprintf(stderr, "robot_node %d: %s (warning %lld)\n", args_.robot, what.c_str(), (long long)warnings_);
  }

  Args args_;
  RobotNode node_;
  lcm::LCM* lc_;
  std::vector<std::uint8_t> buf_;
  std::int64_t last_notice_seq_ = 0;
  std::int64_t warnings_ = 0;
};

int run(const Args& a) {
  std::string effective;
  RobotOptions o;
  cli::ConfigChoice cfg;
  try {
    cfg = cli::find_config(a.config);
    o = load_robot_options(cfg.path, &effective);
  } catch (const config::ConfigError& e) {
    std::fprintf(stderr, "robot_node: %s\n", e.what());
    return 2;
  }
  if (!a.mode.empty() && !parse_mode(a.mode, &o.mode)) {
    std::fprintf(stderr, "robot_node: --mode '%s' is not one of ekf, gated, ela, consensus\n", a.mode.c_str());
    return 2;
  }
  if (a.check) {  // e.g. after editing /etc/elaslam/elaslam.yaml, before restarting the service
    std::printf("robot_node %d: %s (%s): valid, mode %s\n", a.robot, cfg.path.c_str(), cfg.origin.c_str(),
                to_string(o.mode));
    if (a.verbose) std::printf("%s\n", effective.c_str());
    return 0;
  }
  lcm::LCM lc(a.lcm_url);
  if (!lc.good()) {
    std::fprintf(stderr, "robot_node %d: cannot open LCM (%s). Multicast on loopback needs a route: "
                 "ip route add 224.0.0.0/4 dev lo (see tools/netns_run.sh)\n", a.robot, describe_lcm_url(a.lcm_url).c_str());
    return 1;
  }
  Shell shell(a, o, &lc);
  if (!shell.subscribe()) {
    std::fprintf(stderr, "robot_node %d: cannot subscribe\n", a.robot);
    return 1;
  }
  std::fprintf(stderr, "robot_node %d: %s, config %s (%s), mode=%s lcm=%s\n", a.robot,
               cli::version_line("robot_node").c_str(), cfg.path.c_str(), cfg.origin.c_str(), to_string(o.mode),
               describe_lcm_url(a.lcm_url).c_str());
  if (a.verbose) std::fprintf(stderr, "%s\n", effective.c_str());
  install_stop_handlers();
  auto next_status = std::chrono::steady_clock::now();
  while (!stop_requested().load()) {
    if (lc.handleTimeout(100) < 0 && !stop_requested().load()) {  // < 0 also on EINTR from our signal
      std::fprintf(stderr, "robot_node %d: LCM handle error\n", a.robot);
      shell.final_line();
      return 1;
    }
    if (std::chrono::steady_clock::now() >= next_status) {
      shell.publish_status();
      next_status += std::chrono::milliseconds(static_cast<int>(a.status_period_s * 1000));
    }
  }
  shell.publish_status();
  shell.final_line();
  return 0;
}

}  // namespace
}  // namespace elaslam

int main(int argc, char** argv) {
  elaslam::Args a;
  CLI::App app{"elaslam robot_node: one robot's EKF-SLAM with the ELA gate, on LCM"};
  elaslam::cli::add_version_flag(app, "robot_node");
  app.add_option("--config", a.config,
                 "YAML config file, its robot: section (default: $ELASLAM_CONFIG, else /etc/elaslam/elaslam.yaml, "
                 "else the installed paper.yaml)");
  app.add_option("--robot", a.robot, "this robot's id (1-8)")->required()->check(CLI::Range(1, 8));
  app.add_option("--mode", a.mode, "override robot.mode: ekf, gated, ela, consensus");
  app.add_option("--lcm-url", a.lcm_url, "LCM URL (default: LCM_DEFAULT_URL, else LCM's default)");
  app.add_option("--channel-suffix", a.suffix, "suffix appended to every channel name");
  app.add_option("--sensor-queue", a.sensor_queue, "SENSOR_<R> subscription queue capacity")->check(CLI::Range(1, 100000));
  app.add_option("--notice-queue", a.notice_queue, "DYNAMIC_NOTICE queue capacity")->check(CLI::Range(1, 100000));
  app.add_option("--status-period", a.status_period_s, "seconds between STATUS_ROBOT messages")->check(CLI::Range(0.05, 60.0));
  app.add_flag("--verbose", a.verbose, "print the effective configuration");
  app.add_flag("--check", a.check, "check the configuration, print where it came from and exit (0: valid)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  return elaslam::run(a);
}

// main_robot: the team's global map, as its own process on LCM.
//   main_robot [--config FILE] [--state PATH] [--lcm-url URL]
// The config: --config, else $ELASLAM_CONFIG, else /etc/elaslam/elaslam.yaml, else
// the installed default (common/cli.hpp).
// Subscribes LMAP_EVENT, LMAP_SNAPSHOT; publishes GLOBAL_MAP, DYNAMIC_NOTICE,
// STATUS_MAIN. The map is saved to --state atomically (write, then rename) on change
// at a bounded rate and at shutdown, and reloaded at start.
#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <vector>

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/cli.hpp"
#include "elaslam/common/lcm_util.hpp"
#include "elaslam/main_robot/main_node.hpp"
#include "elaslam/pose_estimate_t.hpp"

namespace elaslam {
namespace {

using Clock = std::chrono::steady_clock;

struct Args {
  std::string config;
  std::string state;
  std::string lcm_url;
  std::string suffix;
  int queue = 10000;
  bool check = false;
};

GlobalMapOptions load_options(const std::string& path) {
  config::Document doc = config::Document::from_file(path);
  GlobalMapOptions o;
  doc.section("main", [&](config::Reader& r) { parse(r, &o); });
  doc.allow({"scenario", "robot", "lcm", "team", "dataset"});
  doc.finish();
  return o;
}

bool save_state(const GlobalMap& map, const std::string& path) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    if (!out) return false;
    out << map.to_json();
    out.flush();
    if (!out) return false;
  }
  return std::rename(tmp.c_str(), path.c_str()) == 0;
}

class Shell {
 public:
  Shell(const Args& a, const GlobalMapOptions& o, lcm::LCM* lc) : args_(a), node_(o), lc_(lc) {}

  bool subscribe() {
    auto* e = subscribe_raw<Shell, &Shell::on_event>(*lc_, channels::lmap_event(args_.suffix), this);
    auto* s = subscribe_raw<Shell, &Shell::on_snapshot>(*lc_, channels::lmap_snapshot(args_.suffix), this);
    // Every robot's POSE marks the end of its frame: GLOBAL_MAP for frame k goes out
    // as soon as every robot seen so far has finished k (plus a periodic one).
    auto* p = subscribe_raw<Shell, &Shell::on_pose>(*lc_, "POSE_[0-9]+" + args_.suffix, this);
    if (!e || !s || !p) return false;
    p->setQueueCapacity(1000);
    // Events come in bursts (one per observed landmark per robot per frame): a deep
    // queue, on purpose; losses show up as seq gaps and are repaired by snapshots.
    e->setQueueCapacity(args_.queue);
    s->setQueueCapacity(100);
    return true;
  }

  void on_event(const lcm::ReceiveBuffer* rb, const std::string&) {
    landmark_event_t m;
    if (m.decode(rb->data, 0, static_cast<int>(rb->data_size)) < 0) return decode_error("landmark_event_t");
    std::string why;
    if (!node_.on_event(m, &why)) warn("event refused: " + why);
    send_notices();
  }

  void on_snapshot(const lcm::ReceiveBuffer* rb, const std::string&) {
    lmap_snapshot_t m;
    if (m.decode(rb->data, 0, static_cast<int>(rb->data_size)) < 0) return decode_error("lmap_snapshot_t");
    std::string why;
    if (!node_.on_snapshot(m, &why)) warn("snapshot refused: " + why);
    send_notices();
  }

  void on_pose(const lcm::ReceiveBuffer* rb, const std::string&) {
    pose_estimate_t m;
    if (m.decode(rb->data, 0, static_cast<int>(rb->data_size)) < 0) return decode_error("pose_estimate_t");
    const int done = node_.on_robot_frame(m.robot_id, m.frame);
    if (done >= 0)
      publish_msg(*lc_, channels::global_map(args_.suffix), node_.global_map_msg(now_utime(), done), &buf_);
  }

  void publish_map() { publish_msg(*lc_, channels::global_map(args_.suffix), node_.global_map_msg(now_utime()), &buf_); }
  void publish_status() { publish_msg(*lc_, channels::status_main(args_.suffix), node_.status_msg(now_utime()), &buf_); }
  MainNode& node() { return node_; }

 private:
  void send_notices() {
    for (const auto& n : node_.take_notices(now_utime())) publish_msg(*lc_, channels::dynamic_notice(args_.suffix), n, &buf_);
  }
  void decode_error(const char* type) {
    node_.count_decode_error();
    warn(std::string("cannot decode a ") + type);
  }
  void warn(const std::string& what) {
    if (++warnings_ <= 20 || warnings_ % 1000 == 0)
      std::fprintf(stderr, "main_robot: %s (warning %lld)\n", what.c_str(), (long long)warnings_);
  }

  Args args_;
  MainNode node_;
  lcm::LCM* lc_;
  std::vector<std::uint8_t> buf_;
  std::int64_t warnings_ = 0;
};

int run(const Args& a) {
  GlobalMapOptions o;
  cli::ConfigChoice cfg;
  try {
    cfg = cli::find_config(a.config);
    o = load_options(cfg.path);
  } catch (const config::ConfigError& e) {
    std::fprintf(stderr, "main_robot: %s\n", e.what());
    return 2;
  }
  if (a.check) {  // e.g. after editing /etc/elaslam/elaslam.yaml, before restarting the service
    std::printf("main_robot: %s (%s): valid\n", cfg.path.c_str(), cfg.origin.c_str());
    return 0;
  }
  lcm::LCM lc(a.lcm_url);
  if (!lc.good()) {
    std::fprintf(stderr, "main_robot: cannot open LCM (%s). Multicast on loopback needs a route: "
                 "ip route add 224.0.0.0/4 dev lo (see tools/netns_run.sh)\n", describe_lcm_url(a.lcm_url).c_str());
    return 1;
  }
  Shell shell(a, o, &lc);
  if (!a.state.empty()) {
    std::ifstream in(a.state);
    if (in) {
      std::stringstream ss;
      ss << in.rdbuf();
      std::string why;
      if (!shell.node().map().from_json(ss.str(), &why)) {
        std::fprintf(stderr, "main_robot: cannot load state %s: %s\n", a.state.c_str(), why.c_str());
        return 2;
      }
      std::fprintf(stderr, "main_robot: resumed from %s (version %lld, %d static, %d moving)\n", a.state.c_str(),
                   (long long)shell.node().map().version(), shell.node().map().count(GlobalStatus::kStatic),
                   shell.node().map().count(GlobalStatus::kMoving));
    }
  }
  if (!shell.subscribe()) {
    std::fprintf(stderr, "main_robot: cannot subscribe\n");
    return 1;
  }
  std::fprintf(stderr, "main_robot: %s, config %s (%s), lcm=%s\n", cli::version_line("main_robot").c_str(),
               cfg.path.c_str(), cfg.origin.c_str(), describe_lcm_url(a.lcm_url).c_str());
  install_stop_handlers();
  const auto map_period = std::chrono::microseconds(static_cast<std::int64_t>(1e6 / o.publish_rate_hz));
  const auto save_period = std::chrono::milliseconds(static_cast<std::int64_t>(o.state_save_interval_s * 1000));
  auto next_map = Clock::now(), next_status = Clock::now(), next_save = Clock::now();
  std::int64_t saved_version = shell.node().map().version();
  while (!stop_requested().load()) {
    if (lc.handleTimeout(5) < 0 && !stop_requested().load()) {  // < 0 also on EINTR from our signal
      std::fprintf(stderr, "main_robot: LCM handle error\n");
      break;
    }
    const auto now = Clock::now();
    if (now >= next_map) shell.publish_map(), next_map += map_period;
    if (now >= next_status) shell.publish_status(), next_status += std::chrono::seconds(1);
    if (!a.state.empty() && now >= next_save && shell.node().map().version() != saved_version) {
      if (!save_state(shell.node().map(), a.state)) std::fprintf(stderr, "main_robot: cannot save %s\n", a.state.c_str());
      saved_version = shell.node().map().version();
      next_save = now + save_period;
    }
  }
  shell.publish_map();
  shell.publish_status();
  if (!a.state.empty() && !save_state(shell.node().map(), a.state))
    std::fprintf(stderr, "main_robot: cannot save %s\n", a.state.c_str());
  const auto& c = shell.node().counters();
  std::fprintf(stderr, "main_robot: events=%lld snapshots=%lld duplicates=%lld gaps=%lld rejected=%lld "
               "decode_errors=%lld notices=%lld static=%d moving=%d version=%lld\n",
               (long long)c.events, (long long)c.snapshots, (long long)c.duplicates, (long long)c.gaps,
               (long long)c.rejected_inputs, (long long)c.decode_errors, (long long)c.notices_sent,
               shell.node().map().count(GlobalStatus::kStatic), shell.node().map().count(GlobalStatus::kMoving),
               (long long)shell.node().map().version());
  return 0;
}

}  // namespace
}  // namespace elaslam

int main(int argc, char** argv) {
  elaslam::Args a;
  CLI::App app{"elaslam main_robot: the team's global map, on LCM"};
  elaslam::cli::add_version_flag(app, "main_robot");
  app.add_option("--config", a.config,
                 "YAML config file, its main: section (default: $ELASLAM_CONFIG, else /etc/elaslam/elaslam.yaml, "
                 "else the installed paper.yaml)");
  app.add_option("--state", a.state, "file to persist the global map in (reloaded at start)");
  app.add_option("--lcm-url", a.lcm_url, "LCM URL (default: LCM_DEFAULT_URL, else LCM's default)");
  app.add_option("--channel-suffix", a.suffix, "suffix appended to every channel name");
  app.add_option("--event-queue", a.queue, "LMAP_EVENT subscription queue capacity")->check(CLI::Range(1, 1000000));
  app.add_flag("--check", a.check, "check the configuration, print where it came from and exit (0: valid)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  return elaslam::run(a);
}

// main_robot: the team's global map, as its own process on LCM.
//   main_robot [--config FILE] [--state PATH] [--lcm-url URL] [--channel-suffix S]
// The config: --config, else $ELASLAM_CONFIG, else /etc/elaslam/elaslam.yaml, else
// the installed default (common/cli.hpp).
// Subscribes LMAP_EVENT(S), LMAP_SNAPSHOT, POSE_<r>; publishes GLOBAL_MAP, DYNAMIC_NOTICE,
// STATUS_MAIN. A thin shell: MainNode on the node shell (MainPorts, main_node.hpp),
// exactly as the in-process team run runs it. The map is saved to --state atomically
// (write, then rename) on change at a bounded rate and at shutdown, and reloaded at start.
#include <chrono>
#include <cstdio>
#include <string>

#include <CLI/CLI.hpp>

#include "elaslam/common/atomic_file.hpp"
#include "elaslam/common/cli.hpp"
#include "elaslam/main_robot/main_node.hpp"
#include "elaslam/transport/auth_transport.hpp"
#include "elaslam/transport/node_shell.hpp"
#include "elaslam/transport/process.hpp"

namespace elaslam {
namespace {

struct Args {
  std::string config;
  std::string state;
  transport::TransportArgs transport;
  MainQueues queues;
  bool check = false;
};

GlobalMapOptions load_options(const std::string& path) {
  config::Document doc = config::Document::from_file(path);
  GlobalMapOptions o;
  doc.section("main", [&](config::Reader& r) { parse(r, &o); });
  doc.allow_sections();
  doc.finish();
  if (auto problems = check_shared_config(path); !problems.empty()) throw config::ConfigError(path, std::move(problems));
  return o;
}

/// files::write_atomic: a temporary made by mkstemp beside it (never a planted link
/// followed), fsync'ed, renamed over, the directory fsync'ed. Says so when it failed.
void save_state(const GlobalMap& map, const std::string& path) {
  std::string why;
  if (files::write_atomic(path, map.to_json(), &why)) return;
  std::fprintf(stderr, "main_robot: cannot save %s: %s\n", path.c_str(), why.c_str());
}

/// The saved map, when --state names a file that exists; false (said why) when it
/// cannot be read or does not hold (from_json checks it like a message).
bool resume(const std::string& path, GlobalMap* map) {
  std::string text, why;
  bool missing = false;
  if (path.empty()) return true;
  if (!files::read_all(path, &text, &why, &missing)) {
    if (missing) return true;
    std::fprintf(stderr, "main_robot: cannot load state %s: %s\n", path.c_str(), why.c_str());
    return false;
  }
  if (!map->from_json(text, &why)) {
    std::fprintf(stderr, "main_robot: cannot load state %s: %s\n", path.c_str(), why.c_str());
    return false;
  }
  std::fprintf(stderr, "main_robot: resumed from %s (version %lld, %d static, %d moving)\n", path.c_str(),
               (long long)map->version(), map->count(GlobalStatus::kStatic), map->count(GlobalStatus::kMoving));
  return true;
}

void final_line(const MainNode& node) {
  const auto& c = node.counters();
  std::fprintf(stderr, "main_robot: events=%lld snapshots=%lld duplicates=%lld gaps=%lld rejected=%lld "
               "decode_errors=%lld notices=%lld static=%d moving=%d version=%lld maps=%lld map_chunks=%lld "
               "moving_sets=%lld stale_poses=%lld runs_started=%lld occupied=%lld team_map_left_out=%lld\n",
               (long long)c.events, (long long)c.snapshots, (long long)c.duplicates, (long long)c.gaps,
               (long long)c.rejected_inputs, (long long)c.decode_errors, (long long)c.notices_sent,
               node.map().count(GlobalStatus::kStatic), node.map().count(GlobalStatus::kMoving),
               (long long)node.map().version(), (long long)c.maps_published, (long long)c.map_chunks,
               (long long)c.moving_sets, (long long)c.stale_poses, (long long)c.runs_started,
               (long long)c.occupied, (long long)node.map().rounds_left_out());
}

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
    std::fflush(stdout);
    return transport::check_team_key(a.transport, cfg.path, "main_robot");
  }
  transport::install_stop_handlers();  // before LCM and the start line (process.hpp)
  int open_rc = 1;  // authenticated when a team key is configured (transport/process.hpp)
  const auto lcm = transport::open_lcm(a.transport, cfg.path, transport::auth::kSenderMain, "main_robot", &open_rc);
  if (!lcm) return open_rc;
  transport::NodeShell shell(*lcm, transport::ShellOptions("main_robot", a.transport.channel_suffix));
  MainNode node(o);
  node.set_incarnation(transport::now_utime());  // a later start has a larger one (landmark_event_t)
  MainPorts<transport::NodeShell> ports(shell, node);
  if (!resume(a.state, &node.map())) return 2;
  if (!ports.open(a.queues)) {
    shell.say("cannot subscribe");
    return 1;
  }
  std::fprintf(stderr, "main_robot: %s, config %s (%s), lcm=%s\n", cli::version_line("main_robot").c_str(),
               cfg.path.c_str(), cfg.origin.c_str(), transport::describe_url(a.transport.lcm_url).c_str());
  using Clock = transport::NodeShell::Clock;
  const auto map_period_us = static_cast<std::int64_t>(1e6 / o.publish_rate_hz);
  shell.every(std::chrono::microseconds(map_period_us), [&] { ports.publish_map_if_quiet(map_period_us); });
  shell.every(std::chrono::seconds(1), [&] { ports.publish_status(); });
  const auto save_period = std::chrono::milliseconds(static_cast<std::int64_t>(o.state_save_interval_s * 1000));
  auto next_save = Clock::now();
  std::int64_t saved_version = node.map().version();
  shell.every(Clock::duration::zero(), [&] {  // each turn: saved on change, at most once a save_period
    const auto now = Clock::now();
    if (a.state.empty() || now < next_save || node.map().version() == saved_version) return;
    save_state(node.map(), a.state);
    saved_version = node.map().version();
    next_save = now + save_period;
  });
  shell.spin(5);  // a transport failure is logged; the map is still published and saved
  ports.publish_map();
  ports.publish_status();
  if (!a.state.empty()) save_state(node.map(), a.state);
  final_line(node);
  return 0;
}

}  // namespace
}  // namespace elaslam

int main(int argc, char** argv) {
  return elaslam::cli::guarded_main("main_robot", [&] {
    namespace cli = elaslam::cli;
    elaslam::Args a;
    CLI::App app{"elaslam main_robot: the team's global map, on LCM"};
    cli::add_version_flag(app, "main_robot");
    cli::add_config_option(app, &a.config, "its main: section");
    app.add_option("--state", a.state, "file to persist the global map in (reloaded at start)");
    elaslam::transport::add_transport_options(app, &a.transport);
    app.add_option("--event-queue", a.queues.event, "LMAP_EVENT subscription queue capacity")
        ->check(cli::range(1, 1000000));
    app.add_option("--events-queue", a.queues.events, "LMAP_EVENTS subscription queue capacity")
        ->check(cli::range(1, 1000000));
    app.add_flag("--check", a.check, "check the configuration, print where it came from and exit (0: valid)");
    if (const int rc = cli::parse(app, argc, argv); rc >= 0) return rc;
    return elaslam::run(a);
  });
}

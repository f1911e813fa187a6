// SPDX-License-Identifier: Apache-2.0
// viewer: the team live in a browser. Subscribes to the team's channels as a plain
// listener and serves a page that draws the global map, the robots and their health,
// pushed over Server-Sent Events; /state.json is the same state for scripts.
// Reads RUN_INFO, POSE_<r>, GLOBAL_MAP, DYNAMIC_NOTICE, STATUS_ROBOT_<r>,
// CANDIDATES_<r>, TRACKS_<r>, GLOBAL_TRACKS and GROUND_TRUTH (viewer/STATE_SCHEMA.md).
//   viewer [--config FILE] [--port P] [--bind ADDR] [--token-file FILE] [--http-netns PATH]
//          [--rate HZ] [--max-clients N] [--lcm-url URL] [--channel-suffix S] [--key-file FILE]
//   viewer --make-token FILE
// The LCM URL is --lcm-url, else $LCM_DEFAULT_URL. It listens on 127.0.0.1 unless
// --bind says otherwise; --port 0 takes a free port. It prints "viewer: http://..."
// on stdout once it listens (with "?token=..." when it has a token). --http-netns PATH
// (root; /run/netns/NAME or /proc/PID/ns/net): the HTTP socket is opened in that
// network namespace and LCM in the process's own, so a team running in a private
// namespace (tools/run_team.sh --view) is seen from a browser on the host.
// Access (docs/security.md, "The viewer as an HTTP service"): a peer on this machine's loopback (127.0.0.0/8,
// ::1) needs nothing; any other must show the token of --token-file (a file of 64+
// hexadecimal digits, mode 0600, made by --make-token FILE) as "Authorization: Bearer
// TOKEN" or "?token=TOKEN", else 401. A --bind that is not loopback without a token
// is refused (exit 2).
// Never slows the team, never falls over: LCM queues are bounded (drops are LCM's,
// seen as gaps in a robot's POSE frames and counted); each browser gets only the newest
// state (a slow one skips states); at most --max-clients event streams at once, one
// whose reader takes nothing for 5 s is closed and a new one may evict a stalled one;
// a request must arrive whole within 5 s, with at most 100 header lines and 16 KiB of
// head; at most 256 connections (64 per address), the rest refused at once (503).
// SIGINT / SIGTERM end it (exit 0).
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

#include "elaslam/common/cli.hpp"
#include "elaslam/common/config.hpp"
#include "elaslam/transport/auth_transport.hpp"
#include "elaslam/transport/node_shell.hpp"
#include "elaslam/transport/process.hpp"
#include "elaslam/viewer/view_ports.hpp"
#include "elaslam/viewer/view_state.hpp"

// Last: httplib's system headers define macros that break Eigen's (pulled in above).
#include "http_service.hpp"

namespace {

using namespace elaslam;
using viewer::ViewLimits;
using viewer::ViewState;

/// The config's main: bounds the state checks messages against: -1 to go on, else 2
/// after saying why.
int read_view_limits(const std::string& config, std::string* config_path, ViewLimits* limits) {
  try {
    *config_path = cli::find_config(config).path;
    *limits = viewer::load_view_limits(*config_path);
  } catch (const config::ConfigError& e) {
    std::fprintf(stderr, "viewer: %s\n", e.what());
    return cli::kExitBadInput;
  }
  return -1;
}

/// Builds the state for Latest when a message changed it, else once a second (status
/// ages, counters).
class StatePublisher {
 public:
  StatePublisher(const ViewState& state, const transport::NodeShell& shell,
                 const viewer::ViewPorts<transport::NodeShell>& ports, const viewer::GuardedServer& http,
                 viewer::Latest& latest, double rate_hz)
      : state_(state), shell_(shell), ports_(ports), http_(http), latest_(latest), rate_hz_(rate_hz) {}

  void operator()() {
    const auto now = std::chrono::steady_clock::now();
    if (state_.changes() == built_changes_ && now - built_at_ < std::chrono::seconds(1)) return;
    built_changes_ = state_.changes();
    built_at_ = now;
    const transport::ShellCounters c = shell_.counters();
    const long long bad = static_cast<long long>(state_.bad_messages() + c.inputs.decode_errors + c.auth_refused);
    latest_.put(state_.to_json(ports_.now_s(), viewer::viewer_counters_json(static_cast<long long>(c.inputs.received),
                                                                            bad, ports_.missed_poses(),
                                                                            http_.event_streams(), rate_hz_)));
  }

 private:
  const ViewState& state_;
  const transport::NodeShell& shell_;
  const viewer::ViewPorts<transport::NodeShell>& ports_;
  const viewer::GuardedServer& http_;
  viewer::Latest& latest_;
  double rate_hz_;
  long long built_changes_ = -1;
  std::chrono::steady_clock::time_point built_at_ = std::chrono::steady_clock::now();
};

int viewer_main(int argc, char** argv) {
  viewer::ViewerOptions o;
  if (const int rc = viewer::parse_viewer_options(argc, argv, &o); rc >= 0) return rc;
  std::string token;
  if (const int rc = viewer::load_viewer_token(o, &token); rc >= 0) return rc;
  std::string config_path;
  ViewLimits limits;
  if (const int rc = read_view_limits(o.config, &config_path, &limits); rc >= 0) return rc;

  viewer::GuardedServer http(viewer::HttpLimits{}, o.max_clients);
  int bind_rc = 1;
  const int bound = viewer::bind_http(http, o, &bind_rc);
  if (bound <= 0) return bind_rc;

  int open_rc = 1;
  const auto lcm =
      transport::open_lcm(o.transport, config_path, transport::kSenderTool, false, 0, "viewer", &open_rc, nullptr);
  if (!lcm) return open_rc;
  transport::NodeShell shell(*lcm, transport::ShellOptions("viewer", o.transport.channel_suffix, nullptr));
  ViewState state(limits);
  viewer::ViewPorts<transport::NodeShell> ports(shell, state);
  if (!ports.open()) {
    std::fprintf(stderr, "viewer: the transport refused a subscription\n");
    return 1;
  }

  viewer::Latest latest;
  const viewer::AccessPolicy access(token);
  viewer::add_routes(http, latest, access);
  transport::install_stop_handlers();
  StatePublisher publish(state, shell, ports, http, latest, o.rate_hz);
  publish();  // an empty state, never "{}", before the first browser asks
  std::thread server([&] { http.listen_after_bind(); });
  shell.every(std::chrono::milliseconds(static_cast<long long>(1000.0 / o.rate_hz)), [&] { publish(); });
  std::printf("viewer: %s\n", viewer::viewer_url(o.bind, bound, token).c_str());
  std::fflush(stdout);
  const auto exit = shell.spin(50);
  latest.stop();
  http.shutdown();
  server.join();
  if (exit == transport::NodeShell::Exit::kTransportError) {
    std::fprintf(stderr, "viewer: LCM handle error\n");
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return elaslam::cli::guarded_main("viewer", [&] { return viewer_main(argc, argv); });
}

// viewer: the team live in a browser. Subscribes to the team's channels as a plain
// listener and serves a page that draws the global map, the robots and their health,
// pushed over Server-Sent Events; /state.json is the same state for scripts.
// Reads RUN_INFO, POSE_<r>, GLOBAL_MAP, DYNAMIC_NOTICE, STATUS_ROBOT_<r>,
// CANDIDATES_<r> and GROUND_TRUTH (viewer/STATE_SCHEMA.md).
//   viewer [--config FILE] [--port P] [--bind ADDR] [--http-netns PATH] [--rate HZ]
//          [--lcm-url URL] [--channel-suffix S] [--key-file FILE]
// The LCM URL is --lcm-url, else $LCM_DEFAULT_URL. It listens on 127.0.0.1 unless
// --bind says otherwise; --port 0 takes a free port. It prints "viewer: http://..."
// on stdout once it listens. --http-netns PATH (root; /run/netns/NAME or
// /proc/PID/ns/net): the HTTP socket is opened in that network namespace and LCM in
// the process's own, so a team running in a private namespace (tools/run_team.sh
// --view) is seen from a browser on the host.
// Never slows the team: LCM queues are bounded (drops are LCM's, seen as gaps in a
// robot's POSE frames and counted), each browser gets only the newest state (a slow
// one skips states; a stalled one is dropped after the write timeout), at most
// --max-clients event streams at once. SIGINT / SIGTERM end it (exit 0).
#include <arpa/inet.h>
#include <fcntl.h>
#include <sched.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include <CLI/CLI.hpp>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/cli.hpp"
#include "elaslam/common/config.hpp"
#include "elaslam/main_robot/global_map.hpp"
#include "elaslam/transport/auth_transport.hpp"
#include "elaslam/transport/node_shell.hpp"
#include "elaslam/transport/process.hpp"
#include "elaslam/viewer/view_ports.hpp"
#include "elaslam/viewer/view_state.hpp"

// Last: its system headers define macros that break Eigen's (pulled in above).
#include <httplib.h>

namespace elaslam::viewer {
extern const char* const kIndexHtml;  // viewer/web/index.html, embedded at build time
}

namespace {

using namespace elaslam;
using viewer::ViewLimits;
using viewer::ViewState;

/// The newest state, shared between the LCM thread (writer) and the HTTP threads.
class Latest {
 public:
  void put(std::string json) {
    {
      std::lock_guard<std::mutex> l(m_);
      json_ = std::make_shared<const std::string>(std::move(json));
      ++seq_;
    }
    cv_.notify_all();
  }
  /// The state after `after` (waits at most `wait`); nullptr when none came or stopping.
  std::shared_ptr<const std::string> next(long long* after, std::chrono::milliseconds wait) {
    std::unique_lock<std::mutex> l(m_);
    cv_.wait_for(l, wait, [&] { return seq_ > *after || stopping_; });
    if (stopping_ || seq_ <= *after) return nullptr;
    *after = seq_;
    return json_;
  }
  std::shared_ptr<const std::string> now() {
    std::lock_guard<std::mutex> l(m_);
    return json_;
  }
  void stop() {
    {
      std::lock_guard<std::mutex> l(m_);
      stopping_ = true;
    }
    cv_.notify_all();
  }

 private:
  std::mutex m_;
  std::condition_variable cv_;
  std::shared_ptr<const std::string> json_ = std::make_shared<const std::string>("{}");  // replaced before serving
  long long seq_ = 0;
  bool stopping_ = false;
};

/// Enter the network namespace at `path`: 0, or the exit code after saying why
/// (2: no such namespace, bad input; 1: not allowed to enter it).
int enter_netns(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    std::fprintf(stderr, "viewer: cannot open the network namespace %s: %s\n", path.c_str(), std::strerror(errno));
    return 2;
  }
  const int rc = ::setns(fd, CLONE_NEWNET);
  const int err = errno;
  ::close(fd);
  if (rc == 0) return 0;
  std::fprintf(stderr, "viewer: cannot enter the network namespace %s: %s\n", path.c_str(), std::strerror(err));
  return err == EINVAL ? 2 : 1;  // EINVAL: the file is not a network namespace
}

int viewer_main(int argc, char** argv) {
  transport::TransportArgs targs;
  std::string config, bind = "127.0.0.1", http_netns;
  int port = 8765, max_clients = 8;
  double rate_hz = 20.0;
  CLI::App app{"elaslam viewer: the team's map, robots and health in a browser (Server-Sent Events)"};
  cli::add_version_flag(app, "viewer");
  cli::add_config_option(app, &config, "its main: section (landmark ids, bounds) and team: section (the team key)");
  transport::add_transport_options(app, &targs);
  app.add_option("--port", port, "HTTP port (0: any free port)")->capture_default_str()->check(cli::range(0, 65535));
  app.add_option("--bind", bind, "address to listen on (127.0.0.1: this machine only)")->capture_default_str();
  app.add_option("--http-netns", http_netns,
                 "open the HTTP socket in this network namespace (/run/netns/NAME, /proc/PID/ns/net); LCM stays in the process's own");
  app.add_option("--rate", rate_hz, "states pushed per second")->capture_default_str()->check(cli::range(1.0, 100.0));
  app.add_option("--max-clients", max_clients, "event streams served at once")
      ->capture_default_str()
      ->check(cli::range(1, 64));
  if (const int rc = cli::parse(app, argc, argv); rc >= 0) return rc;
  in6_addr any_address{};
  if (::inet_pton(AF_INET, bind.c_str(), &any_address) != 1 && ::inet_pton(AF_INET6, bind.c_str(), &any_address) != 1) {
    std::fprintf(stderr, "--bind: '%s' is not an IPv4 or IPv6 address\n", bind.c_str());
    return 2;
  }

  std::string config_path;
  GlobalMapOptions mo;
  try {
    config_path = cli::find_config(config).path;
    config::Document doc = config::Document::from_file(config_path);
    doc.section("main", [&](config::Reader& r) { parse(r, &mo); });
    doc.allow_sections();
    doc.finish();
  } catch (const config::ConfigError& e) {
    std::fprintf(stderr, "viewer: %s\n", e.what());
    return 2;
  }
  ViewLimits limits;
  limits.max_landmark_id = mo.max_landmark_id;
  limits.world_bound_m = mo.limits.world_bound;

  httplib::Server http;
  http.set_write_timeout(5, 0);  // a stalled browser is dropped, never waited for
  // A thread per connection: the event streams (at most max_clients) and room for
  // /, /state.json and the refusals beyond that, whatever the streams do.
  http.new_task_queue = [max_clients] { return new httplib::ThreadPool(static_cast<std::size_t>(max_clients) + 4); };
  // The HTTP socket in --http-netns, then back to our own namespace for LCM.
  const std::string own_netns = "/proc/self/ns/net";
  const int own = http_netns.empty() ? -1 : ::open(own_netns.c_str(), O_RDONLY | O_CLOEXEC);
  if (own < 0 && !http_netns.empty()) {
    std::fprintf(stderr, "viewer: cannot open %s: %s\n", own_netns.c_str(), std::strerror(errno));
    return 1;
  }
  if (!http_netns.empty()) {
    if (const int rc = enter_netns(http_netns); rc != 0) {
      ::close(own);
      return rc;
    }
  }
  const int bound = port == 0 ? http.bind_to_any_port(bind) : (http.bind_to_port(bind, port) ? port : -1);
  if (own >= 0) {
    const int rc = ::setns(own, CLONE_NEWNET);
    ::close(own);
    if (rc != 0) {
      std::perror("viewer: cannot return to its own network namespace");
      return 1;
    }
  }
  if (bound <= 0) {
    std::fprintf(stderr, "viewer: cannot listen on %s:%d (in use? another --port)\n", bind.c_str(), port);
    return 1;
  }

  int open_rc = 1;
  const auto lcm = transport::open_lcm(targs, config_path, transport::kSenderTool, false, 0, "viewer", &open_rc, nullptr);
  if (!lcm) return open_rc;
  transport::NodeShell shell(*lcm, transport::ShellOptions("viewer", targs.channel_suffix, nullptr));
  ViewState state(limits);
  viewer::ViewPorts<transport::NodeShell> ports(shell, state);
  if (!ports.open()) {
    std::fprintf(stderr, "viewer: the transport refused a subscription\n");
    return 1;
  }

  Latest latest;
  std::atomic<int> clients{0};
  const auto period = std::chrono::milliseconds(static_cast<long long>(1000.0 / rate_hz));
  http.Get("/", [](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    res.set_content(viewer::kIndexHtml, "text/html; charset=utf-8");
  });
  http.Get("/state.json", [&](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    res.set_content(*latest.now(), "application/json");
  });
  http.Get("/events", [&](const httplib::Request&, httplib::Response& res) {
    if (clients.fetch_add(1) >= max_clients) {
      clients.fetch_sub(1);
      res.status = 503;
      res.set_content("too many event streams\n", "text/plain");
      return;
    }
    res.set_header("Cache-Control", "no-store");
    auto seen = std::make_shared<long long>(0);
    res.set_chunked_content_provider(
        "text/event-stream",
        [&latest, seen](std::size_t, httplib::DataSink& sink) {
          // Only the newest state: a slow browser skips states, it never queues them.
          const auto json = latest.next(seen.get(), std::chrono::milliseconds(1000));
          if (!json) {
            if (!sink.is_writable()) return false;
            static const char kKeepAlive[] = ": keep-alive\n\n";
            return sink.write(kKeepAlive, sizeof kKeepAlive - 1);
          }
          std::string event = "event: state\ndata: ";
          event += *json;
          event += "\n\n";
          return sink.write(event.data(), event.size());
        },
        [&clients](bool) { clients.fetch_sub(1); });
  });
  transport::install_stop_handlers();
  // Rebuilt when a message changed it, else once a second (status ages, counters).
  long long built_changes = -1;
  auto built_at = std::chrono::steady_clock::now();
  auto publish = [&] {
    const auto now = std::chrono::steady_clock::now();
    if (state.changes() == built_changes && now - built_at < std::chrono::seconds(1)) return;
    built_changes = state.changes();
    built_at = now;
    const transport::ShellCounters c = shell.counters();
    char counters[256];
    std::snprintf(counters, sizeof counters,
                  "{\"messages\":%lld,\"bad_messages\":%lld,\"queue_drops\":%lld,\"clients\":%d,\"updates_per_s\":%g}",
                  static_cast<long long>(c.inputs.received),
                  static_cast<long long>(state.bad_messages() + c.inputs.decode_errors + c.auth_refused),
                  ports.missed_poses(), clients.load(), rate_hz);
    latest.put(state.to_json(ports.now_s(), counters));
  };
  publish();  // an empty state, never "{}", before the first browser asks
  std::thread server([&] { http.listen_after_bind(); });
  shell.every(period, publish);
  // Listening on every address: this machine's loopback is one of them.
  const std::string host = bind == "0.0.0.0" ? "127.0.0.1" : bind == "::" ? "[::1]"
                           : bind.find(':') != std::string::npos ? "[" + bind + "]" : bind;
  std::printf("viewer: http://%s:%d/\n", host.c_str(), bound);
  std::fflush(stdout);
  const auto exit = shell.spin(50);
  latest.stop();
  http.stop();
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

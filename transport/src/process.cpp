#include "elaslam/transport/process.hpp"

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>

#include <CLI/CLI.hpp>

#include "elaslam/transport/lcm_transport.hpp"

namespace elaslam::transport {
namespace {

extern "C" void on_stop_signal(int) { stop_flag().store(true); }

}  // namespace

std::int64_t now_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::atomic<bool>& stop_flag() {
  static std::atomic<bool> flag{false};
  return flag;
}

void install_stop_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

void add_transport_options(CLI::App& app, TransportArgs* args) {
  app.add_option("--lcm-url", args->lcm_url, "LCM URL (default: $LCM_DEFAULT_URL, else LCM's default)");
  app.add_option("--channel-suffix", args->channel_suffix, "suffix appended to every channel name")
      ->check(CLI::Validator(
          [](std::string& s) {
            for (char c : s)
              if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_')
                return std::string("a channel suffix has letters, digits and '_' only");
            return std::string();
          },
          "[A-Za-z0-9_]*", "channel suffix"));
}

namespace {

/// The URL LCM opens: `url`, else $LCM_DEFAULT_URL, else "" (LCM's own default).
std::string effective_url(const std::string& url) {
  if (!url.empty()) return url;
  const char* env = std::getenv("LCM_DEFAULT_URL");
  return env ? env : "";
}

}  // namespace

std::string describe_url(const std::string& url) {
  const std::string used = effective_url(url);
  if (used.empty()) return "LCM default (udpm://239.255.76.67:7667?ttl=0)";
  return url.empty() ? used + " (LCM_DEFAULT_URL)" : used;
}

std::unique_ptr<Transport> open_lcm(const std::string& url, const std::string& who) {
  auto t = std::make_unique<LcmTransport>(effective_url(url));
  if (t->good()) return t;
  std::fprintf(stderr,
               "%s: cannot open LCM (%s). Multicast on loopback needs a route: ip route add 224.0.0.0/4 dev lo "
               "(see tools/netns_run.sh)\n",
               who.c_str(), describe_url(url).c_str());
  return nullptr;
}

}  // namespace elaslam::transport

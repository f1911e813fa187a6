// What every process's main() shares around its node shell: the stop flag that
// SIGINT / SIGTERM set, the wall clock that stamps messages, the --lcm-url and
// --channel-suffix options, and opening LCM with an error that says what to do.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "elaslam/transport/transport.hpp"

namespace CLI {
class App;
}

namespace elaslam::transport {

/// Wall-clock microseconds since the epoch (message utime).
std::int64_t now_utime();

/// Set by SIGINT / SIGTERM once install_stop_handlers() ran (a test may set or clear it).
std::atomic<bool>& stop_flag();
/// SIGINT and SIGTERM set stop_flag(). No SA_RESTART: a blocking wait returns early.
void install_stop_handlers();

struct TransportArgs {
  std::string lcm_url;         // "" : $LCM_DEFAULT_URL, else LCM's default
  std::string channel_suffix;  // e.g. "_SIM2": two teams on one LCM network
};

/// --lcm-url and --channel-suffix (letters, digits and '_': the suffix becomes part of
/// subscription patterns, where other characters would mean something).
void add_transport_options(CLI::App& app, TransportArgs* args);

/// The URL for start-up lines: the given one, else $LCM_DEFAULT_URL (so marked), else
/// LCM's default.
std::string describe_url(const std::string& url);

/// The LCM transport for `url`; nullptr, after printing why to stderr as `who`, when
/// it cannot be opened.
std::unique_ptr<Transport> open_lcm(const std::string& url, const std::string& who);

}  // namespace elaslam::transport

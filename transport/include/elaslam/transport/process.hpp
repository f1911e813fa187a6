// What every process's main() shares around its node shell: the stop flag that
// SIGINT / SIGTERM set, the wall clock that stamps messages, the --lcm-url,
// --channel-suffix and --key-file options, and opening LCM (authenticated when a
// team key is configured: auth_transport.hpp) with an error that says what to do.
#pragma once

#include <atomic>
#include <cstdio>
#include <cstdint>
#include <memory>
#include <string>

#include "elaslam/transport/team_key.hpp"
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
  std::string key_file;        // --key-file: the team key, over the config's team.key_file
};

/// --lcm-url, --channel-suffix (letters, digits and '_': the suffix becomes part of
/// subscription patterns, where other characters would mean something) and --key-file.
void add_transport_options(CLI::App& app, TransportArgs* args);

/// The team key file: --key-file, else team.key_file of the config at `config_path`
/// ("" : no config), else "" (authentication off). A systemd service gets the
/// configured key as its credential team.key (LoadCredential= in the units: its
/// dynamic user cannot read the root-only file itself): when the config names a key
/// and $CREDENTIALS_DIRECTORY/team.key exists, that is the file. *origin (optional)
/// says where the path came from. Throws config::ConfigError when the config's team:
/// section is not valid.
std::string team_key_file(const TransportArgs& args, const std::string& config_path, std::string* origin = nullptr);

/// The configured team key (team_key_file), loaded and checked as a process does at
/// start: *key empty when none is configured. False, after printing why to stderr as
/// `who`, when the team: section or the key file is not acceptable.
bool configured_team_key(const TransportArgs& args, const std::string& config_path, const std::string& who,
                         TeamKey* key, std::string* path, std::string* origin);

/// --check's part for authentication: prints whether it is on and with which key file,
/// on stdout; 0, or 2 (said why on stderr) when the key would stop the process at start.
int check_team_key(const TransportArgs& args, const std::string& config_path, const std::string& who);

/// The URL for start-up lines: the given one, else $LCM_DEFAULT_URL (so marked), else
/// LCM's default.
std::string describe_url(const std::string& url);

/// The LCM transport for `url`; nullptr, after printing why to stderr as `who`, when
/// it cannot be opened.
std::unique_ptr<Transport> open_lcm(const std::string& url, const std::string& who);

/// The process's transport: LCM at args.lcm_url, wrapped in an AuthenticatedTransport
/// (auth_transport.hpp) as `sender_id` with a new incarnation (the wall clock) when a
/// team key is configured (team_key_file). nullptr, after printing why to stderr as
/// `who`, when it cannot be opened; *exit_code is then 2 for a configuration error
/// (the key file or the team: section: restarting will not help) and 1 for LCM.
/// Refused messages are said on `log` at a bounded rate (nullptr: counted only).
std::unique_ptr<Transport> open_lcm(const TransportArgs& args, const std::string& config_path, std::int16_t sender_id,
                                    const std::string& who, int* exit_code, std::FILE* log = stderr);

}  // namespace elaslam::transport

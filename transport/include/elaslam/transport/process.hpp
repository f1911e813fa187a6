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
/// A node calls it before it opens LCM and says it runs: a stop from then on, at
/// whatever point it comes, is seen by the node's loop first thing and is the
/// orderly exit (state saved, exit 0), never death by the signal, for whoever stops
/// it (a test, systemd, run_team.sh).
void install_stop_handlers();

struct TransportArgs {
  std::string lcm_url;         // "" : $LCM_DEFAULT_URL, else LCM's default
  std::string channel_suffix;  // e.g. "_SIM2": two teams on one LCM network
  std::string key_file;        // --key-file: the team key, over the config's team.key_file
  bool channel_groups = false;  // --channel-groups: one port per channel group, or the config's team.channel_groups
};

/// The config's team: section (all optional): the team key file and channel groups.
struct TeamSection {
  std::string key_file;         // "" : authentication off
  bool channel_groups = false;  // grouped_lcm_transport.hpp
};

/// The team: section of the config at `config_path` ("" : none, the defaults). Throws
/// config::ConfigError when it is not valid.
TeamSection read_team_section(const std::string& config_path);

/// --lcm-url, --channel-suffix (letters, digits and '_': the suffix becomes part of
/// subscription patterns, where other characters would mean something), --key-file and
/// --channel-groups.
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

/// Whether the process opens LCM in channel groups: --channel-groups, else the
/// config's team.channel_groups. False, after printing why to stderr as `who`, when
/// the team: section is not valid or, with groups on, the LCM URL leaves them no
/// ports (not udpm://, or past port 65535): a configuration error.
bool channel_groups_on(const TransportArgs& args, const std::string& config_path, const std::string& who, bool* on);

/// --check's part for the transport: prints on stdout whether authentication is on
/// and with which key file, and whether channel groups are on and on which ports; 0,
/// or 2 (said why on stderr) when the key or the groups would stop the process at
/// start.
int check_team_key(const TransportArgs& args, const std::string& config_path, const std::string& who);

/// The URL for start-up lines: the given one, else $LCM_DEFAULT_URL (so marked), else
/// LCM's default.
std::string describe_url(const std::string& url);

/// The LCM transport for `url` (with `channel_groups`: one port per group of the
/// channels with `suffix`, grouped_lcm_transport.hpp); nullptr, after printing why to
/// stderr as `who`, when it cannot be opened.
std::unique_ptr<Transport> open_lcm(const std::string& url, const std::string& who, bool channel_groups = false,
                                    const std::string& suffix = "");

/// The process's transport: LCM at args.lcm_url (in channel groups with
/// --channel-groups or the config's team.channel_groups), wrapped in an AuthenticatedTransport
/// (auth_transport.hpp) as `sender_id` with a new incarnation (the wall clock) when a
/// team key is configured (team_key_file). nullptr, after printing why to stderr as
/// `who`, when it cannot be opened; *exit_code is then 2 for a configuration error
/// (the key file, the team: section, a URL without room for the channel groups:
/// restarting will not help) and 1 for LCM.
/// Refused messages are said on `log` at a bounded rate (nullptr: counted only).
std::unique_ptr<Transport> open_lcm(const TransportArgs& args, const std::string& config_path, std::int16_t sender_id,
                                    const std::string& who, int* exit_code, std::FILE* log = stderr);

}  // namespace elaslam::transport

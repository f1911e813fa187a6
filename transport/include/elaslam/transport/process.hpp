// SPDX-License-Identifier: Apache-2.0
// What every process's main() shares around its node shell: the stop flag that
// SIGINT / SIGTERM set, the wall clock that stamps messages, the --lcm-url,
// --channel-suffix, --key-file and --mission options, and opening LCM (authenticated
// when the team's public keys are configured: auth_transport.hpp) with an error that
// says what to do.
#pragma once

#include <array>
#include <atomic>
#include <cstdio>
#include <cstdint>
#include <memory>
#include <string>

#include <utility>
#include <vector>

#include "elaslam/transport/auth_transport.hpp"
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
  std::string key_file;        // --key-file: this node's secret key, over the config's team.key_file
  std::string mission;         // --mission: the mission id, over the roster's team.mission
  std::string roster;          // --roster: the team's roster file, over the config's
  bool channel_groups = false;  // --channel-groups: one port per channel group, or the config's team.channel_groups
};

/// The config's team: section (all optional; docs/security.md "Keys and missions").
/// The roster (mission, public_keys, revoked) is either in it or in the roster file
/// it names, a YAML file with a team: section of those three keys (what
/// `elaslam-keys team` writes).
struct TeamSection {
  std::string key_file;         // this node's secret key (nodes that send); "{sender}": the sender's name
  std::string roster_file;      // the roster, in a file of its own
  std::string mission;          // 16 hexadecimal digits
  /// The roster: sender name (robot_<r>, main, simulator, tool) -> one public key, or
  /// two separated by a space (while the sender's key is rotated), 64 hexadecimal digits each.
  std::vector<std::pair<std::string, std::string>> public_keys;
  std::string revoked;          // public keys no message may be signed with, separated by spaces
  bool channel_groups = false;  // grouped_lcm_transport.hpp
};

/// The team: section of the config at `config_path` ("" : none, the defaults), with the
/// roster file it names read too unless `roster` is false (--roster replaces it).
/// Throws config::ConfigError when it is not valid: a name that is no sender, a key or
/// a mission that is not hexadecimal of the right length.
TeamSection read_team_section(const std::string& config_path, bool roster = true);

/// A roster file (a team: section of mission, public_keys and revoked only) into *t's
/// roster fields, which it replaces. Throws config::ConfigError when it is not valid.
void read_roster_file(const std::string& path, TeamSection* t);

/// --lcm-url, --channel-suffix (letters, digits and '_': the suffix becomes part of
/// subscription patterns, where other characters would mean something), --key-file,
/// --mission, --roster and --channel-groups.
void add_transport_options(CLI::App& app, TransportArgs* args);

/// This node's secret key file: --key-file, else team.key_file of the config at
/// `config_path` ("" : no config), with "{sender}" replaced by `sender` (the node's
/// sender name: robot_2, main, ...), else "". A systemd service gets the configured key
/// as its credential node.key (LoadCredential= in the units: its dynamic user cannot
/// read the root-only file itself): when the config names a key and
/// $CREDENTIALS_DIRECTORY/node.key exists, that is the file. *origin (optional) says
/// where the path came from. Throws config::ConfigError when the team: section is not valid.
std::string node_key_file(const TransportArgs& args, const std::string& config_path, const std::string& sender,
                          std::string* origin = nullptr);

/// Authentication as configured for sender `sender_id` (kSenderTool for a process that
/// only receives): on when the config's team.public_keys lists keys. Then the mission
/// (--mission, team.mission) is required, and a sender (`sends`) needs its secret key
/// (node_key_file), whose public key the roster must list under its sender name.
/// *setup filled (its incarnation and suffix left to the caller), *on set; false,
/// after printing why to stderr as `who`, when any of it is not acceptable.
/// *description (optional): one line for the start-up log.
bool configured_auth(const TransportArgs& args, const std::string& config_path, const std::string& who,
                     std::int16_t sender_id, bool sends, auth::AuthSetup* setup, bool* on,
                     std::string* description = nullptr);

/// Whether the process opens LCM in channel groups: --channel-groups, else the
/// config's team.channel_groups. False, after printing why to stderr as `who`, when
/// the team: section is not valid or, with groups on, the LCM URL leaves them no
/// ports (not udpm://, or past port 65535): a configuration error.
bool channel_groups_on(const TransportArgs& args, const std::string& config_path, const std::string& who, bool* on);

/// --check's part for the transport: prints on stdout whether authentication is on
/// (the roster, the mission, this node's key) and whether channel groups are on and on
/// which ports; 0, or 2 (said why on stderr) when the keys or the groups would stop the
/// process at start.
int check_transport(const TransportArgs& args, const std::string& config_path, const std::string& who,
                    std::int16_t sender_id, bool sends);

/// The URL for start-up lines: the given one, else $LCM_DEFAULT_URL (so marked), else
/// LCM's default.
std::string describe_url(const std::string& url);

/// The LCM transport for `url` (with `channel_groups`: one port per group of the
/// channels with `suffix`, grouped_lcm_transport.hpp); nullptr, after printing why to
/// stderr as `who`, when it cannot be opened.
std::unique_ptr<Transport> open_lcm(const std::string& url, const std::string& who, bool channel_groups = false,
                                    const std::string& suffix = "");

/// The process's transport: LCM at args.lcm_url (in channel groups with
/// --channel-groups or the config's team.channel_groups), wrapped in an
/// AuthenticatedTransport (auth_transport.hpp) as `sender_id` with `incarnation`
/// (incarnation.hpp) when authentication is configured (configured_auth; `sends`:
/// whether the process publishes, and so needs its key). nullptr, after printing why
/// to stderr as `who`, when it cannot be opened; *exit_code is then 2 for a
/// configuration error (a key file, the team: section, a URL without room for the
/// channel groups: restarting will not help) and 1 for LCM.
/// Refused messages are said on `log` at a bounded rate (nullptr: counted only).
/// `auth` (optional): what authentication the process runs with (for its own files).
struct AuthInfo {
  bool on = false;                               // the team's roster is configured
  bool signs = false;                            // ... and this process signs with its own key
  std::uint64_t mission = 0;                     // the mission (on)
  std::array<std::uint8_t, kKeyBytes> file_key{};  // the key of its own files of this mission (signs)
};
std::unique_ptr<Transport> open_lcm(const TransportArgs& args, const std::string& config_path, std::int16_t sender_id,
                                    bool sends, std::int64_t incarnation, const std::string& who, int* exit_code,
                                    std::FILE* log = stderr, AuthInfo* auth = nullptr);

}  // namespace elaslam::transport

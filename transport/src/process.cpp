// SPDX-License-Identifier: Apache-2.0
#include "elaslam/transport/process.hpp"

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <system_error>

#include <CLI/CLI.hpp>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/config.hpp"
#include "elaslam/common/log.hpp"
#include "elaslam/transport/auth_transport.hpp"
#include "elaslam/transport/grouped_lcm_transport.hpp"
#include "elaslam/transport/lcm_transport.hpp"
#include "elaslam/transport/keys.hpp"

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
  app.add_option("--key-file", args->key_file,
                 "this node's secret key: sign what it sends (default: the config's team.key_file)");
  app.add_option("--mission", args->mission,
                 "the mission id, 16 hexadecimal digits (default: the roster's team.mission)");
  app.add_option("--roster", args->roster,
                 "the team's roster file (public keys, mission; elaslam-keys team writes one; default: the config's "
                 "team: section or its team.roster_file)");
  app.add_flag("--channel-groups", args->channel_groups,
               "one UDP port per channel group, from the URL's port up (default: the config's team.channel_groups)");
}

namespace {

/// The roster's keys of a team: section (the config's, or a roster file's).
void read_roster_keys(config::Reader& r, TeamSection* t) {
  r.read_optional("mission", &t->mission);
  std::uint64_t mission = 0;
  std::string why;
  if (r.has("mission") && !parse_mission(t->mission, &mission, &why)) r.fail("mission", why);
  r.read_optional("revoked", &t->revoked);
  r.section(
      "public_keys",
      [&](config::Reader& k) {
        for (std::int16_t id = 1; id <= kSenderTool; ++id) {
          const std::string name = sender_name(id);
          if (name.empty() || !k.has(name)) continue;
          std::string keys;
          k.read(name, &keys);
          t->public_keys.emplace_back(name, keys);
        }
      },
      true);
}

}  // namespace

TeamSection read_team_section(const std::string& config_path, bool roster) {
  TeamSection t;
  if (config_path.empty()) return t;
  config::Document doc = config::Document::from_file(config_path);
  bool inline_roster = false;
  doc.section(
      "team",
      [&](config::Reader& r) {
        r.read_optional("key_file", &t.key_file);
        r.read_optional("channel_groups", &t.channel_groups);
        r.read_optional("roster_file", &t.roster_file);
        inline_roster = r.has("mission") || r.has("public_keys") || r.has("revoked");
        if (inline_roster && !t.roster_file.empty())
          r.fail("roster_file", "the roster is either in the file it names or here (mission, public_keys, revoked), not both");
        read_roster_keys(r, &t);
      },
      true);
  doc.allow_sections();
  doc.finish();
  if (t.roster_file.empty() || !roster) return t;
  // The roster in a file of its own: a team: section with mission, public_keys and
  // revoked only. A relative path is relative to the config's directory.
  if (t.roster_file[0] != '/') {
    const std::size_t slash = config_path.rfind('/');
    if (slash != std::string::npos) t.roster_file = config_path.substr(0, slash + 1) + t.roster_file;
  }
  read_roster_file(t.roster_file, &t);
  return t;
}

void read_roster_file(const std::string& path, TeamSection* t) {
  t->mission.clear();
  t->public_keys.clear();
  t->revoked.clear();
  t->roster_file = path;
  config::Document roster = config::Document::from_file(path);
  roster.section("team", [&](config::Reader& r) { read_roster_keys(r, t); });
  roster.finish();
}

std::string node_key_file(const TransportArgs& args, const std::string& config_path, const std::string& sender,
                          std::string* origin) {
  std::string where;
  if (origin == nullptr) origin = &where;
  if (!args.key_file.empty()) {
    *origin = "--key-file";
    return args.key_file;
  }
  if (config_path.empty()) return "";
  std::string path = read_team_section(config_path, false).key_file;
  *origin = "team.key_file in " + config_path;
  // "{sender}" stands for the node's sender name: one config for every node of a team.
  if (const std::size_t at = path.find("{sender}"); at != std::string::npos && !sender.empty())
    path.replace(at, 8, sender);
  const char* creds = std::getenv("CREDENTIALS_DIRECTORY");
  if (path.empty() || creds == nullptr || *creds == '\0') return path;
  const std::string credential = std::string(creds) + "/node.key";
  std::error_code ec;
  if (!std::filesystem::exists(credential, ec)) return path;
  *origin += ", passed by systemd as the credential node.key (LoadCredential=)";
  return credential;
}

namespace {

/// The keys of a roster entry: one or two (a space between), each 64 hexadecimal digits.
bool parse_keys(const std::string& text, std::vector<PublicKey>* keys, std::string* why) {
  std::size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && (text[i] == ' ' || text[i] == ',')) ++i;
    if (i == text.size()) break;
    std::size_t j = i;
    while (j < text.size() && text[j] != ' ' && text[j] != ',') ++j;
    PublicKey k{};
    if (!from_hex(text.substr(i, j - i), k.data(), k.size())) {
      *why = "'" + text.substr(i, j - i) + "' is not a public key (64 hexadecimal digits; elaslam-keys public FILE prints one)";
      return false;
    }
    keys->push_back(k);
    i = j;
  }
  return true;
}

/// The roster and mission of the team: section (the command line's mission over it).
bool read_roster(const TransportArgs& args, const TeamSection& t, auth::AuthSetup* setup, std::string* why) {
  std::vector<PublicKey> revoked;
  if (!parse_keys(t.revoked, &revoked, why)) return *why = "team.revoked: " + *why, false;
  for (const PublicKey& k : revoked)
    if (!setup->roster.revoke(k)) return *why = "team.revoked: more than 64 keys", false;
  for (const auto& [name, text] : t.public_keys) {
    std::int16_t id = 0;
    sender_of_name(name, &id);
    std::vector<PublicKey> keys;
    if (!parse_keys(text, &keys, why)) return *why = "team.public_keys." + name + ": " + *why, false;
    for (const PublicKey& k : keys) {
      if (setup->roster.revoked(k)) continue;  // revoked wins: an old config that still lists it
      if (!setup->roster.add(id, k, why)) return *why = "team.public_keys." + name + ": " + *why, false;
    }
  }
  if (setup->roster.empty()) return true;
  const std::string mission = args.mission.empty() ? t.mission : args.mission;
  if (mission.empty())
    return *why = "team.public_keys is set but no mission id is (team.mission, --mission; elaslam-keys mission makes one)",
           false;
  if (!parse_mission(mission, &setup->mission, why))
    return *why = (args.mission.empty() ? "team.mission: " : "--mission: ") + *why, false;
  return true;
}

}  // namespace

bool configured_auth(const TransportArgs& args, const std::string& config_path, const std::string& who,
                     std::int16_t sender_id, bool sends, auth::AuthSetup* setup, bool* on, std::string* description) {
  *on = false;
  *setup = auth::AuthSetup{};
  TeamSection t;
  std::string why, origin, key_path;
  try {
    t = read_team_section(config_path, args.roster.empty());
    if (!args.roster.empty()) read_roster_file(args.roster, &t);  // --roster over the config's
    key_path = node_key_file(args, config_path, sender_name(sender_id), &origin);
  } catch (const config::ConfigError& e) {
    log::print(stderr, log::Priority::kErr, "%s: %s\n", who.c_str(), e.what());
    return false;
  }
  if (!read_roster(args, t, setup, &why)) {
    log::print(stderr, log::Priority::kErr, "%s: %s (%s%s)\n", who.c_str(), why.c_str(), config_path.c_str(),
               t.roster_file.empty() ? "" : (", roster " + t.roster_file).c_str());
    return false;
  }
  if (setup->roster.empty()) {
    if (!key_path.empty() && sends)  // a key without a roster would be a node nobody can verify
      log::print(stderr, log::Priority::kWarning,
                 "%s: warning: a key file is given (%s) but no team.public_keys: authentication off\n",
                 who.c_str(), origin.c_str());
    if (description != nullptr) *description = "authentication off (no team.public_keys)";
    return true;
  }
  setup->sender_id = sender_id;
  if (sends) {
    if (key_path.empty()) {
      log::print(stderr, log::Priority::kErr,
                 "%s: team.public_keys is set: this node signs what it sends and needs its secret key "
                 "(team.key_file, --key-file; elaslam-keys new FILE makes one)\n", who.c_str());
      return false;
    }
    if (!SigningKey::load(key_path, &setup->key, &why)) {
      log::print(stderr, log::Priority::kErr, "%s: %s (%s)\n", who.c_str(), why.c_str(), origin.c_str());
      return false;
    }
    const PublicKey& pk = setup->key.public_key();
    if (setup->roster.revoked(pk)) {
      log::print(stderr, log::Priority::kErr,
                 "%s: the key %s is revoked (team.revoked): make a new one and list it\n", who.c_str(),
                 key_path.c_str());
      return false;
    }
    if (!setup->roster.holds(sender_id, pk)) {
      log::print(stderr, log::Priority::kErr,
                 "%s: the public key of %s (%s) is not %s's in team.public_keys of %s\n", who.c_str(),
                 key_path.c_str(), to_hex(pk.data(), pk.size()).c_str(), sender_name(sender_id).c_str(),
                 config_path.c_str());
      return false;
    }
  }
  *on = true;
  if (description != nullptr)
    *description = "authentication on: mission " + mission_text(setup->mission) + ", roster " +
                   setup->roster.describe() + (t.roster_file.empty() ? "" : " (" + t.roster_file + ")") +
                   (sends ? ", signing as " + sender_name(sender_id) + " with " + key_path + " (" + origin + ")"
                          : ", verifying only");
  return true;
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

std::unique_ptr<Transport> open_lcm(const std::string& url, const std::string& who, bool channel_groups,
                                    const std::string& suffix) {
  if (channel_groups) {
    auto g = std::make_unique<GroupedLcmTransport>(effective_url(url), suffix, who, stderr);
    if (g->good()) {
      std::string why;
      std::fprintf(stderr, "%s: LCM in channel groups: %s up to %s\n", who.c_str(),
                   group_url(effective_url(url), 0, &why).c_str(),
                   group_url(effective_url(url), channels::kChannelGroups - 1, &why).c_str());
      return g;
    }
    log::print(stderr, log::Priority::kErr,
               "%s: cannot open LCM in channel groups: %s (see tools/netns_run.sh)\n", who.c_str(),
               g->error().c_str());
    return nullptr;
  }
  auto t = std::make_unique<LcmTransport>(effective_url(url), who, stderr);
  if (t->good()) return t;
  log::print(stderr, log::Priority::kErr,
             "%s: cannot open LCM (%s). Multicast on loopback needs a route: ip route add 224.0.0.0/4 dev lo "
             "(see tools/netns_run.sh)\n",
             who.c_str(), describe_url(url).c_str());
  return nullptr;
}

bool channel_groups_on(const TransportArgs& args, const std::string& config_path, const std::string& who, bool* on) {
  try {
    const bool configured = read_team_section(config_path, false).channel_groups;  // checked also under the flag
    *on = args.channel_groups || configured;
  } catch (const config::ConfigError& e) {
    log::print(stderr, log::Priority::kErr, "%s: %s\n", who.c_str(), e.what());
    return false;
  }
  std::string why;
  if (*on && group_url(effective_url(args.lcm_url), 0, &why).empty()) {  // restarting will not help
    log::print(stderr, log::Priority::kErr, "%s: %s\n", who.c_str(), why.c_str());
    return false;
  }
  return true;
}

int check_transport(const TransportArgs& args, const std::string& config_path, const std::string& who,
                    std::int16_t sender_id, bool sends) {
  auth::AuthSetup setup;
  bool on = false;
  std::string description;
  if (!configured_auth(args, config_path, who, sender_id, sends, &setup, &on, &description)) return 2;
  std::printf("%s: %s\n", who.c_str(), description.c_str());
  bool groups = false;
  if (!channel_groups_on(args, config_path, who, &groups)) return 2;
  if (!groups) {
    std::printf("%s: channel groups off: every channel on the LCM URL's port\n", who.c_str());
    return 0;
  }
  std::string why;
  const std::string url = effective_url(args.lcm_url);
  std::printf("%s: channel groups on: %s up to %s\n", who.c_str(), group_url(url, 0, &why).c_str(),
              group_url(url, channels::kChannelGroups - 1, &why).c_str());
  return 0;
}

std::unique_ptr<Transport> open_lcm(const TransportArgs& args, const std::string& config_path, std::int16_t sender_id,
                                    bool sends, std::int64_t incarnation, const std::string& who, int* exit_code,
                                    std::FILE* log, AuthInfo* info) {
  auth::AuthSetup setup;
  bool on = false;
  std::string description;
  if (!configured_auth(args, config_path, who, sender_id, sends, &setup, &on, &description)) {
    *exit_code = 2;
    return nullptr;
  }
  bool groups = false;
  if (!channel_groups_on(args, config_path, who, &groups)) {
    *exit_code = 2;
    return nullptr;
  }
  auto lcm = open_lcm(args.lcm_url, who, groups, args.channel_suffix);
  if (!lcm) {
    *exit_code = 1;
    return nullptr;
  }
  if (info != nullptr) {
    info->on = on;
    info->signs = on && !setup.key.empty();
    info->mission = on ? setup.mission : 0;
    if (info->signs) info->file_key = setup.key.file_key(setup.mission);
  }
  if (!on) return lcm;
  std::fprintf(stderr, "%s: %s, incarnation %lld\n", who.c_str(), description.c_str(), static_cast<long long>(incarnation));
  setup.incarnation = incarnation;
  setup.channel_suffix = args.channel_suffix;
  return std::make_unique<auth::AuthenticatedTransport>(std::move(lcm), std::move(setup), who, log);
}

}  // namespace elaslam::transport

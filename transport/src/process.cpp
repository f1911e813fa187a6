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
#include "elaslam/transport/auth_transport.hpp"
#include "elaslam/transport/grouped_lcm_transport.hpp"
#include "elaslam/transport/lcm_transport.hpp"
#include "elaslam/transport/team_key.hpp"

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
                 "team key file: authenticate every message (default: the config's team.key_file; none: off)");
  app.add_flag("--channel-groups", args->channel_groups,
               "one UDP port per channel group, from the URL's port up (default: the config's team.channel_groups)");
}

TeamSection read_team_section(const std::string& config_path) {
  TeamSection t;
  if (config_path.empty()) return t;
  config::Document doc = config::Document::from_file(config_path);
  doc.section(
      "team",
      [&](config::Reader& r) {
        r.read_optional("key_file", &t.key_file);
        r.read_optional("channel_groups", &t.channel_groups);
      },
      true);
  doc.allow_sections();
  doc.finish();
  return t;
}

std::string team_key_file(const TransportArgs& args, const std::string& config_path, std::string* origin) {
  std::string where;
  if (origin == nullptr) origin = &where;
  if (!args.key_file.empty()) {
    *origin = "--key-file";
    return args.key_file;
  }
  if (config_path.empty()) return "";
  const std::string path = read_team_section(config_path).key_file;
  *origin = "team.key_file in " + config_path;
  const char* creds = std::getenv("CREDENTIALS_DIRECTORY");
  if (path.empty() || creds == nullptr || *creds == '\0') return path;
  const std::string credential = std::string(creds) + "/team.key";
  std::error_code ec;
  if (!std::filesystem::exists(credential, ec)) return path;
  *origin += ", passed by systemd as the credential team.key (LoadCredential=; 4 bytes \"none\": " + path + " is missing)";
  return credential;
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
    auto g = std::make_unique<GroupedLcmTransport>(effective_url(url), suffix);
    if (g->good()) {
      std::string why;
      std::fprintf(stderr, "%s: LCM in channel groups: %s up to %s\n", who.c_str(),
                   group_url(effective_url(url), 0, &why).c_str(),
                   group_url(effective_url(url), channels::kChannelGroups - 1, &why).c_str());
      return g;
    }
    std::fprintf(stderr, "%s: cannot open LCM in channel groups: %s (see tools/netns_run.sh)\n", who.c_str(),
                 g->error().c_str());
    return nullptr;
  }
  auto t = std::make_unique<LcmTransport>(effective_url(url));
  if (t->good()) return t;
  std::fprintf(stderr,
               "%s: cannot open LCM (%s). Multicast on loopback needs a route: ip route add 224.0.0.0/4 dev lo "
               "(see tools/netns_run.sh)\n",
               who.c_str(), describe_url(url).c_str());
  return nullptr;
}

bool configured_team_key(const TransportArgs& args, const std::string& config_path, const std::string& who,
                         TeamKey* key, std::string* path, std::string* origin) {
  try {
    *path = team_key_file(args, config_path, origin);
  } catch (const config::ConfigError& e) {
    std::fprintf(stderr, "%s: %s\n", who.c_str(), e.what());
    return false;
  }
  std::string why;
  if (!path->empty() && !load_team_key(*path, key, &why)) {
    std::fprintf(stderr, "%s: %s (%s)\n", who.c_str(), why.c_str(), origin->c_str());
    return false;
  }
  return true;
}

bool channel_groups_on(const TransportArgs& args, const std::string& config_path, const std::string& who, bool* on) {
  try {
    const bool configured = read_team_section(config_path).channel_groups;  // checked also under the flag
    *on = args.channel_groups || configured;
  } catch (const config::ConfigError& e) {
    std::fprintf(stderr, "%s: %s\n", who.c_str(), e.what());
    return false;
  }
  std::string why;
  if (*on && group_url(effective_url(args.lcm_url), 0, &why).empty()) {  // restarting will not help
    std::fprintf(stderr, "%s: %s\n", who.c_str(), why.c_str());
    return false;
  }
  return true;
}

int check_team_key(const TransportArgs& args, const std::string& config_path, const std::string& who) {
  TeamKey key;
  std::string path, origin;
  if (!configured_team_key(args, config_path, who, &key, &path, &origin)) return 2;
  if (key.empty())
    std::printf("%s: authentication off (no team key configured: team.key_file, --key-file)\n", who.c_str());
  else
    std::printf("%s: authentication on, team key %s (%s): readable and valid\n", who.c_str(), path.c_str(),
                origin.c_str());
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
                                    const std::string& who, int* exit_code, std::FILE* log) {
  TeamKey key;
  std::string key_path, origin;
  if (!configured_team_key(args, config_path, who, &key, &key_path, &origin)) {
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
  if (key.empty()) return lcm;
  std::fprintf(stderr, "%s: messages authenticated with the team key %s (sender id %d)\n", who.c_str(),
               key_path.c_str(), sender_id);
  return std::make_unique<auth::AuthenticatedTransport>(std::move(lcm), key, sender_id, now_utime(),
                                                        args.channel_suffix, who, log);
}

}  // namespace elaslam::transport

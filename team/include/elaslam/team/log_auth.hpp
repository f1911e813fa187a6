// Reading a keyed team's recording as its nodes read the wire (docs/security.md,
// "Message authentication"): lcm-logger records everything on the group, what an
// attacker injected too, and LCM's decoders ignore the 54-byte trailer, so a tool
// that trusts the log scores forged messages as the team's. With the team key, each
// event must pass the checks the receivers make (auth::Authenticator::open: the MAC,
// the sender bound to its channel, the anti-replay window per sender); accepted
// events lose their trailer, refused ones are counted per reason and skipped.
// Used by evaluate and log_info (--key-file, or the config's team.key_file).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "elaslam/team/log_reader.hpp"
#include "elaslam/transport/auth_transport.hpp"
#include "elaslam/transport/team_key.hpp"

namespace elaslam {

class LogAuth {
 public:
  /// `suffix`: the team's channel suffix (the channels' owners depend on it).
  LogAuth(const transport::TeamKey& key, const std::string& suffix);

  /// True when `ev` verifies (its data is then the payload only); false, counted,
  /// when a keyed receiver would have refused it. Channels that are not the team's
  /// (LCM_SELF_TEST, a tool's) pass as they are: no node receives them.
  bool admit(LogEvent* ev);

  std::int64_t accepted() const { return auth_.counters().accepted; }
  std::int64_t refused() const { return auth_.counters().refused(); }
  /// Refusals per channel and reason (auth::to_string).
  const std::map<std::string, std::map<std::string, std::int64_t>>& refused_by_channel() const { return refused_; }
  /// {"key_file": .., "accepted": N, "refused": N, "refused_by": {channel: {reason: N}}}
  nlohmann::json to_json(const std::string& key_file) const;

 private:
  transport::auth::Authenticator auth_;
  std::string suffix_;
  std::map<std::string, std::map<std::string, std::int64_t>> refused_;
};

/// The key of --key-file, else of the config's team.key_file (`config_path`, "" for
/// none), found and checked as the processes do (transport::configured_team_key):
/// *auth null when none is configured. False, after printing why to stderr as `who`
/// (a bad team: section, a key file others can read, ...), when it cannot be used.
/// *key_file: the path used.
bool open_log_auth(const std::string& key_file_option, const std::string& config_path, const std::string& suffix,
                   const std::string& who, std::unique_ptr<LogAuth>* auth, std::string* key_file);

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// Reading a keyed team's recording as its nodes read the wire (docs/security.md,
// "Message authentication"): a recorder records everything on the group, what an
// attacker injected too, and LCM's decoders ignore the 98-byte trailer, so a tool
// that trusts the log scores forged messages as the team's. With the team's roster
// and mission, each event must pass the checks the receivers make
// (auth::Authenticator::open: the signature with its sender's key, the sender bound
// to its channel, the mission, the anti-replay window per sender, on the recording's
// receive times); accepted events lose their trailer, refused ones are counted per
// reason and skipped. Used by evaluate and log_info (the --config's team: section).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "elaslam/logs/log_reader.hpp"
#include "elaslam/transport/auth_transport.hpp"

namespace elaslam {

class LogAuth {
 public:
  /// `setup`: the roster and mission (no key of its own); its suffix: the team's
  /// channel suffix (the channels' owners depend on it).
  explicit LogAuth(transport::auth::AuthSetup setup);

  /// True when `ev` verifies (its data is then the payload only); false, counted,
  /// when a keyed receiver would have refused it. Channels that are not the team's
  /// (LCM_SELF_TEST, a tool's) pass as they are: no node receives them.
  bool admit(LogEvent* ev);

  std::int64_t accepted() const { return auth_.counters().accepted; }
  std::int64_t refused() const { return auth_.counters().refused(); }
  /// Refusals per channel and reason (auth::to_string).
  const std::map<std::string, std::map<std::string, std::int64_t>>& refused_by_channel() const { return refused_; }
  /// {"roster": .., "mission": .., "accepted": N, "refused": N, "refused_by": {channel: {reason: N}},
  ///  "refused_by_reason": {reason: N}}
  nlohmann::json to_json(const std::string& source) const;
  std::uint64_t mission() const { return auth_.mission(); }

 private:
  std::string suffix_;
  transport::auth::Authenticator auth_;
  std::map<std::string, std::map<std::string, std::int64_t>> refused_;
};

/// The roster and mission of `roster_option` (--roster), else of the config's team:
/// section (`config_path`, "" for none); `mission_option`: --mission over the roster's.
/// Read and checked as the processes do (transport::configured_auth): *auth null when
/// no roster is configured. False, after printing why to stderr as `who` (a bad team:
/// section, ...), when it cannot be used. *source: where the roster came from.
bool open_log_auth(const std::string& roster_option, const std::string& mission_option, const std::string& config_path,
                   const std::string& suffix, const std::string& who, std::unique_ptr<LogAuth>* auth,
                   std::string* source);

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// Deterministic keys and a team's authentication setup for the tests of message
// authentication (transport/auth_transport.hpp): every sender's key made from a seed
// of its own, one roster holding them all, one mission.
#pragma once

#include <array>
#include <cstdint>
#include <initializer_list>
#include <string>

#include "elaslam/transport/auth_transport.hpp"
#include "elaslam/transport/keys.hpp"

namespace elaslam::test {

constexpr std::uint64_t kTestMission = 0x1234abcd5678ef90ull;

/// The key of `seed` (any int; the same seed, the same key).
inline transport::SigningKey test_key(int seed) {
  std::array<std::uint8_t, transport::kKeyBytes> s{};
  for (std::size_t i = 0; i < s.size(); ++i) s[i] = static_cast<std::uint8_t>(seed * 37 + 7 * static_cast<int>(i) + 1);
  return transport::SigningKey(s);
}

/// Sender `id`'s key in the test team: seed id (the same for every test).
inline transport::SigningKey team_key(std::int16_t id) { return test_key(id); }

/// A roster of the test team: main, simulator, tool and robots 1..16, each its team_key.
inline transport::Roster team_roster() {
  transport::Roster r;
  std::string why;
  for (std::int16_t id = 1; id <= 16; ++id) r.add(id, team_key(id).public_key(), &why);
  for (std::int16_t id : {transport::kSenderMain, transport::kSenderSimulator, transport::kSenderTool})
    r.add(id, team_key(id).public_key(), &why);
  return r;
}

/// The setup of sender `id` in the test team (signing with its key), or of a receiver
/// only (`sends` false).
inline transport::auth::AuthSetup team_setup(std::int16_t id, std::int64_t incarnation, std::string suffix = "",
                                             bool sends = true, std::uint64_t mission = kTestMission) {
  transport::auth::AuthSetup s;
  s.roster = team_roster();
  s.mission = mission;
  if (sends) s.key = team_key(id);
  s.sender_id = id;
  s.incarnation = incarnation;
  s.channel_suffix = std::move(suffix);
  return s;
}

/// The team: section of a config for the test team (its roster and mission), as text.
inline std::string team_yaml(std::initializer_list<std::int16_t> senders) {
  std::string y = "team:\n  mission: \"" + transport::mission_text(kTestMission) + "\"\n  public_keys:\n";
  for (std::int16_t s : senders) {
    const auto k = team_key(s).public_key();
    y += "    " + transport::sender_name(s) + ": \"" + transport::to_hex(k.data(), k.size()) + "\"\n";
  }
  return y;
}

/// Sender `id`'s secret key file text (64 hexadecimal digits).
inline std::string team_key_text(std::int16_t id) {
  std::array<std::uint8_t, transport::kKeyBytes> s{};
  for (std::size_t i = 0; i < s.size(); ++i) s[i] = static_cast<std::uint8_t>(id * 37 + 7 * static_cast<int>(i) + 1);
  return transport::to_hex(s.data(), s.size()) + "\n";
}

}  // namespace elaslam::test

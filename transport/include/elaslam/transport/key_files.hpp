// SPDX-License-Identifier: Apache-2.0
// Making the team's keys (the keys tool, elaslam-keys; docs/security.md "Keys and
// missions"): a node's new secret key file, a new mission id, and a whole team's key
// files with its roster (the config's team: section). A secret key file is 64
// hexadecimal characters and a newline, mode 0600, written to a temporary file that
// is then linked to its path: an existing file (or a symbolic link there) is never
// overwritten or followed.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <string>
#include <vector>

#include "elaslam/transport/keys.hpp"

namespace elaslam::transport {

/// Write `text` to a new file at `path` with `mode`, never replacing anything there
/// (link(2) fails on anything at `path`); false with why.
bool write_new_file(const std::string& path, const std::string& text, std::string* why, mode_t mode = 0600);

/// A new random key at `path` (write_new_file, mode 0600); its public key in *pub.
bool make_key_file(const std::string& path, PublicKey* pub, std::string* why);

/// A new random mission id's text (16 hexadecimal digits, not zero).
std::string new_mission();

/// The senders of a team: main, the simulator, the robots (1 .. contract::kMaxRobots),
/// and the tool when asked; false with why on a robot id out of range.
bool team_senders(const std::vector<int>& robots, bool tool, std::vector<std::int16_t>* senders, std::string* why);

/// A key per sender in `dir` (made with mode 0700 when missing: <name>.key) and the
/// roster at `roster_path` (mode 0644: the services' dynamic users read it): the
/// config's team: section with a new mission and every public key, also in *yaml.
/// False with why on the first file that could not be made.
bool make_team_keys(const std::string& dir, const std::vector<std::int16_t>& senders, const std::string& roster_path,
                    std::string* yaml, std::string* why);

}  // namespace elaslam::transport

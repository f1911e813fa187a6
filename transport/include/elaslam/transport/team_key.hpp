// The team key of message authentication (auth_transport.hpp, docs/security.md):
// 32 secret bytes that every process of one team holds, read from a key file that
// only its owner can read. The key is never printed; it is wiped from memory when
// the TeamKey goes away (sodium_memzero).
//
// A key file is refused unless it is
//   - a regular file (not a symbolic link, a directory or a device),
//   - owned by the running user or by root,
//   - without group or other permissions (0600 or 0400),
//   - exactly 32 bytes (raw), or 64 hexadecimal characters (an optional newline after).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

namespace elaslam::transport {

class TeamKey {
 public:
  static constexpr std::size_t kBytes = 32;  // crypto_auth_hmacsha512256_KEYBYTES

  TeamKey() = default;
  explicit TeamKey(const std::array<std::uint8_t, kBytes>& bytes) : bytes_(bytes), set_(true) {}
  TeamKey(const TeamKey& other) = default;
  TeamKey& operator=(const TeamKey& other) = default;
  ~TeamKey();

  bool empty() const { return !set_; }
  const std::uint8_t* data() const { return bytes_.data(); }

 private:
  std::array<std::uint8_t, kBytes> bytes_{};
  bool set_ = false;
};

/// Read the key file at `path` into *key; false, with why in *why (never the key's
/// bytes), when the file is not acceptable (rules above).
bool load_team_key(const std::string& path, TeamKey* key, std::string* why);

// A new key: tools/make_team_key.sh PATH (installed: elaslam-make-team-key).

}  // namespace elaslam::transport

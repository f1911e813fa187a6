// SPDX-License-Identifier: Apache-2.0
// The keys of message authentication (auth_transport.hpp, docs/security.md): every
// node that sends has a key pair of its own (Ed25519, libsodium); the team's public
// keys, one or two per sender (two while a key is rotated), are the roster in the
// config's team: section, with the keys revoked. A message verifies only with the
// public key of the one sender that may publish on its channel: a node that is taken
// over can speak only as itself. Receive-only tools (viewer, monitor, evaluate) need
// the roster and no key of their own.
//
// A secret key file holds the key's 32-byte seed, raw or as 64 hexadecimal
// characters (a newline after), and is refused unless it is
//   - a regular file (not a symbolic link, a directory or a device),
//   - owned by the running user or by root,
//   - without group or other permissions (0600 or 0400),
//   - not all zeros.
// The seed is never printed and is wiped from memory (sodium_memzero).
// Make keys with build/bin/keys (installed as elaslam-keys).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace elaslam::transport {

constexpr std::size_t kKeyBytes = 32;  // a seed, a public key
using PublicKey = std::array<std::uint8_t, kKeyBytes>;

/// Sender ids: robots use their robot id (1 .. contract::kMaxRobots); the other roles these.
constexpr int kMaxRobotSenders = 16;
constexpr std::int16_t kSenderMain = 100;
constexpr std::int16_t kSenderSimulator = 101;
constexpr std::int16_t kSenderTool = 102;  // a tool that publishes (a test's publisher, a sensor driver's stand-in)

/// A sender's name in the roster: "robot_<r>", "main", "simulator", "tool"; "" for no sender.
std::string sender_name(std::int16_t id);
/// The sender id of a roster name; false when it names none.
bool sender_of_name(const std::string& name, std::int16_t* id);

/// Lower-case hexadecimal of `n` bytes.
std::string to_hex(const std::uint8_t* bytes, std::size_t n);
/// `hex` (exactly 2n hexadecimal digits) into `n` bytes; false when it is not.
bool from_hex(const std::string& hex, std::uint8_t* bytes, std::size_t n);
bool from_hex(const char* hex, std::size_t len, std::uint8_t* bytes, std::size_t n);  // (no copy of a secret)
/// A key's id on the wire: its first four bytes, big-endian.
std::uint32_t key_id(const PublicKey& key);

/// Read the secret key file at `path` into *seed; false with why (never the key's
/// bytes) when the file is not acceptable (rules above).
bool load_secret_key_file(const std::string& path, std::array<std::uint8_t, kKeyBytes>* seed, std::string* why);

/// A node's signing key: the Ed25519 key pair of a seed. Wiped when it goes away.
class SigningKey {
 public:
  SigningKey() = default;
  explicit SigningKey(const std::array<std::uint8_t, kKeyBytes>& seed);
  SigningKey(const SigningKey& other) = default;
  SigningKey& operator=(const SigningKey& other) = default;
  ~SigningKey();
  /// The key of the file at `path` (load_secret_key_file); false with why.
  static bool load(const std::string& path, SigningKey* key, std::string* why);

  bool empty() const { return !set_; }
  const PublicKey& public_key() const { return public_; }
  /// The Ed25519 signature of a 64-byte digest.
  void sign(const std::uint8_t* digest64, std::uint8_t* signature64) const;
  /// A 32-byte key for a node's own files of one mission (state files' MAC,
  /// common/state_seal.hpp), derived from the seed and the mission id with BLAKE2b:
  /// such a file is sealed only with this node's key, and a file of another mission
  /// does not verify (a new mission starts fresh).
  std::array<std::uint8_t, kKeyBytes> file_key(std::uint64_t mission) const;

 private:
  std::array<std::uint8_t, 64> secret_{};  // libsodium's secret key: the seed and the public key
  PublicKey public_{};
  bool set_ = false;
};

/// Ed25519 verification of a signature over a 64-byte digest.
bool verify_signature(const PublicKey& key, const std::uint8_t* digest64, const std::uint8_t* signature64);

/// The team's public keys: per sender id at most kKeysPerSender, and the revoked keys
/// (refused wherever they are listed). Fixed memory, looked up without allocation.
class Roster {
 public:
  static constexpr int kKeysPerSender = 2;
  static constexpr int kMaxRevoked = 64;

  /// Add a key of `sender`; false with why: no such sender, a third key, a key that is
  /// not a point of the curve, a key already given to another sender, a revoked key.
  bool add(std::int16_t sender, const PublicKey& key, std::string* why);
  /// Revoke a key: it is taken out of the roster and never added again. False when the
  /// list of revoked keys is full.
  bool revoke(const PublicKey& key);
  bool revoked(const PublicKey& key) const;
  /// The key of `sender` with id `id`, or nullptr.
  const PublicKey* find(std::int16_t sender, std::uint32_t id) const;
  /// Is `key` one of `sender`'s?
  bool holds(std::int16_t sender, const PublicKey& key) const;
  bool empty() const { return count_ == 0; }
  int size() const { return count_; }
  /// "robot_1 (2 keys), main, simulator" for the start-up line.
  std::string describe() const;

 private:
  struct Slot {
    std::array<PublicKey, kKeysPerSender> keys{};
    int n = 0;
  };
  static int slot_of(std::int16_t id);
  std::array<Slot, kMaxRobotSenders + 4> slots_{};
  std::array<PublicKey, kMaxRevoked> revoked_{};
  int revoked_n_ = 0;
  int count_ = 0;
};

/// A mission id (docs/security.md "Missions"): 16 hexadecimal digits, not zero.
bool parse_mission(const std::string& hex, std::uint64_t* mission, std::string* why);
std::string mission_text(std::uint64_t mission);

}  // namespace elaslam::transport

// SPDX-License-Identifier: Apache-2.0
#include "elaslam/transport/keys.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include <sodium.h>

#include "elaslam/common/contract.hpp"
#include "elaslam/common/secret_file.hpp"

namespace elaslam::transport {
namespace {

static_assert(crypto_sign_SEEDBYTES == kKeyBytes && crypto_sign_PUBLICKEYBYTES == kKeyBytes);
static_assert(crypto_sign_SECRETKEYBYTES == 64 && crypto_sign_BYTES == 64);
static_assert(kMaxRobotSenders == contract::kMaxRobots);

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

/// Wipes a buffer on every way out.
struct Scratch {
  std::uint8_t buf[160] = {};
  ~Scratch() { sodium_memzero(buf, sizeof buf); }
};

void init_sodium() {
  if (sodium_init() < 0) throw std::runtime_error("libsodium could not be initialised");
}

}  // namespace

std::string sender_name(std::int16_t id) {
  if (id >= 1 && id <= kMaxRobotSenders) return "robot_" + std::to_string(id);
  switch (id) {
    case kSenderMain: return "main";
    case kSenderSimulator: return "simulator";
    case kSenderTool: return "tool";
    default: return "";
  }
}

bool sender_of_name(const std::string& name, std::int16_t* id) {
  for (std::int16_t s : {kSenderMain, kSenderSimulator, kSenderTool})
    if (name == sender_name(s)) return *id = s, true;
  for (std::int16_t r = 1; r <= kMaxRobotSenders; ++r)
    if (name == sender_name(r)) return *id = r, true;
  return false;
}

std::string to_hex(const std::uint8_t* bytes, std::size_t n) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string s(2 * n, '0');
  for (std::size_t i = 0; i < n; ++i) s[2 * i] = kDigits[bytes[i] >> 4], s[2 * i + 1] = kDigits[bytes[i] & 15];
  return s;
}

bool from_hex(const std::string& hex, std::uint8_t* bytes, std::size_t n) {
  return from_hex(hex.data(), hex.size(), bytes, n);
}

bool from_hex(const char* hex, std::size_t len, std::uint8_t* bytes, std::size_t n) {
  if (len != 2 * n) return false;
  for (std::size_t i = 0; i < n; ++i) {
    const int hi = hex_value(hex[2 * i]), lo = hex_value(hex[2 * i + 1]);
    if (hi < 0 || lo < 0) return false;
    bytes[i] = static_cast<std::uint8_t>(hi * 16 + lo);
  }
  return true;
}

std::uint32_t key_id(const PublicKey& k) {
  return (std::uint32_t{k[0]} << 24) | (std::uint32_t{k[1]} << 16) | (std::uint32_t{k[2]} << 8) | k[3];
}

bool load_secret_key_file(const std::string& path, std::array<std::uint8_t, kKeyBytes>* seed, std::string* why) {
  const std::string where = "key file " + path + ": ";
  Scratch s;
  std::size_t n = 0;
  bool more = false;
  if (!files::read_secret_file(path, "key file", s.buf, sizeof s.buf, &n, &more, why)) return false;
  std::size_t len = n;
  if (len == kKeyBytes) {
    std::memcpy(seed->data(), s.buf, len);
  } else {
    if (len == 2 * kKeyBytes + 1 && s.buf[len - 1] == '\n') --len;
    if (!from_hex(reinterpret_cast<const char*>(s.buf), len, seed->data(), kKeyBytes)) {
      sodium_memzero(seed->data(), seed->size());
      *why = where + "has " + std::to_string(n) + (more ? " or more" : "") +
             " bytes that are not a key: a secret key is 32 random bytes, raw or as 64 hexadecimal characters "
             "(make one with elaslam-keys new FILE)";
      return false;
    }
  }
  if (sodium_is_zero(seed->data(), seed->size())) {
    *why = where + "is all zeros: not a key (make one with elaslam-keys new FILE)";
    return false;
  }
  return true;
}

SigningKey::SigningKey(const std::array<std::uint8_t, kKeyBytes>& seed) : set_(true) {
  init_sodium();
  crypto_sign_seed_keypair(public_.data(), secret_.data(), seed.data());
}

SigningKey::~SigningKey() { sodium_memzero(secret_.data(), secret_.size()); }

bool SigningKey::load(const std::string& path, SigningKey* key, std::string* why) {
  std::array<std::uint8_t, kKeyBytes> seed{};
  const bool ok = load_secret_key_file(path, &seed, why);
  if (ok) *key = SigningKey(seed);
  sodium_memzero(seed.data(), seed.size());
  return ok;
}

void SigningKey::sign(const std::uint8_t* digest64, std::uint8_t* signature64) const {
  crypto_sign_detached(signature64, nullptr, digest64, 64, secret_.data());
}

std::array<std::uint8_t, kKeyBytes> SigningKey::file_key(std::uint64_t mission) const {
  static constexpr char kContext[] = "elaslam: a node's own files, mission ";
  unsigned char input[sizeof kContext - 1 + 8];
  std::memcpy(input, kContext, sizeof kContext - 1);
  for (int i = 7; i >= 0; --i, mission >>= 8) input[sizeof kContext - 1 + static_cast<std::size_t>(i)] = mission & 0xff;
  std::array<std::uint8_t, kKeyBytes> k{};
  // Keyed with the seed (the secret key's first half).
  crypto_generichash(k.data(), k.size(), input, sizeof input, secret_.data(), crypto_sign_SEEDBYTES);
  return k;
}

bool verify_signature(const PublicKey& key, const std::uint8_t* digest64, const std::uint8_t* signature64) {
  return crypto_sign_verify_detached(signature64, digest64, 64, key.data()) == 0;
}

// ---- Roster ------------------------------------------------------------------------------

int Roster::slot_of(std::int16_t id) {
  if (id >= 1 && id <= kMaxRobotSenders) return id;
  switch (id) {
    case kSenderMain: return kMaxRobotSenders + 1;
    case kSenderSimulator: return kMaxRobotSenders + 2;
    case kSenderTool: return kMaxRobotSenders + 3;
    default: return -1;
  }
}

bool Roster::add(std::int16_t sender, const PublicKey& key, std::string* why) {
  init_sodium();
  const int slot = slot_of(sender);
  if (slot < 0) {
    *why = "no such sender (robot_1 .. robot_16, main, simulator, tool)";
    return false;
  }
  if (revoked(key)) {
    *why = "the key " + to_hex(key.data(), key.size()) + " is revoked (team.revoked)";
    return false;
  }
  if (crypto_core_ed25519_is_valid_point(key.data()) != 1) {
    *why = "not an Ed25519 public key: " + to_hex(key.data(), key.size());
    return false;
  }
  for (const Slot& s : slots_)
    for (int i = 0; i < s.n; ++i)
      if (s.keys[static_cast<std::size_t>(i)] == key) {
        *why = "the key " + to_hex(key.data(), key.size()) + " is listed twice: one key belongs to one sender";
        return false;
      }
  Slot& s = slots_[static_cast<std::size_t>(slot)];
  if (s.n == kKeysPerSender) {
    *why = "more than " + std::to_string(kKeysPerSender) + " keys for " + sender_name(sender) +
           " (a key and its successor while it is rotated)";
    return false;
  }
  for (int i = 0; i < s.n; ++i)
    if (key_id(s.keys[static_cast<std::size_t>(i)]) == key_id(key)) {
      *why = "two keys of " + sender_name(sender) + " begin with the same four bytes (their id on the wire): make another";
      return false;
    }
  s.keys[static_cast<std::size_t>(s.n++)] = key;
  ++count_;
  return true;
}

bool Roster::revoke(const PublicKey& key) {
  if (revoked(key)) return true;
  if (revoked_n_ == kMaxRevoked) return false;
  revoked_[static_cast<std::size_t>(revoked_n_++)] = key;
  for (Slot& s : slots_) {
    for (int i = 0; i < s.n; ++i) {
      if (s.keys[static_cast<std::size_t>(i)] != key) continue;
      for (int j = i; j + 1 < s.n; ++j) s.keys[static_cast<std::size_t>(j)] = s.keys[static_cast<std::size_t>(j + 1)];
      --s.n, --count_;
      break;
    }
  }
  return true;
}

bool Roster::revoked(const PublicKey& key) const {
  for (int i = 0; i < revoked_n_; ++i)
    if (revoked_[static_cast<std::size_t>(i)] == key) return true;
  return false;
}

const PublicKey* Roster::find(std::int16_t sender, std::uint32_t id) const {
  const int slot = slot_of(sender);
  if (slot < 0) return nullptr;
  const Slot& s = slots_[static_cast<std::size_t>(slot)];
  for (int i = 0; i < s.n; ++i)
    if (key_id(s.keys[static_cast<std::size_t>(i)]) == id) return &s.keys[static_cast<std::size_t>(i)];
  return nullptr;
}

bool Roster::holds(std::int16_t sender, const PublicKey& key) const {
  const PublicKey* k = find(sender, key_id(key));
  return k != nullptr && *k == key;
}

std::string Roster::describe() const {
  std::string out;
  for (std::int16_t id = 1; id <= kSenderTool; ++id) {
    const int slot = slot_of(id);
    if (slot < 0 || slots_[static_cast<std::size_t>(slot)].n == 0) continue;
    if (!out.empty()) out += ", ";
    out += sender_name(id);
    if (slots_[static_cast<std::size_t>(slot)].n > 1) out += " (" + std::to_string(slots_[static_cast<std::size_t>(slot)].n) + " keys)";
  }
  return out.empty() ? "no keys" : out;
}

bool parse_mission(const std::string& hex, std::uint64_t* mission, std::string* why) {
  std::uint8_t b[8];
  if (!from_hex(hex, b, sizeof b)) {
    *why = "a mission id is 16 hexadecimal digits (make one with elaslam-keys mission), got '" + hex + "'";
    return false;
  }
  std::uint64_t v = 0;
  for (std::uint8_t x : b) v = (v << 8) | x;
  if (v == 0) {
    *why = "a mission id is not zero (make one with elaslam-keys mission)";
    return false;
  }
  *mission = v;
  return true;
}

std::string mission_text(std::uint64_t mission) {
  std::uint8_t b[8];
  for (int i = 7; i >= 0; --i, mission >>= 8) b[i] = static_cast<std::uint8_t>(mission & 0xff);
  return to_hex(b, sizeof b);
}

}  // namespace elaslam::transport

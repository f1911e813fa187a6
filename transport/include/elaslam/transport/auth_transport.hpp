// Message authentication (issue 15; docs/security.md "Message authentication").
// Every message carries, after LCM's encoded payload, a trailer of 54 bytes:
//
//   offset  size  field
//   0       4     magic "ELA1"
//   4       2     sender id (int16, big-endian): a robot's id 1..16, kSenderMain,
//                 kSenderSimulator, kSenderTool
//   6       8     sender incarnation (int64, big-endian): the sender's start time [us
//                 since the epoch], so a restart is newer
//   14      8     counter (uint64, big-endian): 1, 2, 3, ... per message of this
//                 incarnation, over all its channels
//   22      32    MAC: HMAC-SHA-512-256 (libsodium crypto_auth_hmacsha512256) with
//                 the team key over  u32be(len(channel)) | channel | payload | bytes 0..21
//
// LCM's generated decoders (C++, Python, Java) read what their type needs and ignore
// what follows, so recordings, lcm-spy and the Python tools read sealed messages
// unchanged (tests/transport/test_auth_transport.cpp decodes a sealed message).
//
// Receiving, before anything decodes the bytes: no trailer or a bad magic
// (unauthenticated), a MAC that does not verify (forged or altered; compared in
// constant time), a sender id that may not publish on the channel (wrong sender), a
// counter already seen or too old for the sender's window (replayed), an incarnation
// older than every one tracked for its sender (stale) are dropped and counted. Per
// sender id the windows of the last kIncarnations incarnations are kept, each the
// highest counter seen and a bitmap of the kWindow counters below it (IPsec's
// anti-replay window, RFC 4303 3.4.3), so that two live processes with one robot id
// (main_robot's duplicate-sender detection) both get through. The payload handed on
// is the same bytes without the trailer: no copy, no allocation.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <list>
#include <memory>
#include <string>
#include <vector>

#include "elaslam/transport/team_key.hpp"
#include "elaslam/transport/transport.hpp"

namespace elaslam::transport::auth {

constexpr std::size_t kMagicBytes = 4;
constexpr std::size_t kHeaderBytes = 22;  // magic, sender, incarnation, counter: what the MAC covers after the payload
constexpr std::size_t kMacBytes = 32;
constexpr std::size_t kTrailerBytes = kHeaderBytes + kMacBytes;  // 54
constexpr char kMagic[kMagicBytes] = {'E', 'L', 'A', '1'};

/// Sender ids: robots use their robot id (1 .. contract::kMaxRobots); the other roles these.
/// Robot sender ids 1..kMaxRobotSenders (contract::kMaxRobots; auth_transport.cpp checks).
constexpr int kMaxRobotSenders = 16;
constexpr std::int16_t kSenderMain = 100;
constexpr std::int16_t kSenderSimulator = 101;
constexpr std::int16_t kSenderTool = 102;  // a tool (monitor, a test's publisher): no team channel

/// Replay windows: incarnations tracked per sender id, counters per window.
constexpr int kIncarnations = 4;
constexpr int kWindow = 256;

enum class Verdict : std::uint8_t {
  kAccepted = 0,
  kUnauthenticated,  // shorter than a trailer, or no magic: sent without the key's layer
  kForged,           // the MAC does not verify: forged, altered, or another key
  kWrongSender,      // the sender id may not publish on this channel (or is no team sender)
  kReplayed,         // counter seen before, or below the sender's window
  kStale,            // an incarnation older than every one tracked for this sender id
};
constexpr int kVerdicts = 6;
const char* to_string(Verdict v);

/// Refusals by reason, and what went through.
struct AuthCounters {
  std::int64_t sealed = 0;    // messages sent with a trailer
  std::int64_t accepted = 0;  // messages that verified
  std::array<std::int64_t, kVerdicts> refused_by{};  // index: Verdict (kAccepted unused)
  std::int64_t refused() const;
};

/// Who sent a verified message.
struct Sender {
  std::int16_t id = 0;
  std::int64_t incarnation = 0;
  std::uint64_t counter = 0;
};

/// May sender `id` publish on `channel` (a team channel with `suffix`)? Per-robot
/// channels belong to their robot, the map's channels to main_robot, the world's to
/// the simulator; LMAP_EVENT, LMAP_EVENTS and LMAP_SNAPSHOT to robots, whose payload's
/// robot_id (bytes 20..21 of the three types' encoding) must be the sender's. Channels that are not
/// the team's: any sender of the team. docs/security.md lists what is bound.
bool sender_may_publish(std::int16_t id, const std::string& channel, const std::string& suffix,
                        const std::uint8_t* payload, std::size_t size);

/// The anti-replay state of every sender id: fixed memory, no allocation.
class ReplayGuard {
 public:
  /// kAccepted (and recorded), kReplayed, kStale or kWrongSender (an id without a slot).
  Verdict check(const Sender& s);

 private:
  struct Window {
    std::int64_t incarnation = 0;
    std::uint64_t highest = 0;                 // highest counter seen (0: none)
    std::array<std::uint64_t, kWindow / 64> bits{};  // bit i: counter highest - i seen
    bool used = false;
  };
  struct Slot {
    std::array<Window, kIncarnations> windows;
  };
  static int slot_of(std::int16_t id);
  std::array<Slot, kMaxRobotSenders + 4> slots_{};  // robots 1..16, main, simulator, tool (and 0 unused)
};

/// Seals outgoing and opens incoming messages of one process with the team key.
class Authenticator {
 public:
  Authenticator(const TeamKey& key, std::int16_t sender_id, std::int64_t incarnation, std::string channel_suffix = {});
  ~Authenticator();
  Authenticator(const Authenticator&) = delete;
  Authenticator& operator=(const Authenticator&) = delete;

  /// Append the trailer to `buf`'s first `size` bytes (the payload); `buf` must hold
  /// size + kTrailerBytes. Returns size + kTrailerBytes.
  std::size_t seal(const std::string& channel, std::uint8_t* buf, std::size_t size);

  /// Verify a received message; on kAccepted, *payload_size is its size without the
  /// trailer and *sender who sent it. Allocates nothing. `receiver` (1..64, 0: none)
  /// names the subscription it is handed to: LCM hands one datagram to every
  /// subscription that matches its channel, and the message just accepted is accepted
  /// again for each other receiver once (a replay reaches a receiver that had it).
  Verdict open(const std::string& channel, const std::uint8_t* data, std::size_t size, std::size_t* payload_size,
               Sender* sender, int receiver = 0);
  /// The MAC and sender checks of open() without the replay check (tests, tools).
  Verdict verify(const std::string& channel, const std::uint8_t* data, std::size_t size, std::size_t* payload_size,
                 Sender* sender) const;

  const AuthCounters& counters() const { return counters_; }
  std::int16_t sender_id() const { return sender_id_; }
  std::int64_t incarnation() const { return incarnation_; }

 private:
  void mac(const std::string& channel, const std::uint8_t* payload, std::size_t size, const std::uint8_t* header,
           std::uint8_t* out) const;

  // HMAC's state after the key (its inner and outer pads hashed), made once: each
  // message starts from a copy, two SHA-512 blocks fewer than init() per message.
  struct Keyed;
  std::unique_ptr<Keyed> keyed_;
  std::int16_t sender_id_;
  std::int64_t incarnation_;
  std::uint64_t counter_ = 0;
  std::string suffix_;
  ReplayGuard guard_;
  AuthCounters counters_;
  Sender last_{};                  // the message accepted last
  std::uint64_t last_receivers_ = 0;  // bit r - 1: receiver r has had it
};

/// A Transport that seals what it publishes and opens what it receives, around
/// another transport (LcmTransport). Refused messages never reach a subscriber: they
/// are counted (counters(), refused()) and logged at a bounded rate (the first 20,
/// then every 1000th) naming the channel and the reason.
class AuthenticatedTransport final : public Transport {
 public:
  /// `log`: where refusals are said (nullptr: counted only); `who` prefixes the lines.
  AuthenticatedTransport(std::unique_ptr<Transport> inner, const TeamKey& key, std::int16_t sender_id,
                         std::int64_t incarnation, std::string channel_suffix, std::string who,
                         std::FILE* log = stderr);
  /// The same around a transport that the caller keeps (and that outlives this one):
  /// several processes' layers on one in-process bus in the tests.
  AuthenticatedTransport(Transport& inner, const TeamKey& key, std::int16_t sender_id, std::int64_t incarnation,
                         std::string channel_suffix, std::string who, std::FILE* log = stderr);
  ~AuthenticatedTransport() override;

  bool good() const override { return inner_->good(); }
  const char* kind() const override { return inner_->kind(); }
  bool publish(const std::string& channel, const void* data, std::size_t size) override;
  int subscribe(const std::string& pattern, RawHandler handler, void* context, int queue_capacity) override;
  void unsubscribe(int id) override;
  int handle_timeout(int timeout_ms) override;
  TransportRefusals refusals() const override;
  bool channel_groups() const override { return inner_->channel_groups(); }

  const AuthCounters& counters() const { return auth_.counters(); }
  const Authenticator& authenticator() const { return auth_; }
  Transport& inner() { return *inner_; }

 private:
  struct Sub {
    AuthenticatedTransport* self;
    RawHandler handler;
    void* context;
    int id = 0;
    int receiver = 0;  // 1..64 in order of subscription (Authenticator::open), 0 beyond
  };
  static void dispatch(const RawMessage& m, void* sub);
  void refused_warning(const std::string& channel, Verdict v, std::size_t size);

  std::unique_ptr<Transport> owned_;
  Transport* inner_;
  Authenticator auth_;
  std::string who_;
  std::FILE* log_;
  std::list<Sub> subs_;  // stable addresses: the inner transport holds a pointer to each
  std::vector<std::uint8_t> out_;
  std::int64_t warnings_ = 0;
  int subscriptions_ = 0;
};

}  // namespace elaslam::transport::auth

// SPDX-License-Identifier: Apache-2.0
// Message authentication (docs/security.md "Message authentication"). Every message
// carries, after LCM's encoded payload, a trailer of 98 bytes, big-endian:
//
//   offset  size  field
//   0       4     magic "ELA2"
//   4       2     sender id (int16): a robot's id 1..16, kSenderMain, kSenderSimulator, kSenderTool
//   6       4     key id: the first four bytes of the sender's public key (keys.hpp)
//   10      8     mission id (uint64): the mission the sender belongs to (team.mission)
//   18      8     sender incarnation (int64): larger at each start of the sender (incarnation.hpp)
//   26      8     counter (uint64): 1, 2, 3, ... per message of this incarnation, over all its channels
//   34      64    Ed25519 signature, with the sender's key, of
//                 SHA-512( u32(len(channel)) | channel | payload | bytes 0..33 )
//
// LCM's generated decoders (C++, Python, Java) read what their type needs and ignore
// what follows, so recordings, lcm-spy and the Python tools read signed messages
// unchanged.
//
// Receiving, before anything decodes the bytes, a message is refused and counted when
// it has no trailer (unauthenticated), its key id is none of its sender's keys in the
// roster or a revoked one (unknown key), its signature does not verify with that key
// (forged or altered), its sender may not publish on the channel (wrong sender), it
// belongs to another mission (other mission), its counter was seen or is too old for
// the sender's window (replayed), its counter jumps further ahead than kMaxCounterJump
// (jump: held; the next message that continues it confirms it, a partition healed),
// or its incarnation is older than every one tracked while its sender is heard
// (stale). Per sender id the windows of the last kIncarnations incarnations are kept,
// each the highest counter seen and a bitmap of the kWindow counters below it (IPsec's
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

#include "elaslam/transport/keys.hpp"
#include "elaslam/transport/transport.hpp"

namespace elaslam::transport::auth {

constexpr std::size_t kMagicBytes = 4;
constexpr std::size_t kHeaderBytes = 34;  // magic, sender, key id, mission, incarnation, counter: signed after the payload
constexpr std::size_t kSignatureBytes = 64;
constexpr std::size_t kTrailerBytes = kHeaderBytes + kSignatureBytes;  // 98
constexpr char kMagic[kMagicBytes] = {'E', 'L', 'A', '2'};

/// Replay windows: incarnations tracked per sender id, counters per window.
constexpr int kIncarnations = 4;
constexpr int kWindow = 256;
/// The largest forward jump of a sender's counter taken as it comes: about three minutes
/// of the busiest sender (main_robot at 100 Hz with 16 robots sends some 6,000
/// messages a second), more than any receiver misses between two messages it hears,
/// whatever channels it reads. A jump beyond is held (refused) until the sender's
/// next message continues it: a datagram with a far counter cannot silence a sender.
constexpr std::uint64_t kMaxCounterJump = std::uint64_t{1} << 20;
/// An incarnation older than every one tracked for its sender is taken (a sender that
/// restarted with its counter or clock reset) only when none of the tracked ones was
/// heard for this long: while the sender is heard it is a replay, and refused.
constexpr std::int64_t kQuietUs = 2000000;

enum class Verdict : std::uint8_t {
  kAccepted = 0,
  kUnauthenticated,  // shorter than a trailer, or no magic: sent without the layer (no key)
  kForged,           // the signature does not verify: forged, altered
  kUnknownKey,       // the key id is none of the sender's keys in the roster (or a revoked one's)
  kWrongSender,      // the sender id may not publish on this channel (or is no team sender)
  kOtherMission,     // signed for another mission (a recording of an earlier one)
  kReplayed,         // counter seen before, or below the sender's window
  kJump,             // counter further ahead than kMaxCounterJump: held until the next message confirms it
  kStale,            // an incarnation older than every one tracked while its sender is heard
  kMalformed,        // not a message at all: a size or channel name no datagram can have (malformed_message)
};
constexpr int kVerdicts = 10;
const char* to_string(Verdict v);
/// A short name for counters and JSON: "forged", "other_mission", ...
const char* key_of(Verdict v);

/// Refusals by reason, and what went through.
struct AuthCounters {
  std::int64_t sealed = 0;    // messages sent with a trailer
  std::int64_t accepted = 0;  // messages that verified
  std::array<std::int64_t, kVerdicts> refused_by{};  // index: Verdict (kAccepted unused)
  std::int64_t healed = 0;    // counter jumps confirmed by the next message (a partition healed)
  std::int64_t refused() const;
};

/// Who sent a verified message.
struct Sender {
  std::int16_t id = 0;
  std::uint32_t key_id = 0;
  std::uint64_t mission = 0;
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
  /// kAccepted (and recorded), kReplayed, kJump, kStale or kWrongSender (an id without
  /// a slot). `now_us`: the receiver's monotonic clock (kQuietUs); *healed set when a
  /// held jump was confirmed by this message.
  Verdict check(const Sender& s, std::int64_t now_us, bool* healed = nullptr);

 private:
  struct Window {
    std::int64_t incarnation = 0;
    std::uint64_t highest = 0;                       // highest counter seen (0: none)
    std::uint64_t held = 0;                          // a counter beyond kMaxCounterJump, waiting to be confirmed
    std::array<std::uint64_t, kWindow / 64> bits{};  // bit i: counter highest - i seen
    std::int64_t heard_us = 0;                       // when a message of it was last accepted
    bool used = false;
  };
  struct Slot {
    std::array<Window, kIncarnations> windows;
  };
  static int slot_of(std::int16_t id);
  static void slide(Window* w, std::uint64_t counter);
  std::array<Slot, kMaxRobotSenders + 4> slots_{};  // robots 1..16, main, simulator, tool (and 0 unused)
};

/// What a process authenticates with: the team's roster and mission, and for a process
/// that sends, its own signing key and sender id.
struct AuthSetup {
  Roster roster;
  std::uint64_t mission = 0;
  SigningKey key;          // empty: this process only receives (viewer, monitor, evaluate)
  std::int16_t sender_id = kSenderTool;
  std::int64_t incarnation = 0;
  std::string channel_suffix;
};

/// Signs outgoing and verifies incoming messages of one process.
class Authenticator {
 public:
  explicit Authenticator(AuthSetup setup);
  Authenticator(const Authenticator&) = delete;
  Authenticator& operator=(const Authenticator&) = delete;

  /// Append the trailer to `buf`'s first `size` bytes (the payload); `buf` must hold
  /// size + kTrailerBytes. Returns size + kTrailerBytes. Needs a signing key.
  std::size_t seal(const std::string& channel, std::uint8_t* buf, std::size_t size);

  /// Verify a received message; on kAccepted, *payload_size is its size without the
  /// trailer and *sender who sent it. Allocates nothing. `receiver` (1..64, 0: none)
  /// names the subscription it is handed to: LCM hands one datagram to every
  /// subscription that matches its channel, and the message just accepted is accepted
  /// again for each other receiver once (a replay reaches a receiver that had it).
  /// `now_us`: the receiver's monotonic clock (0: now).
  Verdict open(const std::string& channel, const std::uint8_t* data, std::size_t size, std::size_t* payload_size,
               Sender* sender, int receiver = 0, std::int64_t now_us = 0);
  /// The signature, key, mission and sender checks of open() without the replay check.
  Verdict verify(const std::string& channel, const std::uint8_t* data, std::size_t size, std::size_t* payload_size,
                 Sender* sender) const;

  const AuthCounters& counters() const { return counters_; }
  std::int16_t sender_id() const { return setup_.sender_id; }
  std::int64_t incarnation() const { return setup_.incarnation; }
  std::uint64_t mission() const { return setup_.mission; }
  bool can_sign() const { return !setup_.key.empty(); }
  const Roster& roster() const { return setup_.roster; }

 private:
  void digest(const std::string& channel, const std::uint8_t* payload, std::size_t size, const std::uint8_t* header,
              std::uint8_t* out) const;

  AuthSetup setup_;
  std::uint32_t key_id_ = 0;
  std::uint64_t counter_ = 0;
  ReplayGuard guard_;
  AuthCounters counters_;
  Sender last_{};                     // the message accepted last
  std::uint64_t last_receivers_ = 0;  // bit r - 1: receiver r has had it
  std::size_t last_size_ = 0;         // ... its size, channel and trailer
  std::string last_channel_;
  std::array<std::uint8_t, kTrailerBytes> last_trailer_{};
};

/// A Transport that signs what it publishes and verifies what it receives, around
/// another transport (LcmTransport). Refused messages never reach a subscriber: they
/// are counted (counters(), refused()) and logged at a bounded rate (the first 20,
/// then every 1000th) naming the channel and the reason.
class AuthenticatedTransport final : public Transport {
 public:
  /// `log`: where refusals are said (nullptr: counted only); `who` prefixes the lines.
  AuthenticatedTransport(std::unique_ptr<Transport> inner, AuthSetup setup, std::string who, std::FILE* log = stderr);
  /// The same around a transport that the caller keeps (and that outlives this one):
  /// several processes' layers on one in-process bus in the tests.
  AuthenticatedTransport(Transport& inner, AuthSetup setup, std::string who, std::FILE* log = stderr);
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
  void refused_warning(const std::string& channel, Verdict v, std::size_t size, const Sender& s);

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

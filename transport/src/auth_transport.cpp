// SPDX-License-Identifier: Apache-2.0
#include "elaslam/transport/auth_transport.hpp"

#include <chrono>
#include <cstring>
#include <numeric>
#include <stdexcept>
#include <string_view>

#include <sodium.h>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/log.hpp"
#include "elaslam/common/contract.hpp"

namespace elaslam::transport::auth {
namespace {

static_assert(kWindow % 64 == 0);
static_assert(crypto_hash_sha512_BYTES == 64 && crypto_sign_BYTES == kSignatureBytes);

void put_be(std::uint8_t* p, std::uint64_t v, int bytes) {
  for (int i = bytes - 1; i >= 0; --i, v >>= 8) p[i] = static_cast<std::uint8_t>(v & 0xff);
}
std::uint64_t get_be(const std::uint8_t* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  return v;
}

bool is_robot(std::int16_t id) { return id >= 1 && id <= contract::kMaxRobots; }

std::int64_t monotonic_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// The robot_id field of landmark_event_t, lmap_events_t and lmap_snapshot_t: after the 8-byte
// fingerprint, int64 utime and int32 frame (LCM encodes big-endian, in field order).
constexpr std::size_t kRobotIdOffset = 8 + 8 + 4;

}  // namespace

const char* to_string(Verdict v) {
  switch (v) {
    case Verdict::kAccepted: return "accepted";
    case Verdict::kUnauthenticated: return "unauthenticated (no trailer)";
    case Verdict::kForged: return "forged or altered (the signature does not verify)";
    case Verdict::kUnknownKey: return "signed with a key that is not the sender's in the roster (unknown or revoked)";
    case Verdict::kWrongSender: return "sender may not publish on this channel";
    case Verdict::kOtherMission: return "of another mission";
    case Verdict::kReplayed: return "replayed (counter seen or too old)";
    case Verdict::kJump: return "counter jumps too far ahead (held until the sender's next message confirms it)";
    case Verdict::kStale: return "stale incarnation (older than every one tracked, while its sender is heard)";
    case Verdict::kMalformed: return "malformed (a size or channel name no message can have)";
  }
  return "?";
}

const char* key_of(Verdict v) {
  switch (v) {
    case Verdict::kAccepted: return "accepted";
    case Verdict::kUnauthenticated: return "unauthenticated";
    case Verdict::kForged: return "forged";
    case Verdict::kUnknownKey: return "unknown_key";
    case Verdict::kWrongSender: return "wrong_sender";
    case Verdict::kOtherMission: return "other_mission";
    case Verdict::kReplayed: return "replayed";
    case Verdict::kJump: return "jump";
    case Verdict::kStale: return "stale";
    case Verdict::kMalformed: return "malformed";
  }
  return "?";
}

std::int64_t AuthCounters::refused() const {
  return std::accumulate(refused_by.begin(), refused_by.end(), std::int64_t{0});
}

bool sender_may_publish(std::int16_t id, const std::string& channel, const std::string& suffix,
                        const std::uint8_t* payload, std::size_t size) {
  std::string_view base;
  if (!channels::strip_suffix(channel, suffix, &base)) return true;  // not a team channel
  using namespace channels;
  // (main_robot checks every event of an LMAP_EVENTS against its header's robot_id.)
  if (base == kLmapEvent || base == kLmapEvents || base == kLmapSnapshot)
    return is_robot(id) && size >= kRobotIdOffset + 2 &&
           static_cast<std::int16_t>(get_be(payload + kRobotIdOffset, 2)) == id;
  if (base == kGlobalMap || base == kGlobalMoving || base == kGlobalTracks || base == kDynamicNotice ||
      base == kStatusMain || base == kLmapResync || robot_of(base, kTeamMapPrefix) > 0)
    return id == kSenderMain;
  if (base == kGroundTruth || base == kRunInfo || base == kStatusSim || robot_of(base, kSensorPrefix) > 0)
    return id == kSenderSimulator;
  if (const int r = robot_of(base, kPosePrefix); r > 0) return id == r;
  if (const int r = robot_of(base, kStatusRobotPrefix); r > 0) return id == r;
  if (const int r = robot_of(base, kCandidatesPrefix); r > 0) return id == r;
  if (const int r = robot_of(base, kTracksPrefix); r > 0) return id == r;
  return true;  // another channel (a tool's, a test's): any sender of the team
}

// ---- ReplayGuard --------------------------------------------------------------------

int ReplayGuard::slot_of(std::int16_t id) {
  if (is_robot(id)) return id;
  switch (id) {
    case kSenderMain: return contract::kMaxRobots + 1;
    case kSenderSimulator: return contract::kMaxRobots + 2;
    case kSenderTool: return contract::kMaxRobots + 3;
    default: return -1;
  }
}

void ReplayGuard::slide(Window* w, std::uint64_t counter) {
  const std::uint64_t shift = counter - w->highest;
  if (shift >= static_cast<std::uint64_t>(kWindow)) {
    w->bits.fill(0);
  } else {
    const int words = static_cast<int>(shift / 64), bits = static_cast<int>(shift % 64);
    for (int i = kWindow / 64 - 1; i >= 0; --i) {
      std::uint64_t v = i - words >= 0 ? w->bits[static_cast<std::size_t>(i - words)] << bits : 0;
      if (bits != 0 && i - words - 1 >= 0) v |= w->bits[static_cast<std::size_t>(i - words - 1)] >> (64 - bits);
      w->bits[static_cast<std::size_t>(i)] = v;
    }
  }
  w->highest = counter;
  w->bits[0] |= 1;
}

Verdict ReplayGuard::check(const Sender& s, std::int64_t now_us, bool* healed) {
  if (healed != nullptr) *healed = false;
  const int slot = slot_of(s.id);
  if (slot < 0) return Verdict::kWrongSender;
  if (s.counter == 0) return Verdict::kReplayed;  // counters start at 1
  auto& ws = slots_[static_cast<std::size_t>(slot)].windows;
  Window* w = nullptr;
  Window* oldest = nullptr;
  bool heard = false;  // a tracked incarnation of this sender was heard lately
  for (Window& c : ws) {
    if (c.used && now_us - c.heard_us < kQuietUs) heard = true;
    if (c.used && c.incarnation == s.incarnation) w = &c;
    if (oldest == nullptr || !c.used || (oldest->used && c.incarnation < oldest->incarnation)) oldest = &c;
  }
  if (w == nullptr) {  // a new incarnation: a free window, else the oldest's if it is older
    if (oldest->used && s.incarnation < oldest->incarnation) {
      if (heard) return Verdict::kStale;
      // Every tracked one quiet: the sender started again with a smaller incarnation
      // (its start count or clock reset). The window heard least recently gives way.
      for (Window& c : ws)
        if (c.heard_us < oldest->heard_us) oldest = &c;
    }
    *oldest = Window{};
    oldest->used = true;
    oldest->incarnation = s.incarnation;
    w = oldest;
  }
  if (s.counter > w->highest) {
    if (w->highest != 0 && s.counter - w->highest > kMaxCounterJump) {
      // Far ahead: taken only when the next message continues it (a partition longer
      // than the bound); a lone datagram with a far counter never moves the window.
      const bool continues = w->held != 0 && s.counter > w->held && s.counter - w->held <= kMaxCounterJump;
      if (!continues) {
        w->held = s.counter;
        return Verdict::kJump;
      }
      if (healed != nullptr) *healed = true;
    }
    w->held = 0;
    slide(w, s.counter);
    w->heard_us = now_us;
    return Verdict::kAccepted;
  }
  const std::uint64_t back = w->highest - s.counter;
  if (back >= static_cast<std::uint64_t>(kWindow)) return Verdict::kReplayed;  // below the window
  std::uint64_t& word = w->bits[back / 64];
  const std::uint64_t bit = std::uint64_t{1} << (back % 64);
  if ((word & bit) != 0) return Verdict::kReplayed;
  word |= bit;
  w->heard_us = now_us;
  return Verdict::kAccepted;
}

// ---- Authenticator ------------------------------------------------------------------

Authenticator::Authenticator(AuthSetup setup) : setup_(std::move(setup)) {
  last_channel_.reserve(contract::kMaxChannelBytes + 1);
  if (sodium_init() < 0) throw std::runtime_error("libsodium could not be initialised");
  if (setup_.roster.empty()) throw std::invalid_argument("Authenticator: no public keys (team.public_keys)");
  if (setup_.mission == 0) throw std::invalid_argument("Authenticator: no mission id (team.mission)");
  if (!setup_.key.empty()) {
    if (!setup_.roster.holds(setup_.sender_id, setup_.key.public_key()))
      throw std::invalid_argument("Authenticator: this node's public key is not " + sender_name(setup_.sender_id) +
                                  "'s in the roster (team.public_keys)");
    key_id_ = key_id(setup_.key.public_key());
  }
}

void Authenticator::digest(const std::string& channel, const std::uint8_t* payload, std::size_t size,
                           const std::uint8_t* header, std::uint8_t* out) const {
  crypto_hash_sha512_state st;
  crypto_hash_sha512_init(&st);
  std::uint8_t len[4];
  put_be(len, channel.size(), 4);
  crypto_hash_sha512_update(&st, len, sizeof len);
  crypto_hash_sha512_update(&st, reinterpret_cast<const unsigned char*>(channel.data()), channel.size());
  crypto_hash_sha512_update(&st, payload, size);
  crypto_hash_sha512_update(&st, header, kHeaderBytes);
  crypto_hash_sha512_final(&st, out);
}

std::size_t Authenticator::seal(const std::string& channel, std::uint8_t* buf, std::size_t size) {
  if (setup_.key.empty()) throw std::logic_error("Authenticator::seal: this process has no signing key");
  std::uint8_t* t = buf + size;
  std::memcpy(t, kMagic, kMagicBytes);
  put_be(t + 4, static_cast<std::uint16_t>(setup_.sender_id), 2);
  put_be(t + 6, key_id_, 4);
  put_be(t + 10, setup_.mission, 8);
  put_be(t + 18, static_cast<std::uint64_t>(setup_.incarnation), 8);
  put_be(t + 26, ++counter_, 8);
  std::uint8_t d[64];
  digest(channel, buf, size, t, d);
  setup_.key.sign(d, t + kHeaderBytes);
  ++counters_.sealed;
  return size + kTrailerBytes;
}

Verdict Authenticator::verify(const std::string& channel, const std::uint8_t* data, std::size_t size,
                              std::size_t* payload_size, Sender* sender) const {
  if (malformed_message(channel, data, size) != nullptr) return Verdict::kMalformed;
  if (size < kTrailerBytes) return Verdict::kUnauthenticated;
  const std::size_t n = size - kTrailerBytes;
  const std::uint8_t* t = data + n;
  if (std::memcmp(t, kMagic, kMagicBytes) != 0) return Verdict::kUnauthenticated;
  sender->id = static_cast<std::int16_t>(get_be(t + 4, 2));
  sender->key_id = static_cast<std::uint32_t>(get_be(t + 6, 4));
  sender->mission = get_be(t + 10, 8);
  sender->incarnation = static_cast<std::int64_t>(get_be(t + 18, 8));
  sender->counter = get_be(t + 26, 8);
  const PublicKey* key = setup_.roster.find(sender->id, sender->key_id);
  if (key == nullptr) return Verdict::kUnknownKey;
  std::uint8_t d[64];
  digest(channel, data, n, t, d);
  if (!verify_signature(*key, d, t + kHeaderBytes)) return Verdict::kForged;
  // Signed by the one holder of the key: what it says of itself is now its word.
  if (!sender_may_publish(sender->id, channel, setup_.channel_suffix, data, n)) return Verdict::kWrongSender;
  if (sender->mission != setup_.mission) return Verdict::kOtherMission;
  *payload_size = n;
  return Verdict::kAccepted;
}

Verdict Authenticator::open(const std::string& channel, const std::uint8_t* data, std::size_t size,
                            std::size_t* payload_size, Sender* sender, int receiver, std::int64_t now_us) {
  const std::uint64_t bit = receiver >= 1 && receiver <= 64 ? std::uint64_t{1} << (receiver - 1) : 0;
  // The datagram just accepted, handed to another subscription (LCM hands one datagram
  // to each subscription that matches its channel, one after the other): accepted once
  // more without a second signature check. The same channel, size and trailer
  // (signature included); a replay reaching a receiver that had it is refused.
  if (bit != 0 && (last_receivers_ & bit) == 0 && last_.counter != 0 && size == last_size_ &&
      size >= kTrailerBytes && channel == last_channel_ &&
      std::memcmp(data + size - kTrailerBytes, last_trailer_.data(), kTrailerBytes) == 0) {
    last_receivers_ |= bit;
    *payload_size = size - kTrailerBytes;
    *sender = last_;
    ++counters_.accepted;
    return Verdict::kAccepted;
  }
  Verdict v = verify(channel, data, size, payload_size, sender);
  bool healed = false;
  if (v == Verdict::kAccepted) v = guard_.check(*sender, now_us != 0 ? now_us : monotonic_us(), &healed);
  if (v != Verdict::kAccepted) {
    ++counters_.refused_by[static_cast<std::size_t>(v)];
    return v;
  }
  if (healed) ++counters_.healed;
  ++counters_.accepted;
  last_ = *sender;
  last_receivers_ = bit;
  last_size_ = size;
  last_channel_.assign(channel);  // capacity reserved: no allocation
  std::memcpy(last_trailer_.data(), data + size - kTrailerBytes, kTrailerBytes);
  return v;
}

// ---- AuthenticatedTransport ---------------------------------------------------------

AuthenticatedTransport::AuthenticatedTransport(std::unique_ptr<Transport> inner, AuthSetup setup, std::string who,
                                               std::FILE* log)
    : owned_(std::move(inner)), inner_(owned_.get()), auth_(std::move(setup)), who_(std::move(who)), log_(log) {}

AuthenticatedTransport::AuthenticatedTransport(Transport& inner, AuthSetup setup, std::string who, std::FILE* log)
    : inner_(&inner), auth_(std::move(setup)), who_(std::move(who)), log_(log) {}

AuthenticatedTransport::~AuthenticatedTransport() {
  for (const Sub& s : subs_) inner_->unsubscribe(s.id);
}

bool AuthenticatedTransport::publish(const std::string& channel, const void* data, std::size_t size) {
  if (out_.size() < size + kTrailerBytes) out_.resize(size + kTrailerBytes);  // grows once to the largest message
  std::memcpy(out_.data(), data, size);
  const std::size_t n = auth_.seal(channel, out_.data(), size);
  return inner_->publish(channel, out_.data(), n);
}

int AuthenticatedTransport::subscribe(const std::string& pattern, RawHandler handler, void* context,
                                      int queue_capacity) {
  Sub& s = subs_.emplace_back(Sub{this, handler, context});
  s.receiver = subscriptions_ < 64 ? ++subscriptions_ : 0;
  s.id = inner_->subscribe(pattern, &AuthenticatedTransport::dispatch, &s, queue_capacity);
  if (s.id <= 0) {
    subs_.pop_back();
    return 0;
  }
  return s.id;
}

void AuthenticatedTransport::unsubscribe(int id) {
  for (auto it = subs_.begin(); it != subs_.end(); ++it) {
    if (it->id != id) continue;
    inner_->unsubscribe(id);
    subs_.erase(it);
    return;
  }
}

TransportRefusals AuthenticatedTransport::refusals() const {
  const TransportRefusals inner = inner_->refusals();  // what never reached this layer
  const AuthCounters& c = auth_.counters();
  const auto by = [&](Verdict v) { return c.refused_by[static_cast<std::size_t>(v)]; };
  TransportRefusals r = inner;
  r.total += c.refused();
  r.unauthenticated += by(Verdict::kUnauthenticated);
  r.malformed += by(Verdict::kMalformed);
  r.other_mission += by(Verdict::kOtherMission);
  r.jumps += by(Verdict::kJump);
  r.healed += c.healed;
  return r;
}

int AuthenticatedTransport::handle_timeout(int timeout_ms) { return inner_->handle_timeout(timeout_ms); }

// The one entry of every received message: verified before any subscriber (and so
// before any decoder) sees its bytes; passed on without the trailer.
void AuthenticatedTransport::dispatch(const RawMessage& m, void* context) {
  auto* sub = static_cast<Sub*>(context);
  AuthenticatedTransport& self = *sub->self;
  std::size_t payload_size = 0;
  Sender sender;
  const Verdict v = self.auth_.open(m.channel, m.data, m.size, &payload_size, &sender, sub->receiver);
  if (v != Verdict::kAccepted) return self.refused_warning(m.channel, v, m.size, sender);
  sub->handler(RawMessage{m.channel, m.data, payload_size, m.recv_utime}, sub->context);
}

void AuthenticatedTransport::refused_warning(const std::string& channel, Verdict v, std::size_t size, const Sender& s) {
  // No allocation: a flood of forged datagrams costs a signature check each and a counter, nothing more.
  char name[4 * contract::kMaxChannelBytes + 8];
  if ((++warnings_ <= 20 || warnings_ % 1000 == 0) && log_ != nullptr) {
    if (v == Verdict::kUnauthenticated || v == Verdict::kMalformed)
      log::print(log_, log::Priority::kWarning,
                 "%s: refused a message on %s (%zu bytes): %s (%lld refused so far)\n", who_.c_str(),
                 printable_channel(channel, name), size, to_string(v),
                 static_cast<long long>(auth_.counters().refused()));
    else  // the trailer's claims (unverified for kUnknownKey and kForged)
      log::print(log_, log::Priority::kWarning,
                 "%s: refused a message on %s (%zu bytes, sender %d, mission %016llx, incarnation %lld, "
                 "counter %llu): %s (%lld refused so far)\n",
                 who_.c_str(), printable_channel(channel, name), size, s.id,
                 static_cast<unsigned long long>(s.mission), static_cast<long long>(s.incarnation),
                 static_cast<unsigned long long>(s.counter), to_string(v),
                 static_cast<long long>(auth_.counters().refused()));
  }
}

}  // namespace elaslam::transport::auth

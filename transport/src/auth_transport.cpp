#include "elaslam/transport/auth_transport.hpp"

#include <cstring>
#include <stdexcept>
#include <string_view>

#include <sodium.h>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/contract.hpp"

namespace elaslam::transport::auth {
namespace {

static_assert(crypto_auth_hmacsha512256_BYTES == kMacBytes);
static_assert(crypto_auth_hmacsha512256_KEYBYTES == TeamKey::kBytes);
static_assert(kWindow % 64 == 0);

void put_be(std::uint8_t* p, std::uint64_t v, int bytes) {
  for (int i = bytes - 1; i >= 0; --i, v >>= 8) p[i] = static_cast<std::uint8_t>(v & 0xff);
}
std::uint64_t get_be(const std::uint8_t* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  return v;
}

/// `channel` without `suffix`; false when it does not end with it.
bool is_robot(std::int16_t id) { return id >= 1 && id <= contract::kMaxRobots; }

// The robot_id field of landmark_event_t, lmap_events_t and lmap_snapshot_t: after the 8-byte
// fingerprint, int64 utime and int32 frame (LCM encodes big-endian, in field order).
constexpr std::size_t kRobotIdOffset = 8 + 8 + 4;

}  // namespace

const char* to_string(Verdict v) {
  switch (v) {
    case Verdict::kAccepted: return "accepted";
    case Verdict::kUnauthenticated: return "unauthenticated (no trailer)";
    case Verdict::kForged: return "forged or altered (MAC does not verify)";
    case Verdict::kWrongSender: return "sender may not publish on this channel";
    case Verdict::kReplayed: return "replayed (counter seen or too old)";
    case Verdict::kStale: return "stale incarnation (older than every one tracked)";
  }
  return "?";
}

std::int64_t AuthCounters::refused() const {
  std::int64_t n = 0;
  for (std::int64_t c : refused_by) n += c;
  return n;
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
  if (base == kGlobalMap || base == kGlobalMoving || base == kDynamicNotice || base == kStatusMain || base == kLmapResync ||
      robot_of(base, kTeamMapPrefix) > 0)
    return id == kSenderMain;
  if (base == kGroundTruth || base == kRunInfo || base == kStatusSim || robot_of(base, kSensorPrefix) > 0)
    return id == kSenderSimulator;
  if (const int r = robot_of(base, kPosePrefix); r > 0) return id == r;
  if (const int r = robot_of(base, kStatusRobotPrefix); r > 0) return id == r;
  if (const int r = robot_of(base, kCandidatesPrefix); r > 0) return id == r;
  return true;  // another channel (a tool's, a test's): any sender of the team
}

static_assert(kMaxRobotSenders == contract::kMaxRobots);

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

Verdict ReplayGuard::check(const Sender& s) {
  const int slot = slot_of(s.id);
  if (slot < 0) return Verdict::kWrongSender;
  if (s.counter == 0) return Verdict::kReplayed;  // counters start at 1
  auto& ws = slots_[static_cast<std::size_t>(slot)].windows;
  Window* w = nullptr;
  Window* oldest = nullptr;
  for (Window& c : ws) {
    if (c.used && c.incarnation == s.incarnation) {
      w = &c;
      break;
    }
    if (oldest == nullptr || !c.used || (oldest->used && c.incarnation < oldest->incarnation)) oldest = &c;
  }
  if (w == nullptr) {  // a new incarnation: a free window, else the oldest's if it is older
    if (oldest->used && s.incarnation < oldest->incarnation) return Verdict::kStale;
    *oldest = Window{};
    oldest->used = true;
    oldest->incarnation = s.incarnation;
    w = oldest;
  }
  if (s.counter > w->highest) {  // ahead: slide the window
    const std::uint64_t shift = s.counter - w->highest;
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
    w->highest = s.counter;
    w->bits[0] |= 1;
    return Verdict::kAccepted;
  }
  const std::uint64_t back = w->highest - s.counter;
  if (back >= static_cast<std::uint64_t>(kWindow)) return Verdict::kReplayed;  // below the window
  std::uint64_t& word = w->bits[back / 64];
  const std::uint64_t bit = std::uint64_t{1} << (back % 64);
  if ((word & bit) != 0) return Verdict::kReplayed;
  word |= bit;
  return Verdict::kAccepted;
}

// ---- Authenticator ------------------------------------------------------------------

struct Authenticator::Keyed {
  crypto_auth_hmacsha512256_state state;
};

Authenticator::Authenticator(const TeamKey& key, std::int16_t sender_id, std::int64_t incarnation,
                             std::string channel_suffix)
    : keyed_(std::make_unique<Keyed>()), sender_id_(sender_id), incarnation_(incarnation),
      suffix_(std::move(channel_suffix)) {
  if (sodium_init() < 0) throw std::runtime_error("libsodium could not be initialised");
  if (key.empty()) throw std::invalid_argument("Authenticator: no team key");
  crypto_auth_hmacsha512256_init(&keyed_->state, key.data(), TeamKey::kBytes);
}

Authenticator::~Authenticator() { sodium_memzero(&keyed_->state, sizeof keyed_->state); }

void Authenticator::mac(const std::string& channel, const std::uint8_t* payload, std::size_t size,
                        const std::uint8_t* header, std::uint8_t* out) const {
  crypto_auth_hmacsha512256_state st = keyed_->state;  // = init(key): the key's pads already hashed
  std::uint8_t len[4];
  put_be(len, channel.size(), 4);
  crypto_auth_hmacsha512256_update(&st, len, sizeof len);
  crypto_auth_hmacsha512256_update(&st, reinterpret_cast<const unsigned char*>(channel.data()), channel.size());
  crypto_auth_hmacsha512256_update(&st, payload, size);
  crypto_auth_hmacsha512256_update(&st, header, kHeaderBytes);
  crypto_auth_hmacsha512256_final(&st, out);
  sodium_memzero(&st, sizeof st);
}

std::size_t Authenticator::seal(const std::string& channel, std::uint8_t* buf, std::size_t size) {
  std::uint8_t* t = buf + size;
  std::memcpy(t, kMagic, kMagicBytes);
  put_be(t + 4, static_cast<std::uint16_t>(sender_id_), 2);
  put_be(t + 6, static_cast<std::uint64_t>(incarnation_), 8);
  put_be(t + 14, ++counter_, 8);
  mac(channel, buf, size, t, t + kHeaderBytes);
  ++counters_.sealed;
  return size + kTrailerBytes;
}

Verdict Authenticator::verify(const std::string& channel, const std::uint8_t* data, std::size_t size,
                              std::size_t* payload_size, Sender* sender) const {
  if (size < kTrailerBytes) return Verdict::kUnauthenticated;
  const std::size_t n = size - kTrailerBytes;
  const std::uint8_t* t = data + n;
  if (std::memcmp(t, kMagic, kMagicBytes) != 0) return Verdict::kUnauthenticated;
  std::uint8_t expected[kMacBytes];
  mac(channel, data, n, t, expected);
  if (crypto_verify_32(expected, t + kHeaderBytes) != 0) return Verdict::kForged;
  sender->id = static_cast<std::int16_t>(get_be(t + 4, 2));
  sender->incarnation = static_cast<std::int64_t>(get_be(t + 6, 8));
  sender->counter = get_be(t + 14, 8);
  if (!sender_may_publish(sender->id, channel, suffix_, data, n)) return Verdict::kWrongSender;
  *payload_size = n;
  return Verdict::kAccepted;
}

Verdict Authenticator::open(const std::string& channel, const std::uint8_t* data, std::size_t size,
                            std::size_t* payload_size, Sender* sender, int receiver) {
  Verdict v = verify(channel, data, size, payload_size, sender);
  const std::uint64_t bit = receiver >= 1 && receiver <= 64 ? std::uint64_t{1} << (receiver - 1) : 0;
  if (v == Verdict::kAccepted) {
    const bool again = sender->counter != 0 && last_.id == sender->id && last_.incarnation == sender->incarnation &&
                       last_.counter == sender->counter;
    if (again && bit != 0 && (last_receivers_ & bit) == 0) {  // the same datagram, another subscription
      last_receivers_ |= bit;
      ++counters_.accepted;
      return v;
    }
    v = guard_.check(*sender);
  }
  if (v != Verdict::kAccepted) {
    ++counters_.refused_by[static_cast<std::size_t>(v)];
    return v;
  }
  ++counters_.accepted;
  last_ = *sender;
  last_receivers_ = bit;
  return v;
}

// ---- AuthenticatedTransport ---------------------------------------------------------

AuthenticatedTransport::AuthenticatedTransport(std::unique_ptr<Transport> inner, const TeamKey& key,
                                               std::int16_t sender_id, std::int64_t incarnation,
                                               std::string channel_suffix, std::string who, std::FILE* log)
    : owned_(std::move(inner)), inner_(owned_.get()), auth_(key, sender_id, incarnation, std::move(channel_suffix)),
      who_(std::move(who)), log_(log) {}

AuthenticatedTransport::AuthenticatedTransport(Transport& inner, const TeamKey& key, std::int16_t sender_id,
                                               std::int64_t incarnation, std::string channel_suffix, std::string who,
                                               std::FILE* log)
    : inner_(&inner), auth_(key, sender_id, incarnation, std::move(channel_suffix)), who_(std::move(who)), log_(log) {}

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
  return {auth_.counters().refused(),
          auth_.counters().refused_by[static_cast<std::size_t>(Verdict::kUnauthenticated)]};
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
  if (v != Verdict::kAccepted) return self.refused_warning(m.channel, v, m.size);
  sub->handler(RawMessage{m.channel, m.data, payload_size}, sub->context);
}

void AuthenticatedTransport::refused_warning(const std::string& channel, Verdict v, std::size_t size) {
  // No allocation: a flood of forged datagrams costs a MAC each and a counter, nothing more.
  if ((++warnings_ <= 20 || warnings_ % 1000 == 0) && log_ != nullptr)
    std::fprintf(log_, "%s: refused a message on %s (%zu bytes): %s (%lld refused so far)\n", who_.c_str(),
                 channel.c_str(), size, to_string(v), static_cast<long long>(auth_.counters().refused()));
}

}  // namespace elaslam::transport::auth

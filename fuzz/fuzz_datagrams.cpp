// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: the receive path of robot_node and main_robot from the wire up. An
// input is a burst of raw udpm:// datagrams, as anyone on the team's network can send
// them, and each goes the way it goes in the processes (docs/security.md "Bytes from
// the network"): DatagramAssembler -> DatagramDispatcher (subscriptions matched as LCM
// matches them) -> malformed_message -> AuthenticatedTransport (the test team's keys)
// -> NodeShell (decode, validate) -> the ports' handlers (RobotPorts, MainPorts) -> the
// node. What the node publishes comes back to it as multicast loops back to the sender:
// framed as liblcm frames it, from the process's own address, after the datagram under
// way (a robot reads its own POSE).
//
// An input is [selector: 1 byte] then datagrams, [length: 2 bytes LE][bytes] repeated
// (the records that tests/system/raw_datagrams.py --write-corpus writes). selector % 4:
//   0  robot_node 1 with the team's keys (signs as robot 1, verifies every sender)
//   1  main_robot with the team's keys
//   2  robot_node 1 without authentication (a team without keys: the LCM transport itself)
//   3  main_robot without authentication
// A length 0xFFF8 + k (k = 0..7) is no datagram: the datagrams after it come from sender
// k (10.0.0.(k + 1), port 7667; sender 0 at first), so that the fragments of several
// senders interleave. No UDP datagram is longer than 65,507 bytes, so no datagram is
// lost to these. A length beyond the rest of the input takes the rest. Every datagram
// is fed from a heap block of exactly its size: a read past its end is
// AddressSanitizer's, wherever it is in the input.
//
// Per input the dispatcher and the transports above it are made anew; so are the node,
// its shell and its ports, unless the input before left them as made (no message reached
// a handler, nothing was published: ShellRig::untouched). An outcome depends on its
// input alone. Failures, besides a crash, a sanitizer report and an exception escaping:
// an invariant broken on a message the dispatcher hands a subscription (at most
// contract::kMaxMessageBytes; a channel of 1..63 printable characters, the
// subscription's own when it subscribed a plain name; a short datagram's message is its
// tail after the channel's NUL, and a short datagram is a message exactly when LCM's
// format says so); after an input that reached the node, its status and state must still
// be producible, and main's state must load back (as in fuzz_robot_node, fuzz_main_robot).
//
// `fuzz_datagrams --write-seeds=DIR` writes seeds of real signed traffic instead
// (fuzz/make_datagram_corpus.py) and exits: see write_seeds() at the end.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <list>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "../tests/support/test_keys.hpp"
#include "elaslam/common/channels.hpp"
#include "elaslam/main_robot/global_map.hpp"
#include "elaslam/main_robot/main_ports.hpp"
#include "elaslam/robot_node/robot_ports.hpp"
#include "elaslam/robot_node/robot_options.hpp"
#include "elaslam/robot_node/robot_state.hpp"
#include "elaslam/simulator/messages.hpp"
#include "elaslam/simulator/scenario.hpp"
#include "elaslam/simulator/world.hpp"
#include "elaslam/transport/auth_transport.hpp"
#include "elaslam/transport/udpm_receiver.hpp"
#include "fuzz_options.hpp"
#include "node_harness.hpp"

namespace {

using namespace elaslam;
using transport::RawHandler;
using transport::RawMessage;
using transport::Transport;
using transport::auth::AuthenticatedTransport;
using transport::auth::AuthSetup;

// Start times [us since the epoch] of the senders: incarnations (transport/incarnation.hpp).
constexpr std::int64_t kRobotIncarnation = 1'700'000'000'000'001;
constexpr std::int64_t kMainIncarnation = 1'700'000'000'000'002;
constexpr std::int64_t kSimIncarnation = 1'700'000'000'000'003;
constexpr int kConfigs = 4;
constexpr std::size_t kSenderToken = 0xFFF8;  // a length kSenderToken + k: sender k from here on
constexpr std::size_t kMaxDatagrams = 4096;   // per input: a bound on its cost
// Looped-back bytes per input; beyond, what the node publishes is dropped, as a full
// receive buffer drops it. Far above what a frame publishes (a global map: < 0.7 MB).
constexpr std::size_t kMaxLoopbackBytes = std::size_t{16} << 20;
// liblcm 1.3.1 on Linux (lcm/udpm_util.h): a message whose channel, NUL and payload fit
// 65,499 bytes goes in one datagram ("LC02"); a longer one in fragments ("LC03") of at
// most 65,487 bytes of channel and data each. (On macOS: 1,435 and 1,423.)
constexpr std::size_t kShortMax = 65499;
constexpr std::size_t kFragmentMax = 65487;
constexpr std::size_t kShortHeader = 8, kLongHeader = 20;

[[noreturn]] void fail(const char* what, const std::string& channel, std::size_t size) {
  char name[4 * contract::kMaxChannelBytes + 8];
  std::fprintf(stderr, "fuzz_datagrams: %s (channel '%s', %zu bytes)\n", what,
               transport::printable_channel(channel, name), size);
  std::abort();
}

/// Sender k's address and port, as UdpmReceiver packs them.
std::uint64_t sender_address(std::size_t k) { return (std::uint64_t{0x0A000001u + k} << 16) | 7667; }
constexpr std::uint64_t kOwnAddress = (std::uint64_t{0x0A000064u} << 16) | 7667;  // 10.0.0.100: the process's

std::uint32_t be32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}
void put_be(std::vector<std::uint8_t>* out, std::uint64_t v, int bytes) {
  for (int i = bytes - 1; i >= 0; --i) out->push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

/// The datagrams liblcm sends for one message (the format: udpm_receiver.hpp): one "LC02"
/// when the channel, its NUL and the payload fit `short_max` bytes, else "LC03" fragments
/// of at most `fragment_max` bytes of channel and data, the channel in fragment 0.
std::vector<std::vector<std::uint8_t>> lcm_datagrams(const std::string& channel, const std::uint8_t* data,
                                                     std::size_t size, std::uint32_t seq,
                                                     std::size_t short_max = kShortMax,
                                                     std::size_t fragment_max = kFragmentMax) {
  std::vector<std::vector<std::uint8_t>> out;
  const std::size_t whole = channel.size() + 1 + size;
  if (whole <= short_max) {
    std::vector<std::uint8_t>& d = out.emplace_back();
    d.reserve(kShortHeader + whole);
    d = {'L', 'C', '0', '2'};
    put_be(&d, seq, 4);
    d.insert(d.end(), channel.begin(), channel.end());
    d.push_back(0);
    d.insert(d.end(), data, data + size);
    return out;
  }
  const std::size_t count = (whole + fragment_max - 1) / fragment_max;
  std::size_t offset = 0;  // counts data bytes, not the channel's
  for (std::size_t i = 0; i < count; ++i) {
    std::vector<std::uint8_t>& d = out.emplace_back();
    d = {'L', 'C', '0', '3'};
    put_be(&d, seq, 4);
    put_be(&d, size, 4);
    put_be(&d, offset, 4);
    put_be(&d, i, 2);
    put_be(&d, count, 2);
    std::size_t room = fragment_max;
    if (i == 0) {
      d.insert(d.end(), channel.begin(), channel.end());
      d.push_back(0);
      room -= channel.size() + 1;
    }
    const std::size_t n = std::min(room, size - offset);
    d.insert(d.end(), data + offset, data + offset + n);
    offset += n;
  }
  return out;
}

/// A message as the process put it on the wire (the seeds' source).
struct Published {
  std::string channel;
  std::vector<std::uint8_t> bytes;  // with the authentication trailer when the process signs
};

/// The udpm:// transport of a process (LcmTransport over udpm://) without its socket:
/// subscriptions on a DatagramDispatcher, to which feed() hands each datagram. publish()
/// frames the message as liblcm does and queues its datagrams for the process's own
/// socket (multicast loopback), fed by drain(). Every message the dispatcher hands a
/// subscription is checked on its way (deliver).
class DatagramTransport final : public Transport {
 public:
  explicit DatagramTransport(std::vector<Published>* record = nullptr)
      : dispatcher_("fuzz", nullptr), record_(record) {}
  ~DatagramTransport() override {
    for (const Sub& s : subs_) dispatcher_.unsubscribe(s.id);
  }

  bool good() const override { return true; }
  const char* kind() const override { return "LCM"; }
  bool publish(const std::string& channel, const void* data, std::size_t size) override {
    const auto* p = static_cast<const std::uint8_t*>(data);
    if (record_ != nullptr) record_->push_back(Published{channel, std::vector<std::uint8_t>(p, p + size)});
    if (looped_ + size > kMaxLoopbackBytes) return true;  // sent; lost to a full receive buffer
    looped_ += size;
    for (auto& d : lcm_datagrams(channel, p, size, seq_++)) loopback_.push_back(std::move(d));
    return true;
  }
  int subscribe(const std::string& pattern, RawHandler handler, void* context, int /*queue_capacity*/) override {
    const bool plain = pattern.find_first_of("[](){}.*+?|^$\\") == std::string::npos;
    Sub& s = subs_.emplace_back(Sub{this, handler, context, pattern, plain});
    const int id = dispatcher_.subscribe(pattern, &DatagramTransport::deliver, &s);
    if (id == 0) {  // not a regular expression
      subs_.pop_back();
      return 0;
    }
    s.id = id;
    return id;
  }
  void unsubscribe(int id) override {
    for (auto it = subs_.begin(); it != subs_.end(); ++it) {
      if (it->id != id) continue;
      dispatcher_.unsubscribe(id);
      subs_.erase(it);
      return;
    }
  }
  int handle_timeout(int /*timeout_ms*/) override { return 0; }
  transport::TransportRefusals refusals() const override {
    const std::int64_t n = dispatcher_.malformed();
    return {n, 0, n};
  }
  const transport::DatagramDispatcher& dispatcher() const { return dispatcher_; }

  /// One datagram from `source`, as UdpmReceiver::read feeds it, from a heap block of
  /// exactly its size (a read past its end is AddressSanitizer's); then its verdict as a
  /// short message is checked against LCM's format, read here independently.
  void feed(const std::uint8_t* bytes, std::size_t n, std::uint64_t source, std::int64_t recv_utime) {
    const std::unique_ptr<std::uint8_t[]> block(new std::uint8_t[n]);
    if (n > 0) std::memcpy(block.get(), bytes, n);
    const std::uint8_t* d = block.get();
    datagram_ = d;
    size_ = n;
    recv_utime_ = recv_utime;
    deliveries_ = 0;
    const bool message = dispatcher_.feed(d, n, source, recv_utime);
    if (!message && deliveries_ > 0) fail("a datagram that completed no message was delivered", "", n);
    if (n >= kShortHeader && std::memcmp(d, "LC02", 4) == 0 && message != short_is_message(d, n))
      fail(message ? "a malformed short datagram went through" : "a well-formed short datagram was refused", "", n);
    datagram_ = nullptr;
  }
  /// The datagrams the process published meanwhile, as its socket receives them back.
  void drain(std::int64_t recv_utime) {
    while (!loopback_.empty()) {
      const std::vector<std::uint8_t> d = std::move(loopback_.front());
      loopback_.pop_front();
      feed(d.data(), d.size(), kOwnAddress, recv_utime);
    }
  }

 private:
  struct Sub {
    DatagramTransport* self;
    RawHandler handler;
    void* context;
    std::string pattern;
    bool plain;  // a channel name, not a regular expression
    int id = 0;
  };

  /// LCM's short message: a channel of 1..63 characters in '!'..'~' ended by a NUL within the datagram.
  static bool short_is_message(const std::uint8_t* d, std::size_t n) {
    for (std::size_t i = kShortHeader; i < n && i <= kShortHeader + contract::kMaxChannelBytes; ++i) {
      if (d[i] == 0) return i > kShortHeader;
      if (d[i] <= ' ' || d[i] > '~') return false;
    }
    return false;
  }

  static void deliver(const RawMessage& m, void* context) {
    const Sub& s = *static_cast<const Sub*>(context);
    const DatagramTransport& t = *s.self;
    const std::string& ch = m.channel;
    if (t.datagram_ == nullptr) fail("a message delivered outside feed()", ch, m.size);
    if (m.data == nullptr || m.size > contract::kMaxMessageBytes) fail("a message larger than any", ch, m.size);
    if (ch.empty() || ch.size() > contract::kMaxChannelBytes) fail("a channel name of impossible length", ch, m.size);
    for (const char c : ch)
      if (c <= ' ' || c > '~') fail("a channel name that is not printable ASCII", ch, m.size);
    if (s.plain && ch != s.pattern) fail("a message on a channel its subscription did not name", ch, m.size);
    if (m.recv_utime != t.recv_utime_) fail("a receive time that is not the datagram's", ch, m.size);
    const std::uint8_t* d = t.datagram_;
    if (std::memcmp(d, "LC02", 4) == 0) {
      const std::size_t head = kShortHeader + ch.size() + 1;
      if (t.size_ < head || std::memcmp(d + kShortHeader, ch.data(), ch.size()) != 0 || d[head - 1] != 0 ||
          m.data != d + head || m.size != t.size_ - head)
        fail("a short datagram's message is not its tail after the channel", ch, m.size);
    } else if (std::memcmp(d, "LC03", 4) != 0 || t.size_ < kLongHeader || m.size != be32(d + 8)) {
      fail("a fragmented message whose size is not its fragments' message size", ch, m.size);
    }
    ++s.self->deliveries_;
    s.handler(m, s.context);
  }

  transport::DatagramDispatcher dispatcher_;
  std::list<Sub> subs_;  // stable addresses: the dispatcher holds a pointer to each
  std::deque<std::vector<std::uint8_t>> loopback_;
  std::size_t looped_ = 0;
  std::uint32_t seq_ = 0;  // liblcm's, per process
  const std::uint8_t* datagram_ = nullptr;  // the datagram being fed
  std::size_t size_ = 0;
  std::int64_t recv_utime_ = 0;
  int deliveries_ = 0;
  std::vector<Published>* record_;
};

/// What the node shell subscribes to: it stands for the process's transport while the
/// node lives (across inputs), and passes each subscription, in order, to the chain of
/// the input under way (the authentication layer, or none, over a DatagramTransport),
/// which is made anew per input. Nothing of it is on a message's way: the chain calls
/// the shell's handlers directly.
class Front final : public Transport {
 public:
  void attach(Transport* chain) {
    chain_ = chain;
    for (Sub& s : subs_) {
      s.inner = chain_->subscribe(s.pattern, s.handler, s.context, s.queue);
      if (s.inner == 0) fail("the transport refused a subscription that the shell made", s.pattern, 0);
    }
  }
  void detach() {
    for (Sub& s : subs_) chain_->unsubscribe(s.inner);
    chain_ = nullptr;
  }

  bool good() const override { return true; }
  const char* kind() const override { return "LCM"; }
  bool publish(const std::string& channel, const void* data, std::size_t size) override {
    return chain_ != nullptr && chain_->publish(channel, data, size);
  }
  int subscribe(const std::string& pattern, RawHandler handler, void* context, int queue) override {
    Sub& s = subs_.emplace_back(Sub{next_id_++, pattern, handler, context, queue});
    if (chain_ != nullptr) s.inner = chain_->subscribe(pattern, handler, context, queue);
    return s.id;
  }
  void unsubscribe(int id) override {
    for (auto it = subs_.begin(); it != subs_.end(); ++it) {
      if (it->id != id) continue;
      if (chain_ != nullptr) chain_->unsubscribe(it->inner);
      subs_.erase(it);
      return;
    }
  }
  int handle_timeout(int timeout_ms) override { return chain_ != nullptr ? chain_->handle_timeout(timeout_ms) : 0; }
  transport::TransportRefusals refusals() const override {
    return chain_ != nullptr ? chain_->refusals() : transport::TransportRefusals{};
  }

 private:
  struct Sub {
    int id;
    std::string pattern;
    RawHandler handler;
    void* context;
    int queue;
    int inner = 0;  // the chain's id
  };
  std::list<Sub> subs_;
  Transport* chain_ = nullptr;
  int next_id_ = 1;
};

// ---- the two processes ------------------------------------------------------------------

// config/paper.yaml with 24 filter slots and the team's map on, as fuzz_robot_node's robot.
const RobotOptions& robot_options() {
  static const RobotOptions o = [] {
    RobotOptions r = fuzz::robot_options();
    r.ekf.capacity = 24;
    r.team_map_fuse = true;  // TEAM_MAP_1 subscribed
    return r;
  }();
  return o;
}

const AuthSetup& robot_setup() {
  static const AuthSetup s = test::team_setup(1, kRobotIncarnation);
  return s;
}
const AuthSetup& main_setup() {
  static const AuthSetup s = test::team_setup(transport::kSenderMain, kMainIncarnation);
  return s;
}

using RobotRig = fuzz::ShellRig<RobotNode, RobotPorts>;
using MainRig = fuzz::ShellRig<MainNode, MainPorts>;

RobotNode make_robot() {
  RobotNode n(robot_options(), 1);
  n.set_incarnation(kRobotIncarnation);
  return n;
}
MainNode make_main(const GlobalMapOptions& o = fuzz::main_options()) {
  MainNode n(o);
  n.set_incarnation(kMainIncarnation);
  return n;
}

/// After an input that reached the node: its status and state are still producible.
void check(RobotRig& r) {
  r.ports.publish_status();
  if (save_robot_state(r.node).empty()) fail("robot_node's state cannot be saved", "", 0);
}
void check(MainRig& r) {
  r.ports.publish_map();
  r.ports.publish_status();
  const std::string state = r.node.map().to_json();
  GlobalMap reloaded(fuzz::main_options());
  std::string why;
  if (!reloaded.from_json(state, &why)) {
    std::fprintf(stderr, "fuzz_datagrams: main_robot's saved state does not load back: %s\n", why.c_str());
    std::abort();
  }
}

/// One process of the target: its front and its node, kept while untouched.
template <class Rig>
struct Process {
  Front front;
  std::optional<Rig> rig;
};

/// Every datagram of `data` (the records after the selector) into `wire`, each followed
/// by what the process published meanwhile, 1 ms apart; returns the time after the last.
std::int64_t feed_datagrams(DatagramTransport& wire, const std::uint8_t* data, std::size_t size) {
  std::size_t at = 0, sender = 0, n = 0;
  std::int64_t t = fuzz::ShellRig<RobotNode, RobotPorts>::kEpoch;
  while (at + 2 <= size && n < kMaxDatagrams) {
    std::size_t len = data[at] | (std::size_t{data[at + 1]} << 8);
    at += 2;
    if (len >= kSenderToken) {
      sender = len - kSenderToken;
      continue;
    }
    len = std::min(len, size - at);
    wire.feed(data + at, len, sender_address(sender), t);
    at += len;
    ++n;
    wire.drain(t);
    t += 1000;
  }
  return t;
}

/// What became of an input's datagrams, on stderr ($FUZZ_DATAGRAMS_VERBOSE set: to see
/// that the seeds get through, e.g. `FUZZ_DATAGRAMS_VERBOSE=1 fuzz_datagrams -runs=0 DIR`).
void say_outcome(const char* name, const DatagramTransport& wire, const AuthenticatedTransport* auth,
                 const transport::NodeShell& shell) {
  const transport::ShellCounters c = shell.counters();
  std::fprintf(stderr, "fuzz_datagrams: %s: malformed %lld, dropped fragments %lld", name,
               static_cast<long long>(wire.dispatcher().malformed()),
               static_cast<long long>(wire.dispatcher().dropped_fragments()));
  if (auth != nullptr) {
    std::fprintf(stderr, "; authenticated %lld", static_cast<long long>(auth->counters().accepted));
    for (int v = 1; v < transport::auth::kVerdicts; ++v)
      if (const std::int64_t n = auth->counters().refused_by[static_cast<std::size_t>(v)]; n > 0)
        std::fprintf(stderr, ", %s %lld", transport::auth::key_of(static_cast<transport::auth::Verdict>(v)),
                     static_cast<long long>(n));
  }
  std::fprintf(stderr, "; to the node %lld (decode errors %lld, refused %lld, handler errors %lld); published %lld\n",
               static_cast<long long>(c.inputs.received), static_cast<long long>(c.inputs.decode_errors),
               static_cast<long long>(c.inputs.refused), static_cast<long long>(c.inputs.handler_errors),
               static_cast<long long>(c.published));
}

/// One input through one process: the transports made anew, the node if the last input touched it.
template <class Rig, class Make>
void run(Process<Rig>& p, const char* name, Make make, const AuthSetup* setup, const std::uint8_t* data,
         std::size_t size, std::vector<Published>* record = nullptr) {
  static const bool verbose = std::getenv("FUZZ_DATAGRAMS_VERBOSE") != nullptr;
  if (p.rig && !p.rig->untouched()) p.rig.reset();
  if (!p.rig) p.rig.emplace(p.front, name, make());
  DatagramTransport wire(record);
  std::optional<AuthenticatedTransport> auth;
  if (setup != nullptr) auth.emplace(wire, *setup, name, nullptr);
  p.front.attach(auth ? static_cast<Transport*>(&*auth) : &wire);
  const std::int64_t end = feed_datagrams(wire, data, size);
  if (verbose) say_outcome(name, wire, auth ? &*auth : nullptr, p.rig->shell);
  if (!p.rig->untouched()) {
    check(*p.rig);
    wire.drain(end);
  }
  p.front.detach();
}

int write_seeds(const std::string& dir);

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  const std::string flag = "--write-seeds=";
  for (int i = 1; i < *argc; ++i)
    if (std::strncmp((*argv)[i], flag.c_str(), flag.size()) == 0) std::exit(write_seeds((*argv)[i] + flag.size()));
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static Process<RobotRig> robot;
  static Process<MainRig> main;
  if (size == 0) return 0;
  const int config = data[0] % kConfigs;
  const bool signs = config < 2;
  if (config % 2 == 0)
    run(robot, "robot_node 1", make_robot, signs ? &robot_setup() : nullptr, data + 1, size - 1);
  else
    run(main, "main_robot", [] { return make_main(); }, signs ? &main_setup() : nullptr, data + 1, size - 1);
  return 0;
}

// ---- seeds (--write-seeds=DIR) ----------------------------------------------------------
//
// Real signed traffic, as the processes put it on the wire: robot 1's SENSOR_1 frames of
// config/paper.yaml's scenario, signed by the simulator's key; what robot_node 1 publishes
// on them (POSE_1, LMAP_EVENTS, LMAP_SNAPSHOT, ..., signed by robot 1: recorded under its
// authentication layer, in the run() above); what main_robot publishes on those
// (DYNAMIC_NOTICE, GLOBAL_MOVING, TEAM_MAP_1, ..., signed by main). Each seed is under
// 4 KB (tools/fuzz_campaign.sh's max_len): a few of these messages as liblcm sends
// them, or fragmented as a sender with a small fragment size would (liblcm on macOS
// fragments at 1,423 bytes), interleaved with another sender's; the same without the
// trailers for the configurations without authentication.

namespace {

constexpr int kSeedFrames = 40;
constexpr std::size_t kSeedBytes = 4000;

struct Seed {
  explicit Seed(int selector) : bytes{static_cast<std::uint8_t>(selector)} {}
  void from(std::size_t sender) { le16(kSenderToken + sender); }
  void datagram(const std::vector<std::uint8_t>& d) {
    le16(d.size());
    bytes.insert(bytes.end(), d.begin(), d.end());
  }
  /// `m` as liblcm sends it, or in fragments of `fragment` bytes; false (nothing added)
  /// when it would make the seed longer than kSeedBytes.
  bool message(const Published& m, std::uint32_t seq, std::size_t fragment = kFragmentMax) {
    const auto ds = lcm_datagrams(m.channel, m.bytes.data(), m.bytes.size(), seq,
                                  fragment == kFragmentMax ? kShortMax : fragment, fragment);
    std::size_t n = bytes.size();
    for (const auto& d : ds) n += 2 + d.size();
    if (n > kSeedBytes) return false;
    for (const auto& d : ds) datagram(d);
    return true;
  }
  void le16(std::size_t v) {
    bytes.push_back(static_cast<std::uint8_t>(v & 0xFF));
    bytes.push_back(static_cast<std::uint8_t>(v >> 8));
  }
  std::vector<std::uint8_t> bytes;
};

/// `m` without its authentication trailer: what a sender without the team's key sends.
Published plain(const Published& m) {
  Published p = m;
  if (p.bytes.size() >= transport::auth::kTrailerBytes) p.bytes.resize(p.bytes.size() - transport::auth::kTrailerBytes);
  return p;
}

template <class Msg>
Published sealed(transport::auth::Authenticator& a, const std::string& channel, const Msg& msg) {
  const int n = msg.getEncodedSize();
  Published p{channel, std::vector<std::uint8_t>(static_cast<std::size_t>(n) + transport::auth::kTrailerBytes)};
  if (n < 0 || msg.encode(p.bytes.data(), 0, n) != n) fail("a seed message does not encode", channel, 0);
  p.bytes.resize(a.seal(channel, p.bytes.data(), static_cast<std::size_t>(n)));
  return p;
}

std::vector<Published> sensor_frames() {
  const sim::ScenarioOptions o = sim::load_scenario(fuzz::paper_yaml());
  sim::World world(o);
  std::size_t robot = 0;
  while (robot < o.robots.size() && o.robots[robot].id != 1) ++robot;
  if (robot == o.robots.size()) fail("config/paper.yaml has no robot 1", "", 0);
  transport::auth::Authenticator simulator(test::team_setup(transport::kSenderSimulator, kSimIncarnation));
  std::vector<Published> out;
  for (int k = 0; k < kSeedFrames; ++k) {
    if (k > 0) world.step();
    const std::int64_t utime = fuzz::ShellRig<RobotNode, RobotPorts>::kEpoch + k * 100'000;
    sensor_frame_t m;
    sim::to_message(world.sensor_frame(static_cast<int>(robot)), utime, &m);
    out.push_back(sealed(simulator, channels::sensor(1), m));
  }
  return out;
}

/// The messages of `all` on `channel` (all when empty).
std::vector<Published> on(const std::vector<Published>& all, const std::string& channel) {
  std::vector<Published> out;
  for (const Published& m : all)
    if (m.channel == channel) out.push_back(m);
  return out;
}

/// An input of `messages`, each as liblcm sends it, from sender 0 (signed or plain),
/// until the seed is full.
Seed burst(int selector, const std::vector<Published>& messages, bool signs) {
  Seed s(selector);
  std::uint32_t seq = 0;
  for (const Published& m : messages)
    if (!s.message(signs ? m : plain(m), seq++)) break;
  return s;
}

/// Robot 1's POSE_1 from a second process with robot 1's key and another incarnation
/// (two robots with one id: RobotPorts::on_own).
Published duplicate_pose(const std::vector<Published>& robot) {
  const std::vector<Published> poses = on(robot, channels::pose(1));
  if (poses.empty()) fail("robot 1 published no POSE_1 on the seed frames", "", 0);
  pose_estimate_t p;
  const Published& first = poses.front();
  if (p.decode(first.bytes.data(), 0, static_cast<int>(first.bytes.size())) < 0) fail("POSE_1 does not decode", "", 0);
  p.incarnation = kRobotIncarnation + 1'000'000;
  transport::auth::Authenticator twin(test::team_setup(1, p.incarnation));
  return sealed(twin, channels::pose(1), p);
}

bool write_file(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return false;
  const bool ok = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
  return std::fclose(f) == 0 && ok;
}

/// The team's traffic on the wire, from the simulator's frames up.
struct Traffic {
  std::vector<Published> sensors;    // SENSOR_1, signed by the simulator
  std::vector<Published> robot;      // what robot_node 1 published on them
  std::vector<Published> to_main;    // of those, what main_robot reads
  std::vector<Published> from_main;  // the last of each channel main published that robot 1 reads
};

/// Every message of `messages` as liblcm sends it, in one input of any length (not a seed).
std::vector<std::uint8_t> input_of(int selector, const std::vector<Published>& messages) {
  Seed all(selector);
  std::uint32_t seq = 0;
  for (const Published& m : messages)
    for (const auto& d : lcm_datagrams(m.channel, m.bytes.data(), m.bytes.size(), seq++)) all.datagram(d);
  return all.bytes;
}

/// The simulator's frames, robot_node 1 on them, main_robot on robot 1's messages: each
/// process run as the target runs it (run()), what it published recorded under its
/// authentication layer.
Traffic record_traffic() {
  Traffic t;
  t.sensors = sensor_frames();
  {
    Process<RobotRig> p;
    const std::vector<std::uint8_t> in = input_of(0, t.sensors);
    run(p, "robot_node 1", make_robot, &robot_setup(), in.data() + 1, in.size() - 1, &t.robot);
  }
  for (const Published& m : t.robot)
    if (m.channel == channels::lmap_events() || m.channel == channels::lmap_event() ||
        m.channel == channels::lmap_snapshot() || m.channel == channels::pose(1))
      t.to_main.push_back(m);
  std::vector<Published> main;
  {
    GlobalMapOptions o = fuzz::main_options();
    o.team_map_period_frames = 5;  // TEAM_MAP_1 too
    Process<MainRig> p;
    const std::vector<std::uint8_t> in = input_of(1, t.to_main);
    run(p, "main_robot", [&] { return make_main(o); }, &main_setup(), in.data() + 1, in.size() - 1, &main);
  }
  for (const std::string& ch : {channels::dynamic_notice(), channels::global_moving(), channels::lmap_resync(),
                                channels::team_map(1)})
    if (const auto ms = on(main, ch); !ms.empty()) t.from_main.push_back(ms.back());
  if (t.from_main.empty() || t.to_main.empty()) fail("the seed run published nothing to fuzz with", "", 0);
  std::printf("fuzz_datagrams: from %zu frames: robot 1 published %zu messages, main %zu\n", t.sensors.size(),
              t.robot.size(), main.size());
  return t;
}

struct Named {
  std::string name;
  Seed seed;
};

/// The seeds of one robot configuration (selector 0 signed, 2 plain).
void robot_seeds(const Traffic& t, bool signs, std::vector<Named>* out) {
  const std::string tag = signs ? "signed" : "plain";
  const int selector = signs ? 0 : 2;
  const auto as_sent = [signs](const Published& m) { return signs ? m : plain(m); };
  out->push_back({"robot_" + tag + "_frames", burst(selector, t.sensors, signs)});
  // Frames, then main's messages from main's address, then frames again.
  Seed team(selector);
  std::uint32_t seq = 0;
  for (int k = 0; k < 2; ++k) team.message(as_sent(t.sensors[k]), seq++);
  team.from(1);
  for (const Published& m : t.from_main) team.message(as_sent(m), seq++);
  team.from(0);
  for (int k = 2; k < 4; ++k) team.message(as_sent(t.sensors[k]), seq++);
  out->push_back({"robot_" + tag + "_team", team});
  // A frame in fragments of 120 bytes, interleaved with main's largest message in
  // fragments from main's address.
  const Published a = as_sent(t.sensors[0]);
  const Published b = as_sent(*std::max_element(t.from_main.begin(), t.from_main.end(),
                                                 [](const Published& x, const Published& y) {
                                                   return x.bytes.size() < y.bytes.size();
                                                 }));
  const auto da = lcm_datagrams(a.channel, a.bytes.data(), a.bytes.size(), 7, 120, 120);
  const auto db = lcm_datagrams(b.channel, b.bytes.data(), b.bytes.size(), 9, 120, 120);
  Seed frag(selector);
  for (std::size_t i = 0; i < std::max(da.size(), db.size()); ++i) {
    frag.from(0);
    if (i < da.size()) frag.datagram(da[i]);
    frag.from(1);
    if (i < db.size()) frag.datagram(db[i]);
  }
  out->push_back({"robot_" + tag + "_fragments", frag});
}

/// The seeds of one main configuration (selector 1 signed, 3 plain).
void main_seeds(const Traffic& t, bool signs, std::vector<Named>* out) {
  const std::string tag = signs ? "signed" : "plain";
  const int selector = signs ? 1 : 3;
  out->push_back({"main_" + tag + "_frames", burst(selector, t.to_main, signs)});
  Seed frag(selector);  // robot 1's messages in fragments of 300 bytes
  std::uint32_t seq = 0;
  for (const Published& m : t.to_main)
    if (!frag.message(signs ? m : plain(m), seq++, 300)) break;
  out->push_back({"main_" + tag + "_fragments", frag});
}

int write_seeds(const std::string& dir) {
  const Traffic t = record_traffic();
  std::vector<Named> seeds;
  for (const bool signs : {true, false}) {
    robot_seeds(t, signs, &seeds);
    main_seeds(t, signs, &seeds);
  }
  Seed twin(0);  // a second robot 1 (another incarnation) on POSE_1, from another address
  twin.message(t.sensors[0], 0);
  twin.from(2);
  twin.message(duplicate_pose(t.robot), 0);
  twin.from(0);
  twin.message(t.sensors[1], 1);
  seeds.push_back({"robot_signed_duplicate_id", twin});
  for (const Named& s : seeds) {
    const std::string path = dir + "/" + s.name;
    if (!write_file(path, s.seed.bytes)) {
      std::fprintf(stderr, "fuzz_datagrams: cannot write %s\n", path.c_str());
      return 1;
    }
    std::printf("fuzz_datagrams: %s: %zu bytes\n", path.c_str(), s.seed.bytes.size());
  }
  return 0;
}

}  // namespace

// SPDX-License-Identifier: Apache-2.0
#include "elaslam/transport/udpm_receiver.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

#include "elaslam/common/contract.hpp"
#include "elaslam/common/log.hpp"

namespace elaslam::transport {
namespace {

constexpr std::uint32_t kShortMagic = 0x4c433032;  // "LC02"
constexpr std::uint32_t kLongMagic = 0x4c433033;   // "LC03"
constexpr std::size_t kShortHeader = 8;            // magic, seq
constexpr std::size_t kLongHeader = 20;            // magic, seq, size, offset, number, count

std::uint32_t be32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}
std::uint16_t be16(const std::uint8_t* p) { return static_cast<std::uint16_t>((p[0] << 8) | p[1]); }

/// The channel name at `p` (at most `n` bytes available): its length when it is 1..63
/// printable characters ended by a NUL within those bytes, else 0 with why.
std::size_t channel_length(const std::uint8_t* p, std::size_t n, const char** why) {
  const std::size_t limit = n < contract::kMaxChannelBytes + 1 ? n : contract::kMaxChannelBytes + 1;
  for (std::size_t i = 0; i < limit; ++i) {
    if (p[i] == 0) {
      if (i == 0) *why = "an empty channel name";
      return i;
    }
    if (p[i] <= ' ' || p[i] > '~') {
      *why = "a channel name with bytes that are not printable ASCII";
      return 0;
    }
  }
  *why = n <= contract::kMaxChannelBytes ? "a channel name that runs past the datagram's end (no NUL)"
                                         : "a channel name longer than LCM's 63 characters";
  return 0;
}

}  // namespace

bool parse_udpm_url(const std::string& url, UdpmAddress* a, std::string* why) {
  const std::string u = url.empty() ? "udpm://239.255.76.67:7667?ttl=0" : url;
  const std::string scheme = "udpm://";
  if (u.compare(0, scheme.size(), scheme) != 0) {
    *why = "not a udpm:// URL: '" + u + "'";
    return false;
  }
  const std::size_t q = u.find('?');
  std::string network = u.substr(scheme.size(), q == std::string::npos ? std::string::npos : q - scheme.size());
  if (network.empty()) network = "239.255.76.67:7667";
  const std::size_t colon = network.find(':');
  const std::string host = network.substr(0, colon);
  *a = UdpmAddress{};
  if (inet_aton(host.c_str(), &a->group) == 0 || !IN_MULTICAST(ntohl(a->group.s_addr))) {
    *why = "not a multicast IPv4 address in the LCM URL '" + u + "': '" + host + "'";
    return false;
  }
  if (colon != std::string::npos) {
    const std::string digits = network.substr(colon + 1);
    char* end = nullptr;
    const long port = std::strtol(digits.c_str(), &end, 10);
    if (digits.empty() || *end != '\0' || port < 1 || port > 65535) {
      *why = "not a port in the LCM URL '" + u + "': '" + digits + "'";
      return false;
    }
    a->port = static_cast<std::uint16_t>(port);
  }
  for (std::size_t i = q; i != std::string::npos && i < u.size();) {
    const std::size_t next = u.find('&', i + 1);
    const std::string kv = u.substr(i + 1, next == std::string::npos ? std::string::npos : next - i - 1);
    i = next;
    const std::size_t eq = kv.find('=');
    if (kv.compare(0, eq, "recv_buf_size") != 0 || eq == std::string::npos) continue;
    char* end = nullptr;
    const long v = std::strtol(kv.c_str() + eq + 1, &end, 0);
    if (*end != '\0' || v < 0 || v > (1L << 30)) {
      *why = "not a receive buffer size in the LCM URL '" + u + "': '" + kv.substr(eq + 1) + "'";
      return false;
    }
    a->recv_buf_size = static_cast<int>(v);
  }
  return true;
}

// ---- DatagramAssembler ----------------------------------------------------------------

DatagramAssembler::DatagramAssembler() {
  channel_.reserve(contract::kMaxChannelBytes + 1);
  for (Assembly& a : assemblies_) a.channel.reserve(contract::kMaxChannelBytes + 1);
}

DatagramAssembler::Result DatagramAssembler::feed(const std::uint8_t* d, std::size_t n, std::uint64_t source,
                                                  const std::string** channel, const std::uint8_t** data,
                                                  std::size_t* size, const char** why) {
  if (n < kShortHeader) {
    *why = "shorter than LCM's header";
    return Result::kRefused;
  }
  if (n > kMaxDatagramBytes) {
    *why = "longer than a UDP datagram";
    return Result::kRefused;
  }
  switch (be32(d)) {
    case kShortMagic: return short_message(d, n, channel, data, size, why);
    case kLongMagic: return fragment(d, n, source, channel, data, size, why);
    default: *why = "not LCM's magic (LC02, LC03)"; return Result::kRefused;
  }
}

DatagramAssembler::Result DatagramAssembler::short_message(const std::uint8_t* d, std::size_t n,
                                                           const std::string** channel, const std::uint8_t** data,
                                                           std::size_t* size, const char** why) {
  const std::size_t len = channel_length(d + kShortHeader, n - kShortHeader, why);
  if (len == 0) return Result::kRefused;
  channel_.assign(reinterpret_cast<const char*>(d + kShortHeader), len);
  const std::size_t offset = kShortHeader + len + 1;  // <= n: the NUL is inside the datagram
  *channel = &channel_;
  *data = d + offset;
  *size = n - offset;
  return Result::kMessage;
}

DatagramAssembler::Result DatagramAssembler::fragment(const std::uint8_t* d, std::size_t n, std::uint64_t source,
                                                      const std::string** channel, const std::uint8_t** data,
                                                      std::size_t* size, const char** why) {
  if (n < kLongHeader) {
    *why = "a fragment shorter than its 20-byte header";
    return Result::kRefused;
  }
  const std::uint32_t seq = be32(d + 4), total = be32(d + 8), offset = be32(d + 12);
  const std::uint16_t number = be16(d + 16), count = be16(d + 18);
  if (total == 0 || total > contract::kMaxMessageBytes) {
    *why = "a fragment of a message size 0 or larger than any message";
    return Result::kRefused;
  }
  if (count == 0 || number >= count) {
    *why = "a fragment number not below its message's fragment count";
    return Result::kRefused;
  }
  const std::uint8_t* body = d + kLongHeader;
  std::size_t body_size = n - kLongHeader;
  Assembly* a = find(source);
  if (number == 0) {
    const std::size_t len = channel_length(body, body_size, why);
    if (len == 0) return Result::kRefused;
    if (std::uint64_t{offset} + (body_size - len - 1) > total) {
      *why = "a fragment whose data does not fit its message where it says";
      return Result::kRefused;
    }
    Assembly& s = a != nullptr ? *a : take_slot(source);  // a new message replaces the sender's unfinished one
    s.used = true;
    s.source = source;
    s.seq = seq;
    s.size = total;
    s.fragments = count;
    s.next = 0;
    s.filled = 0;
    s.channel.assign(reinterpret_cast<const char*>(body), len);
    s.data.resize(total);  // capacity kept between messages: no allocation once the largest came
    a = &s;
    body += len + 1;
    body_size -= len + 1;
  } else if (std::uint64_t{offset} + body_size > total) {
    *why = "a fragment whose data does not fit its message where it says";
    return Result::kRefused;
  }
  // Only the next fragment of the message in progress, at the offset where the last ended.
  if (a == nullptr || !a->used || a->seq != seq || a->size != total || a->fragments != count || a->next != number ||
      a->filled != offset) {
    if (a != nullptr && a->used && a->seq == seq) a->used = false;  // out of order: the message is lost
    return Result::kDropped;
  }
  if (body_size > 0) std::memcpy(a->data.data() + offset, body, body_size);
  a->filled += static_cast<std::uint32_t>(body_size);
  a->last_used = ++tick_;
  if (++a->next < a->fragments) return Result::kPending;
  a->used = false;
  if (a->filled != a->size) {
    *why = "a fragmented message whose fragments do not add up to its size";
    return Result::kRefused;
  }
  *channel = &a->channel;
  *data = a->data.data();
  *size = a->size;
  return Result::kMessage;
}

DatagramAssembler::Assembly* DatagramAssembler::find(std::uint64_t source) {
  for (Assembly& a : assemblies_)
    if (a.used && a.source == source) return &a;
  return nullptr;
}

DatagramAssembler::Assembly& DatagramAssembler::take_slot(std::uint64_t /*source*/) {
  Assembly* pick = &assemblies_[0];
  for (Assembly& a : assemblies_) {
    if (!a.used) return a;
    if (a.last_used < pick->last_used) pick = &a;
  }
  return *pick;  // every slot busy: the one idle longest gives way
}

// ---- UdpmReceiver ---------------------------------------------------------------------

std::unique_ptr<UdpmReceiver> UdpmReceiver::open(const UdpmAddress& address, std::string* why) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    *why = std::string("cannot open a UDP socket: ") + std::strerror(errno);
    return nullptr;
  }
  std::unique_ptr<UdpmReceiver> r(new UdpmReceiver(fd));
  const int one = 1;
  // Every LCM process on the host binds the group's port (liblcm does the same).
  if (::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) < 0) {
    *why = std::string("setsockopt SO_REUSEADDR: ") + std::strerror(errno);
    return nullptr;
  }
  if (address.recv_buf_size > 0)
    ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &address.recv_buf_size, sizeof address.recv_buf_size);
  socklen_t len = sizeof r->granted_;
  ::getsockopt(fd, SOL_SOCKET, SO_RCVBUF, &r->granted_, &len);
  ::setsockopt(fd, SOL_SOCKET, SO_TIMESTAMP, &one, sizeof one);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_ANY);
  addr.sin_port = htons(address.port);
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) < 0) {
    *why = "cannot bind UDP port " + std::to_string(address.port) + ": " + std::strerror(errno);
    return nullptr;
  }
  ip_mreq mreq{};
  mreq.imr_multiaddr = address.group;
  mreq.imr_interface.s_addr = htonl(INADDR_ANY);
  if (::setsockopt(fd, IPPROTO_IP, IP_ADD_MEMBERSHIP, &mreq, sizeof mreq) < 0) {
    *why = std::string("cannot join the multicast group: ") + std::strerror(errno) +
           " (multicast on loopback needs a route: ip route add 224.0.0.0/4 dev lo)";
    return nullptr;
  }
  return r;
}

UdpmReceiver::~UdpmReceiver() {
  if (fd_ >= 0) ::close(fd_);
}

bool UdpmReceiver::read(DatagramDispatcher* to, bool* message) {
  sockaddr_in from{};
  iovec vec{buffer_.data(), buffer_.size()};
  alignas(cmsghdr) char control[64];
  msghdr msg{};
  msg.msg_name = &from;
  msg.msg_namelen = sizeof from;
  msg.msg_iov = &vec;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof control;
  const ssize_t n = ::recvmsg(fd_, &msg, MSG_DONTWAIT);
  if (n < 0) return false;  // EAGAIN: none waiting (errors count as none: the next poll tells)
  *message = false;
  std::int64_t recv_utime = 0;
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
    if (c->cmsg_level != SOL_SOCKET || c->cmsg_type != SCM_TIMESTAMP) continue;
    timeval t{};
    std::memcpy(&t, CMSG_DATA(c), sizeof t);
    recv_utime = std::int64_t{t.tv_sec} * 1000000 + t.tv_usec;
  }
  if (recv_utime == 0) {
    timeval t{};
    ::gettimeofday(&t, nullptr);
    recv_utime = std::int64_t{t.tv_sec} * 1000000 + t.tv_usec;
  }
  if ((msg.msg_flags & MSG_TRUNC) != 0) {
    to->refuse_truncated();
    return true;
  }
  const std::uint64_t source = (std::uint64_t{ntohl(from.sin_addr.s_addr)} << 16) | ntohs(from.sin_port);
  *message = to->feed(buffer_.data(), static_cast<std::size_t>(n), source, recv_utime);
  return true;
}

// ---- DatagramDispatcher -----------------------------------------------------------------

DatagramDispatcher::DatagramDispatcher(std::string who, std::FILE* log) : who_(std::move(who)), log_(log) {
  targets_.reserve(16);
}

DatagramDispatcher::~DatagramDispatcher() {
  for (Sub& s : subs_) regfree(&s.rx);
}

int DatagramDispatcher::subscribe(const std::string& pattern, RawHandler handler, void* context) {
  Sub& s = subs_.emplace_back();
  s.id = next_id_;
  s.handler = handler;
  s.context = context;
  if (regcomp(&s.rx, ("^(" + pattern + ")$").c_str(), REG_EXTENDED | REG_NOSUB) != 0) {
    subs_.pop_back();
    return 0;
  }
  return next_id_++;
}

void DatagramDispatcher::unsubscribe(int id) {
  for (auto it = subs_.begin(); it != subs_.end(); ++it) {
    if (it->id != id) continue;
    regfree(&it->rx);
    subs_.erase(it);
    return;
  }
}

bool DatagramDispatcher::feed(const std::uint8_t* datagram, std::size_t size, std::uint64_t source,
                              std::int64_t recv_utime) {
  const std::string* channel = nullptr;
  const std::uint8_t* data = nullptr;
  std::size_t message_size = 0;
  const char* why = nullptr;
  switch (assembler_.feed(datagram, size, source, &channel, &data, &message_size, &why)) {
    case DatagramAssembler::Result::kMessage:
      if (const char* bad = malformed_message(*channel, data, message_size)) {
        refuse(bad, channel, message_size);
        return false;
      }
      deliver(*channel, data, message_size, recv_utime);
      return true;
    case DatagramAssembler::Result::kRefused: refuse(why, nullptr, size); return false;
    case DatagramAssembler::Result::kDropped: ++dropped_fragments_; return false;
    case DatagramAssembler::Result::kPending: return false;
  }
  return false;
}

void DatagramDispatcher::refuse_truncated() { refuse("longer than a UDP datagram", nullptr, 0); }

void DatagramDispatcher::refuse(const char* why, const std::string* channel, std::size_t size) {
  ++malformed_;
  if (log_ == nullptr || (malformed_ > 20 && malformed_ % 1000 != 0)) return;
  char name[4 * contract::kMaxChannelBytes + 8];
  if (channel != nullptr)
    log::print(log_, log::Priority::kWarning,
               "%s: refused a datagram on '%s' (size %zu): %s (%lld so far)\n", who_.c_str(),
               printable_channel(*channel, name), size, why, static_cast<long long>(malformed_));
  else
    log::print(log_, log::Priority::kWarning,
               "%s: refused a datagram of %zu bytes: %s (%lld so far)\n", who_.c_str(), size, why,
               static_cast<long long>(malformed_));
}

void DatagramDispatcher::deliver(const std::string& channel, const std::uint8_t* data, std::size_t size,
                                 std::int64_t recv_utime) {
  // The matching subscriptions first: a handler may subscribe or unsubscribe.
  targets_.clear();
  for (Sub& s : subs_)
    if (regexec(&s.rx, channel.c_str(), 0, nullptr, 0) == 0) targets_.push_back(s.id);
  for (std::size_t i = 0; i < targets_.size(); ++i) {
    for (Sub& s : subs_) {
      if (s.id != targets_[i]) continue;
      s.handler(RawMessage{channel, data, size, recv_utime}, s.context);
      break;
    }
  }
}

}  // namespace elaslam::transport

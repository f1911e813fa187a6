// SPDX-License-Identifier: Apache-2.0
// The receiving side of LCM's udpm:// transport, with every byte checked before it
// is used (docs/security.md "Bytes from the network").
//
// Why not liblcm's own: LCM 1.3.1 (Debian bookworm; upstream master the same)
// parses datagrams in its receive thread without checking their sizes. A fragment
// ("LC03") shorter than its 20-byte header makes its payload size underflow, an
// offset near 2^32 wraps the bound check `offset + size > message size`, and fragment
// 0's channel name is read with strlen past the datagram's end: each makes the
// thread memcpy out of bounds, so one datagram from anyone on the network kills any
// process that subscribes (measured: robot_node, main_robot, the simulator, the
// viewer, the monitor and lcm-logger all ended with SIGSEGV). A short message
// ("LC02") whose channel name lacks its NUL is reported with a payload size of -1.
// liblcm still publishes: an LCM instance that never subscribes never starts its
// receive thread, so it never reads a datagram.
//
// The wire format is LCM's (lcm/lcm_udpm.c, LCM 1.3.1), big-endian:
//   short message:  "LC02" | seq u32 | channel NUL | payload
//   fragment:       "LC03" | seq u32 | message size u32 | offset u32 |
//                   fragment number u16 | fragments u16 | [fragment 0: channel NUL] | data
// A datagram is refused (counted, never read further) when it is shorter than its
// header, its channel name is not 1..63 printable characters ended by a NUL inside
// the datagram, a message size is 0 or beyond contract::kMaxMessageBytes, a
// fragment's number is not below the fragment count, or its data does not fit the
// message where it says (sizes added in 64 bits). Fragments must come in order
// (LCM sends them so; on loopback and a LAN no reordering was seen, LCM.md): one
// that does not continue its message drops the message. At most kAssemblies
// messages are assembled at once (one per sender address and port), the oldest
// replaced first, so memory stays within kAssemblies x kMaxMessageBytes.
#pragma once

#include <netinet/in.h>
#include <regex.h>

#include <array>
#include <cstdio>
#include <list>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "elaslam/transport/transport.hpp"

namespace elaslam::transport {

/// Where a udpm:// URL receives: the multicast group, the port and the socket's
/// receive buffer (the URL's recv_buf_size; 0: the kernel's default).
struct UdpmAddress {
  in_addr group{};
  std::uint16_t port = 7667;
  int recv_buf_size = 0;
};

/// Parse "udpm://GROUP[:PORT][?key=value&...]" (LCM's syntax; "" is LCM's default
/// udpm://239.255.76.67:7667?ttl=0). False with why when it is not a udpm:// URL LCM
/// would accept. Only recv_buf_size matters for receiving; ttl and the rest are the
/// sender's (liblcm's).
bool parse_udpm_url(const std::string& url, UdpmAddress* address, std::string* why);

/// Reassembles LCM datagrams into messages, refusing what is malformed. No socket:
/// UdpmReceiver feeds it what it reads, the tests and the fuzz target what they make.
class DatagramAssembler {
 public:
  static constexpr int kAssemblies = 4;
  static constexpr std::size_t kMaxDatagramBytes = 65535;

  enum class Result : std::uint8_t {
    kMessage,   // *channel, *data, *size: a whole message (valid until the next feed)
    kPending,   // a fragment of a message not yet complete
    kRefused,   // malformed: *why says what (a literal)
    kDropped,   // well formed but of no message in progress (its fragment 0 lost, out of order)
  };

  DatagramAssembler();
  /// One datagram of `size` bytes from sender `source` (address and port).
  Result feed(const std::uint8_t* datagram, std::size_t size, std::uint64_t source, const std::string** channel,
              const std::uint8_t** data, std::size_t* message_size, const char** why);

 private:
  struct Assembly {
    bool used = false;
    std::uint64_t source = 0;
    std::uint32_t seq = 0;
    std::uint32_t size = 0;       // the message's
    std::uint16_t fragments = 0;  // in the message
    std::uint16_t next = 0;       // the fragment number expected next
    std::uint32_t filled = 0;     // bytes received so far, the offset expected next
    std::uint64_t last_used = 0;
    std::string channel;
    std::vector<std::uint8_t> data;
  };
  Result short_message(const std::uint8_t* d, std::size_t n, const std::string** channel, const std::uint8_t** data,
                       std::size_t* size, const char** why);
  Result fragment(const std::uint8_t* d, std::size_t n, std::uint64_t source, const std::string** channel,
                  const std::uint8_t** data, std::size_t* size, const char** why);
  Assembly* find(std::uint64_t source);
  Assembly& take_slot(std::uint64_t source);

  std::string channel_;  // the last short message's, capacity kept
  std::array<Assembly, kAssemblies> assemblies_;
  std::uint64_t tick_ = 0;
};

/// The receiving side's subscriptions and what is fed to them: datagrams assembled
/// into messages (DatagramAssembler), checked (malformed_message), and handed to every
/// subscription whose pattern matches the channel as LCM matches it (anchored at both
/// ends, POSIX extended syntax), in the order they subscribed. What is refused is
/// counted and said on `log` at a bounded rate (the first 20, then every 1000th).
/// LcmTransport feeds it what its socket reads; the fuzz target what it makes.
class DatagramDispatcher {
 public:
  DatagramDispatcher(std::string who, std::FILE* log);
  ~DatagramDispatcher();
  DatagramDispatcher(const DatagramDispatcher&) = delete;
  DatagramDispatcher& operator=(const DatagramDispatcher&) = delete;

  /// An id > 0, or 0 when `pattern` is not a regular expression.
  int subscribe(const std::string& pattern, RawHandler handler, void* context);
  void unsubscribe(int id);
  /// One datagram of sender `source` (address and port): true when it completed a
  /// message, which went to every matching subscription (there may be none).
  bool feed(const std::uint8_t* datagram, std::size_t size, std::uint64_t source, std::int64_t recv_utime);
  /// A datagram longer than the receive buffer (cut by the kernel): counted as malformed.
  void refuse_truncated();

  std::int64_t malformed() const { return malformed_; }
  std::int64_t dropped_fragments() const { return dropped_fragments_; }

 private:
  struct Sub {
    int id;
    RawHandler handler;
    void* context;
    regex_t rx;
  };
  void refuse(const char* why, const std::string* channel, std::size_t size);
  void deliver(const std::string& channel, const std::uint8_t* data, std::size_t size, std::int64_t recv_utime);

  DatagramAssembler assembler_;
  std::list<Sub> subs_;
  std::vector<int> targets_;  // the subscriptions a message goes to, matched before any handler runs
  std::string who_;
  std::FILE* log_;
  int next_id_ = 1;
  std::int64_t malformed_ = 0;
  std::int64_t dropped_fragments_ = 0;
};

/// A udpm:// receive socket joined to the group (as liblcm's: SO_REUSEADDR so that
/// every process on the host receives the group, the URL's receive buffer, kernel
/// receive timestamps), read without blocking.
class UdpmReceiver {
 public:
  /// nullptr with why when the socket cannot be opened, bound or joined.
  static std::unique_ptr<UdpmReceiver> open(const UdpmAddress& address, std::string* why);
  ~UdpmReceiver();
  UdpmReceiver(const UdpmReceiver&) = delete;
  UdpmReceiver& operator=(const UdpmReceiver&) = delete;

  int fd() const { return fd_; }
  /// Read one datagram if one is waiting (never blocks) and feed it to `to`: false when
  /// none was waiting; else *message says whether it completed a message.
  bool read(DatagramDispatcher* to, bool* message);
  /// The receive buffer the kernel granted [bytes].
  int recv_buf_size() const { return granted_; }

 private:
  explicit UdpmReceiver(int fd) : fd_(fd), buffer_(DatagramAssembler::kMaxDatagramBytes + 1) {}
  int fd_;
  int granted_ = 0;
  std::vector<std::uint8_t> buffer_;
};

}  // namespace elaslam::transport

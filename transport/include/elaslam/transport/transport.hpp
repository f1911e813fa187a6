// SPDX-License-Identifier: Apache-2.0
// A transport moves encoded messages between named channels (docs/architecture.md,
// transport/). Two implementations: LCM (lcm_transport.hpp: udpm:// in the
// deployment, memq:// and file:// too) and in-process (inprocess_transport.hpp: one
// FIFO queue in one thread, deterministic: the in-process team run and the tests).
// What a message means, how it is decoded, validated and counted is the node shell's
// (node_shell.hpp); nothing above transport/ talks to LCM directly.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "elaslam/common/contract.hpp"

namespace elaslam::transport {

/// One received message as the transport hands it over; valid during the handler call only.
struct RawMessage {
  const std::string& channel;
  const std::uint8_t* data;
  std::size_t size;             // [bytes]
  std::int64_t recv_utime = 0;  // [us] when it was received (the kernel's stamp over udpm://); 0: not known
};

/// Is what a transport was handed a message at all? nullptr when it is, else why not.
/// Checked on every received datagram before anything reads its bytes: LCM 1.3.1
/// parses a datagram's channel name with strlen, so a name without its terminating
/// NUL runs into what the previous datagram left in the buffer, and the payload size
/// it then reports is negative (as an unsigned 32-bit number, 4294967232..4294967295);
/// the name it reports may hold those leftover bytes too.
inline const char* malformed_message(const std::string& channel, const void* data, std::size_t size) {
  if (data == nullptr) return "no payload";
  if (size > contract::kMaxMessageBytes) return "a payload size larger than any message (a datagram cut short)";
  if (channel.empty() || channel.size() > contract::kMaxChannelBytes) return "a channel name of impossible length";
  for (const char c : channel)
    if (c <= ' ' || c > '~') return "a channel name with bytes that are not printable ASCII";
  return nullptr;
}

/// `channel` for a log line, whatever bytes it holds: printable ASCII as it is, the
/// rest as \xNN, cut to LCM's longest name; into `out`, which it returns. Allocates nothing.
inline const char* printable_channel(const std::string& channel, char (&out)[4 * contract::kMaxChannelBytes + 8]) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::size_t n = 0;
  for (std::size_t i = 0; i < channel.size() && i < contract::kMaxChannelBytes; ++i) {
    const auto c = static_cast<unsigned char>(channel[i]);
    if (c > ' ' && c <= '~') {
      out[n++] = static_cast<char>(c);
    } else {
      out[n++] = '\\', out[n++] = 'x', out[n++] = kHex[c >> 4], out[n++] = kHex[c & 15];
    }
  }
  if (channel.size() > contract::kMaxChannelBytes) out[n++] = '.', out[n++] = '.', out[n++] = '.';
  out[n] = '\0';
  return out;
}

/// A subscription's handler: a plain function and a context pointer (LCM 1.3.1 cannot
/// subscribe a lambda: LCM.md). It runs on the thread that calls handle_timeout() and
/// must not throw (the node shell catches what its handlers throw).
using RawHandler = void (*)(const RawMessage& message, void* context);

/// Queue bounds for subscribe(): keep the transport's own (LCM: 30 messages per
/// subscription, overflow dropped silently), or none at all.
constexpr int kTransportDefaultQueue = -1;
constexpr int kUnboundedQueue = 0;

/// What a transport refused before any subscriber saw it (Transport::refusals).
struct TransportRefusals {
  std::int64_t total = 0;            // for every reason
  std::int64_t unauthenticated = 0;  // of which: no authentication trailer (a sender without the team key)
  std::int64_t malformed = 0;        // of which: not a message at all (malformed_message)
  std::int64_t other_mission = 0;    // of which: signed for another mission (auth_transport.hpp)
  std::int64_t jumps = 0;            // of which: a sender's counter far ahead, held (auth_transport.hpp)
  std::int64_t healed = 0;           // not refused: held jumps that the sender's next message confirmed
};

class Transport {
 public:
  Transport() = default;
  Transport(const Transport&) = delete;
  Transport& operator=(const Transport&) = delete;
  virtual ~Transport() = default;

  /// False when the transport could not be opened; nothing else works then.
  virtual bool good() const = 0;
  /// Short name for messages: "LCM", "in-process".
  virtual const char* kind() const = 0;

  /// Send `size` bytes on `channel`; false when they could not be sent.
  virtual bool publish(const std::string& channel, const void* data, std::size_t size) = 0;

  /// Receive every channel that the regular expression `pattern` matches as a whole (as
  /// LCM reads channel names; a plain name matches itself). `queue_capacity` bounds
  /// this subscription's receive queue where the transport has one (LCM: messages
  /// beyond it are dropped; kUnboundedQueue: no bound). Returns an id > 0, or 0 when the
  /// transport refused.
  virtual int subscribe(const std::string& pattern, RawHandler handler, void* context, int queue_capacity) = 0;
  virtual void unsubscribe(int id) = 0;

  /// Dispatch one message to its subscribers, waiting at most `timeout_ms` for one:
  /// > 0 one was handled, 0 none came, < 0 failure (also a wait interrupted by a
  /// signal). Never call it from inside a handler.
  virtual int handle_timeout(int timeout_ms) = 0;

  /// Messages received but refused before any subscriber saw them (malformed_message;
  /// message authentication: auth_transport.hpp); none for a transport that refuses none.
  virtual TransportRefusals refusals() const { return {}; }

  /// True when a subscription costs the process the wake-ups of its channel group only
  /// (grouped_lcm_transport.hpp), so that a node should not subscribe to a busy channel
  /// it can do without; false when every process receives every channel anyway.
  virtual bool channel_groups() const { return false; }
};

}  // namespace elaslam::transport

// A transport moves encoded messages between named channels (DESIGN.md section 2,
// transport/). Two implementations: LCM (lcm_transport.hpp: udpm:// in the
// deployment, memq:// and file:// too) and in-process (inprocess_transport.hpp: one
// FIFO queue in one thread, deterministic: the in-process team run and the tests).
// What a message means, how it is decoded, validated and counted is the node shell's
// (node_shell.hpp); nothing above transport/ talks to LCM directly.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace elaslam::transport {

/// One received message as the transport hands it over; valid during the handler call only.
struct RawMessage {
  const std::string& channel;
  const std::uint8_t* data;
  std::size_t size;  // [bytes]
};

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

  /// Messages received but refused before any subscriber saw them (message
  /// authentication: auth_transport.hpp); none for a transport that refuses none.
  virtual TransportRefusals refusals() const { return {}; }

  /// True when a subscription costs the process the wake-ups of its channel group only
  /// (grouped_lcm_transport.hpp), so that a node should not subscribe to a busy channel
  /// it can do without; false when every process receives every channel anyway.
  virtual bool channel_groups() const { return false; }
};

}  // namespace elaslam::transport

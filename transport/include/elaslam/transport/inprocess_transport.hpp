// SPDX-License-Identifier: Apache-2.0
// The in-process transport: every node of a team in one process and one thread,
// wired through one FIFO queue (docs/design.md section 1, way 2). It behaves as LCM's
// memq:// does (LCM.md): messages are dispatched in the order they were published, a
// message goes to its subscribers in the order they subscribed, a publish from inside
// a handler is queued behind what is already queued (no recursion), and a message
// that no subscription matches when it is published is dropped. The order of
// dispatch is therefore a function of the order of publication only: runs are
// deterministic. Unlike memq://, several of these can live in one process (the
// sweep runs teams on several threads, one transport each) and queue buffers are
// reused, so a steady flow of messages allocates nothing.
#pragma once

#include <regex.h>  // POSIX extended regular expressions (std::regex trips GCC 12's -Wmaybe-uninitialized under ASan)

#include <cstdint>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "elaslam/transport/transport.hpp"

namespace elaslam::transport {

class InProcessTransport final : public Transport {
 public:
  InProcessTransport();
  ~InProcessTransport() override;

  bool good() const override { return true; }
  const char* kind() const override { return "in-process"; }
  /// Copies the bytes into the queue.
  bool publish(const std::string& channel, const void* data, std::size_t size) override;
  /// `queue_capacity` is ignored: the queue is shared and unbounded, as memq://'s.
  int subscribe(const std::string& pattern, RawHandler handler, void* context, int queue_capacity) override;
  void unsubscribe(int id) override;
  /// Dispatches the oldest queued message without waiting (in one thread nothing else
  /// can publish meanwhile): 1 when one was dispatched, 0 when the queue is empty, -1
  /// from inside a handler.
  int handle_timeout(int timeout_ms) override;

  /// Dispatch until the queue is empty, including what the handlers publish meanwhile.
  /// Returns the number of messages dispatched.
  std::int64_t dispatch_all();

  std::size_t queued() const { return count_; }
  std::int64_t published() const { return published_; }  // messages queued so far
  std::int64_t dropped() const { return dropped_; }      // published with no subscriber

 private:
  struct Slot {
    std::string channel;
    std::vector<std::uint8_t> data;
  };
  struct RegexFree {
    void operator()(regex_t* r) const {
      regfree(r);
      delete r;
    }
  };
  struct Sub {
    std::string pattern;
    bool exact;                                  // no regular expression characters: compared as a string
    std::unique_ptr<regex_t, RegexFree> rx;      // otherwise "^(pattern)$", as LCM matches a whole name
    RawHandler handler;                          // nullptr once unsubscribed
    void* context;
  };

  /// Indices of the subscriptions that match `channel` (cached per channel name).
  const std::vector<std::size_t>& route(const std::string& channel);
  Slot& push_slot();

  // The queue: count_ slots from head_, wrapping. A message is dispatched from its slot
  // (a slot's buffer is only ever reused, so it settles at the largest message it
  // carries); the slot stays taken until its handlers return.
  std::vector<Slot> ring_;
  std::size_t head_ = 0, count_ = 0;
  std::string channel_;                // the name of the message being dispatched (its slot may move)
  std::vector<std::size_t> targets_;   // its subscribers, copied: handlers may (un)subscribe
  std::vector<Sub> subs_;              // index + 1 is the subscription id
  std::unordered_map<std::string, std::vector<std::size_t>> routes_;
  std::uint64_t subs_version_ = 0, routes_version_ = 0;
  bool dispatching_ = false;
  std::int64_t published_ = 0, dropped_ = 0;
};

}  // namespace elaslam::transport

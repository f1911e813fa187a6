// SPDX-License-Identifier: Apache-2.0
// The node shell: what stands between a node's logic (RobotNode, MainNode, the
// simulator's world) and a transport, the same in every process and in the
// in-process team run. Per input: decode into a message allocated once at
// subscription, validate (a hook), count and rate-limit refusals, then hand the
// message to the node; nothing a hook or handler throws gets out (STYLE.md: a bad
// message bumps a counter). Outgoing: encode into one reused buffer and publish.
// Periodic callbacks and the loop that ends on SIGINT / SIGTERM (spin()).
//
// Every message crosses one pipeline:
//   authenticate the bytes -> decode -> validate -> [sender's sequence] -> handler
// Authentication is the transport's (AuthenticatedTransport, auth_transport.hpp, wraps
// the LCM transport when a team key is configured): a message refused there never
// reaches Input<Msg>::dispatch below, and is counted in ShellCounters::auth_refused.
// The bracketed step is where sequence / incarnation tracking belongs (a later
// issue); today a node tracks what it needs itself (sequence.hpp).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "elaslam/common/log.hpp"
#include "elaslam/transport/message_arrays.hpp"
#include "elaslam/transport/sequence.hpp"
#include "elaslam/transport/service_notify.hpp"
#include "elaslam/transport/transport.hpp"

namespace elaslam::transport {

/// What happened to one input's messages.
struct InputCounters {
  std::int64_t received = 0;        // handed over by the transport
  std::int64_t decode_errors = 0;   // not a message of the input's type
  std::int64_t refused = 0;         // refused by the validate hook or by the handler (refuse())
  std::int64_t handler_errors = 0;  // the hook or the handler threw (caught)
};

struct ShellCounters {
  InputCounters inputs;             // summed over every input
  std::int64_t published = 0;
  std::int64_t publish_errors = 0;  // encoding or sending failed
  std::int64_t warnings = 0;        // warn() calls, printed or not
  std::int64_t auth_refused = 0;    // refused by the transport before any input saw them (authentication)
  std::int64_t auth_unauthenticated = 0;  // of which: without an authentication trailer
};

struct ShellOptions {
  explicit ShellOptions(std::string name_, std::string suffix = {}, std::FILE* log_ = stderr)
      : name(std::move(name_)), channel_suffix(std::move(suffix)), log(log_) {}

  std::string name;            // prefix of every log line: "robot_node 1", "main_robot"
  std::string channel_suffix;  // appended to every channel name (common/channels.hpp)
  std::FILE* log;              // nullptr: count, never print (the in-process team run)
  /// Stamps of outgoing messages [us]; empty: the wall clock (process.hpp, now_utime).
  std::function<std::int64_t()> clock;
  /// Ends spin(); nullptr: the process's SIGINT / SIGTERM flag (process.hpp, stop_flag).
  const std::atomic<bool>* stop = nullptr;
  /// The service manager (service_notify.hpp): spin() says READY=1 at its start and
  /// pings the watchdog from its turns. nullptr: none (tests, the in-process team run).
  ServiceNotifier* service = nullptr;
};

class NodeShell {
 public:
  template <class Msg>
  using Handler = std::function<void(const Msg& msg, const std::string& channel)>;
  /// "" accepts the message; anything else is why it is refused.
  template <class Msg>
  using Validator = std::function<std::string(const Msg& msg, const std::string& channel)>;
  using Clock = std::chrono::steady_clock;
  using SequenceGaps = transport::SequenceGaps;  // for the nodes' ports (they include no transport header)
  enum class Exit { kStopped, kTransportError };

  NodeShell(Transport& transport, ShellOptions options);
  ~NodeShell();  // unsubscribes every input
  NodeShell(const NodeShell&) = delete;
  NodeShell& operator=(const NodeShell&) = delete;

  /// Receive `pattern` (a channel name or a regular expression, transport.hpp) as Msg.
  /// Each message is decoded into the input's one Msg (allocated here, reused), given
  /// to `validate` when there is one, then to `handle`; the references are valid for
  /// the call. `queue_capacity`: the transport's receive queue for this input
  /// (transport.hpp). Returns the input's id (> 0), 0 when the transport refused.
  template <class Msg>
  int subscribe(const std::string& pattern, Handler<Msg> handle, int queue_capacity, Validator<Msg> validate = {}) {
    return add_input(std::make_unique<Input<Msg>>(this, std::move(handle), std::move(validate)), pattern,
                     queue_capacity);
  }
  void unsubscribe(int input);
  const InputCounters& input_counters(int input) const;

  /// Encode `msg` into the shell's buffer and publish it; false (and counted) on failure.
  template <class Msg>
  bool publish(const std::string& channel, const Msg& msg) {
    const int size = msg.getEncodedSize();
    if (size >= 0 && scratch_.size() < static_cast<std::size_t>(size)) scratch_.resize(static_cast<std::size_t>(size));
    if (size < 0 || msg.encode(scratch_.data(), 0, size) != size ||
        !transport_.publish(channel, scratch_.data(), static_cast<std::size_t>(size))) {
      ++publish_errors_;
      return false;
    }
    ++published_;
    return true;
  }

  /// From inside a handler: its message is refused (`why` says why). Counted on the
  /// input and logged like warn().
  void refuse(const std::string& why);
  /// A log line at a bounded rate: the first 20, then every 1000th (a flood of bad
  /// messages must not flood the log). Counted even without a log. Priority warning
  /// in the journal (common/log.hpp).
  void warn(const std::string& what);
  /// A log line, always (failures, shutdown); info in the journal unless told.
  void say(const std::string& what, log::Priority priority = log::Priority::kInfo) const;
  /// Also called on every decode error (e.g. a node's own counter, reported in its STATUS).
  void on_decode_error(std::function<void()> fn) { on_decode_error_ = std::move(fn); }

  /// Call `fn` every `period` while spin() runs, first at its first turn after
  /// `first_after`; at most once a turn (late calls do not pile up). A zero period:
  /// every turn. Callbacks run in the order they were added.
  void every(Clock::duration period, std::function<void()> fn, Clock::duration first_after = Clock::duration::zero());
  /// Handle messages (waiting at most `slice_ms` at a time) and run the due callbacks
  /// until the stop flag is set. With a service (ShellOptions::service): READY=1 first,
  /// then a watchdog ping whenever one is due, between messages and callbacks, so a
  /// handler or callback that hangs stops the pings. A transport failure ends it (logged), unless a stop
  /// was requested meanwhile (a signal interrupts the wait).
  Exit spin(int slice_ms);
  bool stop_requested() const { return stop_->load(); }
  /// A loop of its own (the simulator's frames, its waits) says it is alive: a
  /// watchdog ping when one is due (ServiceNotifier::alive). Nothing without a service.
  void alive() {
    if (options_.service != nullptr) options_.service->alive();
  }
  /// READY=1 to the service manager, once (nothing without a service).
  void ready(const std::string& status = {}) {
    if (options_.service != nullptr) options_.service->ready(status);
  }
  /// STOPPING=1: the orderly exit has begun (spin() says it itself).
  void stopping() {
    if (options_.service != nullptr) options_.service->stopping();
  }
  const std::atomic<bool>& stop() const { return *stop_; }

  std::int64_t now_utime() const;
  const std::string& name() const { return options_.name; }
  const std::string& suffix() const { return options_.channel_suffix; }
  Transport& transport() { return transport_; }
  ShellCounters counters() const;
  /// Fill a node's STATUS message (node_status_t) with the transport's refusals
  /// (authentication, malformed datagrams): they happen before any input, so the
  /// node's own counters never see them. FAULT_INPUT_REFUSED when some came since the
  /// last STATUS stamped here, with a line at the first STATUS of a series (one that
  /// follows kQuietStatuses STATUS without any).
  template <class Status>
  void stamp_auth(Status* status) {
    const ShellCounters c = counters();
    status->auth_refused = c.auth_refused;
    status->auth_unauthenticated = c.auth_unauthenticated;
    if (c.auth_refused > stamped_refused_) {
      status->fault_flags |= Status::FAULT_INPUT_REFUSED;
      if (quiet_statuses_ >= kQuietStatuses)
        say("FAULT: " + std::to_string(c.auth_refused - stamped_refused_) +
                " messages refused by the transport since the last status (" + std::to_string(c.auth_refused) +
                " in all): someone without the team's keys sends on its network, or a member is misconfigured",
            log::Priority::kWarning);
      quiet_statuses_ = 0;
    } else if (quiet_statuses_ < kQuietStatuses) {
      ++quiet_statuses_;
    }
    stamped_refused_ = c.auth_refused;
  }
  static constexpr int kQuietStatuses = 10;

 private:
  class InputBase {
   public:
    virtual ~InputBase() = default;
    virtual void dispatch(const RawMessage& m) = 0;
    NodeShell* shell = nullptr;
    int id = 0;         // the transport's subscription id
    InputCounters counters;
  };

  template <class Msg>
  class Input final : public InputBase {
   public:
    Input(NodeShell* s, Handler<Msg> handle, Validator<Msg> validate)
        : msg_(std::make_unique<Msg>()), handle_(std::move(handle)), validate_(std::move(validate)) {
      shell = s;
      reserve_arrays(msg_.get());
    }
    void dispatch(const RawMessage& m) override {
      ++counters.received;
      // m's bytes were authenticated by the transport (auth_transport.hpp) when a key is configured
      if (!decode(m)) return shell->decode_failed(this, Msg::getTypeName());
      if (validate_) {
        const std::string why = validate_(*msg_, m.channel);
        if (!why.empty()) return shell->refuse(why);
      }
      // [the sender's sequence / incarnation here]
      if (handle_) handle_(*msg_, m.channel);
    }

   private:
    // A negative count makes LCM's decoder throw (std::vector::resize): not a message.
    bool decode(const RawMessage& m) {
      if (m.size > contract::kMaxMessageBytes) return false;  // the transport refuses these first (transport.hpp)
      try {
        return msg_->decode(m.data, 0, static_cast<int>(m.size)) >= 0;
      } catch (const std::exception&) {
        return false;
      }
    }
    std::unique_ptr<Msg> msg_;  // on the heap: some messages are tens of KB
    Handler<Msg> handle_;
    Validator<Msg> validate_;
  };

  struct Timer {
    Clock::duration period;
    Clock::time_point next;
    std::function<void()> fn;
  };

  static void dispatch(const RawMessage& m, void* input);
  int add_input(std::unique_ptr<InputBase> input, const std::string& pattern, int queue_capacity);
  void decode_failed(InputBase* input, const char* type);

  Transport& transport_;
  ShellOptions options_;
  const std::atomic<bool>* stop_;
  std::vector<std::unique_ptr<InputBase>> inputs_;
  InputBase* current_ = nullptr;  // the input whose message is being handled
  std::vector<std::uint8_t> scratch_;
  std::vector<Timer> timers_;
  std::function<void()> on_decode_error_;
  std::int64_t published_ = 0, publish_errors_ = 0, warnings_ = 0;
  std::int64_t stamped_refused_ = 0;     // the transport's refusals at the last stamp_auth
  int quiet_statuses_ = kQuietStatuses;  // stamp_auth calls in a row without refusals (capped)
};

}  // namespace elaslam::transport

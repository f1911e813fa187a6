// SPDX-License-Identifier: Apache-2.0
#include "elaslam/transport/node_shell.hpp"

#include <exception>

#include "elaslam/transport/process.hpp"

namespace elaslam::transport {

NodeShell::NodeShell(Transport& transport, ShellOptions options)
    : transport_(transport), options_(std::move(options)), stop_(options_.stop ? options_.stop : &stop_flag()) {}

NodeShell::~NodeShell() {
  for (const auto& in : inputs_)
    if (in->id > 0) transport_.unsubscribe(in->id);
}

int NodeShell::add_input(std::unique_ptr<InputBase> input, const std::string& pattern, int queue_capacity) {
  input->id = transport_.subscribe(pattern, &NodeShell::dispatch, input.get(), queue_capacity);
  if (input->id <= 0) return 0;
  inputs_.push_back(std::move(input));
  return inputs_.back()->id;
}

void NodeShell::unsubscribe(int input) {
  for (const auto& in : inputs_) {
    if (in->id != input || input <= 0) continue;
    transport_.unsubscribe(in->id);
    in->id = -in->id;  // kept: its counters still count
  }
}

const InputCounters& NodeShell::input_counters(int input) const {
  static const InputCounters kNone;
  for (const auto& in : inputs_)
    if (input > 0 && (in->id == input || in->id == -input)) return in->counters;
  return kNone;
}

// The one entry of every received message. Nothing escapes a handler: an exception
// is counted on its input and logged.
void NodeShell::dispatch(const RawMessage& m, void* context) {
  auto* in = static_cast<InputBase*>(context);
  NodeShell& shell = *in->shell;
  shell.current_ = in;
  try {
    in->dispatch(m);
  } catch (const std::exception& e) {
    ++in->counters.handler_errors;
    shell.warn("handling a message on " + m.channel + " failed: " + e.what());
  } catch (...) {
    ++in->counters.handler_errors;
    shell.warn("handling a message on " + m.channel + " failed");
  }
  shell.current_ = nullptr;
}

void NodeShell::decode_failed(InputBase* input, const char* type) {
  ++input->counters.decode_errors;
  if (on_decode_error_) on_decode_error_();
  warn(std::string("cannot decode a ") + type);
}

void NodeShell::refuse(const std::string& why) {
  if (current_ != nullptr) ++current_->counters.refused;
  warn(why);
}

void NodeShell::warn(const std::string& what) {
  if ((++warnings_ <= 20 || warnings_ % 1000 == 0) && options_.log != nullptr)
    log::print(options_.log, log::Priority::kWarning, "%s: %s (warning %lld)\n", options_.name.c_str(), what.c_str(),
               static_cast<long long>(warnings_));
}

void NodeShell::say(const std::string& what, log::Priority priority) const {
  if (options_.log != nullptr) log::print(options_.log, priority, "%s: %s\n", options_.name.c_str(), what.c_str());
}

void NodeShell::every(Clock::duration period, std::function<void()> fn, Clock::duration first_after) {
  timers_.push_back({period, Clock::now() + first_after, std::move(fn)});
}

NodeShell::Exit NodeShell::spin(int slice_ms) {
  ready();
  while (!stop_requested()) {
    if (transport_.handle_timeout(slice_ms) < 0 && !stop_requested()) {  // < 0 also on EINTR from a signal
      say(std::string(transport_.kind()) + " handle error", log::Priority::kErr);
      return Exit::kTransportError;
    }
    const Clock::time_point now = Clock::now();
    if (options_.service != nullptr) options_.service->alive(now);  // the loop turns: the node is alive
    for (Timer& t : timers_) {
      if (now < t.next) continue;
      t.fn();
      t.next += t.period;
      if (t.next <= now) t.next = now + t.period;  // after a stall: once, not once per missed period
    }
  }
  stopping();
  return Exit::kStopped;
}

std::int64_t NodeShell::now_utime() const { return options_.clock ? options_.clock() : transport::now_utime(); }

ShellCounters NodeShell::counters() const {
  ShellCounters c;
  for (const auto& in : inputs_) {
    c.inputs.received += in->counters.received;
    c.inputs.decode_errors += in->counters.decode_errors;
    c.inputs.refused += in->counters.refused;
    c.inputs.handler_errors += in->counters.handler_errors;
  }
  c.published = published_;
  c.publish_errors = publish_errors_;
  c.warnings = warnings_;
  const TransportRefusals r = transport_.refusals();
  c.auth_refused = r.total;
  c.auth_unauthenticated = r.unauthenticated;
  return c;
}

}  // namespace elaslam::transport

// SPDX-License-Identifier: Apache-2.0
#include "elaslam/transport/inprocess_transport.hpp"

#include <cstring>
#include <utility>

namespace elaslam::transport {
namespace {

bool is_plain_name(const std::string& pattern) {
  return pattern.find_first_of(R"(.[]{}()\*+?^$|)") == std::string::npos;
}

}  // namespace

InProcessTransport::InProcessTransport() : ring_(64) {}
InProcessTransport::~InProcessTransport() = default;

const std::vector<std::size_t>& InProcessTransport::route(const std::string& channel) {
  if (routes_version_ != subs_version_) {  // a subscription came or went: match again
    routes_.clear();
    routes_version_ = subs_version_;
  }
  auto it = routes_.find(channel);
  if (it != routes_.end()) return it->second;
  std::vector<std::size_t> matched;
  for (std::size_t i = 0; i < subs_.size(); ++i) {
    const Sub& s = subs_[i];
    if (s.handler != nullptr && (s.exact ? s.pattern == channel : regexec(s.rx.get(), channel.c_str(), 0, nullptr, 0) == 0))
      matched.push_back(i);
  }
  return routes_.emplace(channel, std::move(matched)).first->second;
}

InProcessTransport::Slot& InProcessTransport::push_slot() {
  if (count_ == ring_.size()) {  // full: twice the slots, the queued ones first
    std::vector<Slot> bigger(2 * ring_.size());
    for (std::size_t i = 0; i < ring_.size(); ++i) bigger[i] = std::move(ring_[(head_ + i) % ring_.size()]);
    ring_.swap(bigger);
    head_ = 0;
  }
  Slot& s = ring_[(head_ + count_) % ring_.size()];
  ++count_;
  return s;
}

bool InProcessTransport::publish(const std::string& channel, const void* data, std::size_t size) {
  if (route(channel).empty()) {  // as memq://: nobody listens, nothing is kept
    ++dropped_;
    return true;
  }
  Slot& s = push_slot();
  s.channel.assign(channel);  // buffers keep their capacity: no allocation once warm
  s.data.resize(size);
  if (size > 0) std::memcpy(s.data.data(), data, size);
  ++published_;
  return true;
}

int InProcessTransport::subscribe(const std::string& pattern, RawHandler handler, void* context, int) {
  if (handler == nullptr) return 0;
  Sub s{pattern, is_plain_name(pattern), nullptr, handler, context};
  if (!s.exact) {
    auto rx = std::unique_ptr<regex_t, RegexFree>(new regex_t);
    if (regcomp(rx.get(), ("^(" + pattern + ")$").c_str(), REG_EXTENDED | REG_NOSUB) != 0) {
      delete rx.release();  // regcomp failed: nothing to regfree
      return 0;
    }
    s.rx = std::move(rx);
  }
  subs_.push_back(std::move(s));
  ++subs_version_;
  return static_cast<int>(subs_.size());
}

void InProcessTransport::unsubscribe(int id) {
  if (id < 1 || id > static_cast<int>(subs_.size())) return;
  subs_[static_cast<std::size_t>(id - 1)].handler = nullptr;
  ++subs_version_;
}

int InProcessTransport::handle_timeout(int) {
  if (dispatching_) return -1;  // LCM aborts here; refuse instead
  if (count_ == 0) return 0;
  // A handler's publish may grow the ring, which moves the slots: the data stay where
  // they are (a moved vector keeps its buffer), the name is copied out.
  channel_.assign(ring_[head_].channel);
  const RawMessage m{channel_, ring_[head_].data.data(), ring_[head_].data.size()};
  targets_ = route(channel_);
  dispatching_ = true;
  for (std::size_t i : targets_) {
    // By index, read before the call: a handler may subscribe (subs_ grows) or unsubscribe.
    const RawHandler handler = subs_[i].handler;
    if (handler != nullptr) handler(m, subs_[i].context);
  }
  dispatching_ = false;
  head_ = (head_ + 1) % ring_.size();
  --count_;
  return 1;
}

std::int64_t InProcessTransport::dispatch_all() {
  std::int64_t n = 0;
  while (handle_timeout(0) > 0) ++n;
  return n;
}

}  // namespace elaslam::transport

// SPDX-License-Identifier: Apache-2.0
#include "elaslam/viewer/stream_slots.hpp"

#include <algorithm>
#include <map>

namespace elaslam::viewer {

void ReadProgress::observe(std::uint64_t unacked, std::uint64_t acked, StreamClock::time_point now) {
  const bool taking = unacked == 0 || acked > acked_;
  acked_ = std::max(acked_, acked);
  if (taking) {
    stalled_ = false;
  } else if (!stalled_) {
    stalled_ = true;
    stalled_since_ = now;
  }
}

StreamSlots::Admit StreamSlots::open(Evictable* stream, const std::string& peer, StreamClock::time_point now) {
  std::lock_guard<std::mutex> l(m_);
  Admit how = Admit::kOpened;
  if (static_cast<int>(slots_.size()) >= max_streams_) {
    const int v = victim(peer, now, &how);
    if (v < 0) return Admit::kRefused;
    slots_[static_cast<std::size_t>(v)].stream->evict();
    slots_.erase(slots_.begin() + v);
    ++evictions_;
  }
  slots_.push_back({stream, peer, now, std::nullopt});
  return how;
}

int StreamSlots::victim(const std::string& peer, StreamClock::time_point now, Admit* why) const {
  int stalled = -1;
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    const auto& s = slots_[i].stalled_since;
    if (!s || now - *s < evict_after_) continue;
    if (stalled < 0 || *s < *slots_[static_cast<std::size_t>(stalled)].stalled_since) stalled = static_cast<int>(i);
  }
  if (stalled >= 0) {
    *why = Admit::kEvictedStalled;
    return stalled;
  }
  const int fair = fair_victim(peer);
  if (fair >= 0) *why = Admit::kEvictedFair;
  return fair;
}

int StreamSlots::fair_victim(const std::string& peer) const {
  struct Held {
    int count = 0;
    std::size_t oldest = 0;  // its oldest stream's slot
  };
  std::map<std::string, Held> held;  // at most max_streams_ addresses
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    Held& h = held[slots_[i].peer];
    if (h.count++ == 0 || slots_[i].opened < slots_[h.oldest].opened) h.oldest = i;
  }
  const auto mine = held.find(peer);
  const int own = mine == held.end() ? 0 : mine->second.count;
  // The address holding the most; of two holding as many, the one with the older stream.
  const Held* top = nullptr;
  for (const auto& entry : held) {
    const Held& h = entry.second;
    if (top == nullptr || h.count > top->count ||
        (h.count == top->count && slots_[h.oldest].opened < slots_[top->oldest].opened)) {
      top = &h;
    }
  }
  if (top == nullptr || top->count < own + 2) return -1;
  return static_cast<int>(top->oldest);
}

void StreamSlots::set_stalled(Evictable* stream, std::optional<StreamClock::time_point> since) {
  std::lock_guard<std::mutex> l(m_);
  for (Slot& s : slots_) {
    if (s.stream == stream) s.stalled_since = since;
  }
}

void StreamSlots::close(Evictable* stream) {
  std::lock_guard<std::mutex> l(m_);
  slots_.erase(std::remove_if(slots_.begin(), slots_.end(), [&](const Slot& s) { return s.stream == stream; }),
               slots_.end());
}

int StreamSlots::size() const {
  std::lock_guard<std::mutex> l(m_);
  return static_cast<int>(slots_.size());
}

long long StreamSlots::evictions() const {
  std::lock_guard<std::mutex> l(m_);
  return evictions_;
}

}  // namespace elaslam::viewer

// SPDX-License-Identifier: Apache-2.0
// The viewer's event streams (--max-clients slots): which reader has stopped taking
// what is sent, and which stream a new one may evict when every slot is held
// (docs/security.md, "The viewer as an HTTP service"). Pure logic, tested without sockets
// (tests/viewer/test_stream_slots.cpp); viewer/src/guarded_server.cpp feeds it what
// the kernel shows of each socket.
#pragma once

#include <chrono>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace elaslam::viewer {

using StreamClock = std::chrono::steady_clock;

/// Whether a stream's reader takes what is sent, from two numbers the kernel keeps for
/// its socket: the bytes it has not acknowledged yet (SIOCOUTQ) and the count it has
/// acknowledged (TCP_INFO tcpi_bytes_acked). A reader that keeps up leaves nothing
/// unacknowledged; a slow one acknowledges, slowly; a reader that does not read, or a
/// computer gone to sleep, acknowledges nothing once its receive window is full,
/// while data waits on the viewer's side. Sampled before each write.
class ReadProgress {
 public:
  explicit ReadProgress(StreamClock::time_point start) : stalled_since_(start), stalled_(false) {}

  void observe(std::uint64_t unacked, std::uint64_t acked, StreamClock::time_point now);

  bool stalled() const { return stalled_; }
  /// Since when it has taken nothing (only when stalled()).
  StreamClock::time_point stalled_since() const { return stalled_since_; }
  /// How long it has taken nothing; 0 while it takes what is sent.
  StreamClock::duration stalled_for(StreamClock::time_point now) const {
    return stalled_ ? now - stalled_since_ : StreamClock::duration::zero();
  }

 private:
  StreamClock::time_point stalled_since_;
  bool stalled_;
  std::uint64_t acked_ = 0;
};

/// An event stream as the slots see it: evict() ends it at once from another thread
/// (called under the slots' lock; it must not block or call back into the slots).
class Evictable {
 public:
  virtual void evict() = 0;

 protected:
  ~Evictable() = default;
};

/// The slots of the event streams. When every one is held, a new stream takes the
/// slot of
///   1. the stream stalled the longest, when it has been stalled for evict_after
///      (the reader gone: nobody loses a view);
///   2. else the oldest stream of the peer address that holds the most, when that
///      address holds at least two more than the newcomer's: one address cannot keep
///      every other one out, and the shares settle instead of taking turns;
/// else the new stream is refused (503; the page tries again 2 s later). Thread-safe.
class StreamSlots {
 public:
  enum class Admit { kOpened, kEvictedStalled, kEvictedFair, kRefused };

  StreamSlots(int max_streams, StreamClock::duration evict_after)
      : max_streams_(max_streams), evict_after_(evict_after) {}

  Admit open(Evictable* stream, const std::string& peer, StreamClock::time_point now);
  /// A stream's stall as its own thread saw it (nullopt: it takes what is sent).
  void set_stalled(Evictable* stream, std::optional<StreamClock::time_point> since);
  /// The stream ended; nothing when it was evicted. Must come before `stream` is
  /// destroyed and its socket closed.
  void close(Evictable* stream);

  int size() const;
  long long evictions() const;

 private:
  struct Slot {
    Evictable* stream;
    std::string peer;
    StreamClock::time_point opened;
    std::optional<StreamClock::time_point> stalled_since;
  };
  int victim(const std::string& peer, StreamClock::time_point now, Admit* why) const;  // index or -1
  int fair_victim(const std::string& peer) const;

  mutable std::mutex m_;
  int max_streams_;
  StreamClock::duration evict_after_;
  std::vector<Slot> slots_;  // at most max_streams_
  long long evictions_ = 0;
};

}  // namespace elaslam::viewer

// SPDX-License-Identifier: Apache-2.0
// The viewer's head reader (guarded_server.hpp): one thread that collects every
// connection's next request (head and body) with epoll, each within its deadline and
// checked by HeadScan as its bytes arrive, and hands a whole request to the workers.
// A client that sends slowly, or too much, costs a socket and at most
// max_head_bytes + max_body_bytes of memory here, never a thread. Refusals (the caps'
// 503, HeadScan's 4xx, 408) are answered here without blocking; the connection is then
// drained for refusal_linger so that the client reads the answer instead of a reset.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "connection.hpp"

namespace elaslam::viewer {

class HeadReader {
 public:
  using Dispatch = std::function<void(std::unique_ptr<Connection>)>;

  /// `dispatch` receives each whole request (on this reader's thread; it must not block).
  HeadReader(const HttpLimits& limits, GuardCounters& counters, Dispatch dispatch);
  ~HeadReader();
  HeadReader(const HeadReader&) = delete;
  HeadReader& operator=(const HeadReader&) = delete;

  /// From any thread: a new connection (refuse_status set: to be refused) or one
  /// between two requests (buf holds what arrived beyond the last one). After stop()
  /// the connection is closed.
  void add(std::unique_ptr<Connection> c);
  /// Closes every connection it holds and joins its thread.
  void stop();

 private:
  void run();
  void take_inbox(GuardClock::time_point now);
  void watch(std::unique_ptr<Connection> c, GuardClock::time_point now);
  void on_readable(int fd, GuardClock::time_point now);
  /// The bytes received so far: hand on, refuse or wait; true when `c` is gone (handed
  /// on or closed).
  bool check(Connection& c, GuardClock::time_point now);
  /// Answers `status` and drains the connection for refusal_linger; true when it was
  /// closed at once instead (too many draining).
  bool refuse(Connection& c, int status, const char* why, GuardClock::time_point now);
  void forget(int fd);  // closes
  void expire(GuardClock::time_point now);
  /// At most every 10 s (and once more at the end: `last`), one line on stderr of
  /// what the guard refused since the line before.
  void report(GuardClock::time_point now, bool last);

  HttpLimits limits_;
  GuardCounters& counters_;
  Dispatch dispatch_;
  int epoll_fd_ = -1, wake_fd_ = -1;

  std::mutex m_;
  std::vector<std::unique_ptr<Connection>> inbox_;  // under m_
  bool stopped_ = false;                            // under m_

  // The reader thread's own.
  std::map<int, std::unique_ptr<Connection>> conns_;  // by socket
  std::map<int, GuardClock::time_point> lingering_;   // refused: drained until this
  GuardClock::time_point next_expiry_{}, next_report_{};
  long long reported_[6] = {};

  std::thread thread_;
};

}  // namespace elaslam::viewer

// SPDX-License-Identifier: Apache-2.0
// One client connection of the viewer's guarded HTTP service (guarded_server.hpp):
// its socket, its peer, the bytes of the request being collected, and the counters
// of what the guard refused. Internal to the viewer executable.
#pragma once

#include <atomic>
#include <chrono>
#include <string>

#include "elaslam/viewer/http_guard.hpp"

namespace elaslam::viewer {

using GuardClock = std::chrono::steady_clock;

/// What the guard refused or ended, for the viewer's periodic line on stderr.
struct GuardCounters {
  std::atomic<long long> over_caps{0};       ///< connections refused at once (503): a cap was reached
  std::atomic<long long> bad_requests{0};    ///< requests refused by HeadScan (400, 411, 413, 414, 431)
  std::atomic<long long> timed_out{0};       ///< requests not whole within request_timeout (408)
  std::atomic<long long> slow_responses{0};  ///< responses not written within response_timeout
  std::atomic<long long> evicted{0};         ///< event streams evicted by a new one
  std::atomic<long long> stalled{0};         ///< event streams ended: their reader took nothing for stream_stall_close
};

/// A connection, owned by one thread at a time: the accept loop, the head reader or
/// a worker. Its destructor closes the socket and gives back its place in the caps.
struct Connection {
  /// Takes `fd` (an accepted TCP socket), makes it non-blocking and reads its addresses.
  Connection(int fd, const HttpLimits& limits);
  ~Connection();
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  int fd;
  std::string peer, local;  ///< numeric addresses; an IPv4-mapped IPv6 peer as plain IPv4
  int peer_port = 0, local_port = 0;
  ConnectionCaps* caps = nullptr;  ///< set once admitted: released by the destructor

  std::string buf;                 ///< received and not yet answered (at most head + body + one read)
  HeadScan scan;                   ///< of the request at buf's front
  std::size_t request_bytes = 0;   ///< once whole: the request's head and body at buf's front
  GuardClock::time_point deadline;
  bool between_requests = false;   ///< idle after a response: the keep-alive timeout applies
  std::size_t served = 0;          ///< requests answered on it
  int refuse_status = 0;           ///< set by the accept loop: answer this and close
  const char* refuse_why = "";
};

/// A complete HTTP/1.1 response that refuses a request and closes the connection.
std::string refusal_response(int status, const char* why);

}  // namespace elaslam::viewer

// SPDX-License-Identifier: Apache-2.0
// The viewer's HTTP limits (docs/security.md, "The viewer as an HTTP service"): what a request may be before
// httplib parses it, and how many connections clients may hold. Pure logic, tested
// without sockets (tests/viewer/test_http_guard.cpp); the socket side is
// viewer/src/guarded_server.cpp.
#pragma once

#include <chrono>
#include <cstddef>
#include <map>
#include <mutex>
#include <string>
#include <string_view>

namespace elaslam::viewer {

/// Every bound of the viewer's HTTP service in one place; docs/security.md, "The viewer as an HTTP service"
/// gives each one's reason. Sizes in bytes.
struct HttpLimits {
  std::size_t max_request_line = 4096;      ///< "GET /events?token=... HTTP/1.1\r\n": 414 beyond
  int max_header_lines = 100;               ///< header lines after the request line: 431 beyond
  std::size_t max_head_bytes = 16 * 1024;   ///< request line, headers and the blank line: 431 beyond
  std::size_t max_body_bytes = 4096;        ///< a Content-Length beyond: 413 (the viewer takes no bodies)
  std::chrono::milliseconds request_timeout{5000};     ///< a whole request from its first byte (the first from the accept): else 408
  std::chrono::milliseconds keep_alive_timeout{5000};  ///< an idle connection between two requests: closed
  int keep_alive_max_requests = 100;        ///< requests on one connection (the polling page makes 10 a second)
  std::chrono::milliseconds response_timeout{10000};   ///< writing one response that is not an event stream
  int max_connections = 256;                ///< open at once, all peers: the rest refused at once (503)
  int max_connections_per_address = 64;     ///< open at once from one peer address: the rest refused (503)
  std::chrono::milliseconds stream_stall_close{5000};  ///< an event stream whose reader takes nothing this long: closed
  std::chrono::milliseconds stream_evict_after{2000};  ///< ...and evictable this soon by a new stream when all slots are held
  std::chrono::milliseconds refusal_linger{1000};      ///< a refused connection is drained this long, so its answer is read
  int max_lingering = 64;                   ///< refused connections drained at once; beyond, closed at once
};

/// What the bytes received so far for one request allow.
struct HeadVerdict {
  enum class Kind { kMore, kComplete, kRefuse };
  Kind kind = Kind::kMore;
  int status = 0;                 ///< kRefuse: 400, 411, 413, 414 or 431
  std::size_t request_bytes = 0;  ///< kComplete: head and body, from the start of the data
  const char* why = "";           ///< kRefuse: the reason (the answer's body, the counters)
};

/// An incremental check of one HTTP/1.1 request against HttpLimits before any parser
/// allocates for it: the request line's length, the count of header lines, the size
/// of the head and of the body, CRLF line ends. scan() is given everything received
/// for the request so far (an earlier call was given a prefix of it) and looks only
/// at the bytes it has not seen. A body is taken only with a Content-Length; a
/// Transfer-Encoding is refused (411).
class HeadScan {
 public:
  explicit HeadScan(const HttpLimits& limits) : limits_(limits) {}

  HeadVerdict scan(std::string_view data);
  /// For the next request on the connection.
  void reset() { *this = HeadScan(limits_); }

 private:
  HeadVerdict refuse(int status, const char* why) const { return {HeadVerdict::Kind::kRefuse, status, 0, why}; }
  /// One whole line, its CRLF included; kMore when it is acceptable.
  HeadVerdict on_line(std::string_view line);
  HeadVerdict on_header(std::string_view line);

  HttpLimits limits_;
  std::size_t seen_ = 0;        // bytes of the data looked at
  std::size_t line_start_ = 0;  // where the current line begins
  int header_lines_ = 0;
  bool head_done_ = false;
  std::size_t head_bytes_ = 0;  // once head_done_
  bool has_length_ = false;
  std::size_t content_length_ = 0;
};

/// Connections open at once, in all and per peer address. Thread-safe.
class ConnectionCaps {
 public:
  ConnectionCaps(int max_total, int max_per_address) : max_total_(max_total), max_per_address_(max_per_address) {}

  /// Counts a new connection from `address`; false (not counted) when a cap is reached.
  bool admit(const std::string& address);
  /// The end of a connection admit() counted.
  void release(const std::string& address);
  int open() const;
  int open_from(const std::string& address) const;

 private:
  mutable std::mutex m_;
  int max_total_, max_per_address_;
  int total_ = 0;
  std::map<std::string, int> per_address_;  // only addresses with open connections: at most max_total_
};

/// Is `address` (numeric, as the viewer prints a peer) this machine's loopback:
/// 127.0.0.0/8, ::1 or an IPv4-mapped 127.0.0.0/8 (::ffff:127.0.0.1)?
bool is_loopback_address(std::string_view address);

/// A numeric IPv4 or IPv6 address (what --bind takes)?
bool is_ip_address(std::string_view address);

}  // namespace elaslam::viewer

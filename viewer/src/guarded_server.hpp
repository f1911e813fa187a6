// SPDX-License-Identifier: Apache-2.0
// httplib's server behind the viewer's limits (HttpLimits, docs/security.md, "The viewer as an HTTP service").
// httplib 0.11.4 gives each accepted connection a thread of its pool at once, reads
// the request head there with a timeout per read (not per request) and bounds a
// header line's length but not their count: slow or endless heads held every thread
// and grew its memory without end. Here httplib still parses and answers every
// request (process_request), but only once the whole request is in memory:
//   - the accept loop (httplib's own thread) counts the connection against the caps
//     (over them: 503 at once) and hands it to the head reader: the virtual
//     process_and_close_socket is overridden and the task queue runs it inline;
//   - the head reader (head_reader.hpp, one epoll thread) collects each request
//     within request_timeout, checked by HeadScan as its bytes arrive;
//   - max_streams + 4 workers run process_request on the collected bytes and write
//     the answer within response_timeout; a keep-alive connection goes back to the
//     reader for its next request;
//   - an event stream holds one of max_streams slots (StreamSlots): one whose reader
//     takes nothing for stream_stall_close ends, and a new stream may evict it.
#pragma once

#include <atomic>
#include <memory>

#include "connection.hpp"
#include "elaslam/viewer/http_guard.hpp"
#include "elaslam/viewer/stream_slots.hpp"

// Last: its system headers define macros that break Eigen's.
#include <httplib.h>

namespace elaslam::viewer {

class HeadReader;
class WorkerPool;

class GuardedServer : public httplib::Server {
 public:
  GuardedServer(const HttpLimits& limits, int max_streams);
  ~GuardedServer() override;
  GuardedServer(const GuardedServer&) = delete;
  GuardedServer& operator=(const GuardedServer&) = delete;

  /// Listens on `host`:`port` (0: any free port) with httplib's bind, then with a
  /// backlog of max_connections instead of httplib's 5 (with 5, a burst of connections
  /// waited seconds for the kernel to retry the handshake): the port, or -1.
  int bind_port(const std::string& host, int port);
  /// In a route's handler: makes the connection it serves an event stream in one of
  /// the slots (evicting another one as StreamSlots says when all are held). false:
  /// no slot; answer 503.
  bool begin_event_stream();
  /// Event streams open now (the state's viewer.clients).
  int event_streams() const { return slots_.size(); }
  /// Stops listening (httplib's stop()), ends every connection and joins the threads.
  /// The thread in listen_after_bind() returns; join it after.
  void shutdown();

 private:
  bool process_and_close_socket(socket_t sock) override;  // on httplib's accept thread
  void serve(std::unique_ptr<Connection> c);               // on a worker

  HttpLimits limits_;
  ConnectionCaps caps_;
  StreamSlots slots_;
  GuardCounters counters_;
  std::atomic<bool> stopping_{false};
  std::unique_ptr<HeadReader> reader_;
  std::unique_ptr<WorkerPool> workers_;
};

}  // namespace elaslam::viewer

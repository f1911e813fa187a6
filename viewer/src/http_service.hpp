// SPDX-License-Identifier: Apache-2.0
// What the viewer serves over HTTP: the newest state (Latest), the routes (/,
// /state.json, /events) behind the access check, and the listening socket (--bind,
// --port, --http-netns).
#pragma once

#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>

#include "elaslam/viewer/access_token.hpp"
#include "viewer_options.hpp"

// Last: httplib's system headers define macros that break Eigen's.
#include "guarded_server.hpp"

namespace elaslam::viewer {

/// The newest state, shared between the LCM thread (writer) and the HTTP threads.
class Latest {
 public:
  void put(std::string json);
  /// The state after `after` (waits at most `wait`); nullptr when none came or stopping.
  std::shared_ptr<const std::string> next(long long* after, std::chrono::milliseconds wait);
  std::shared_ptr<const std::string> now();
  void stop();

 private:
  std::mutex m_;
  std::condition_variable cv_;
  std::shared_ptr<const std::string> json_ = std::make_shared<const std::string>("{}");  // replaced before serving
  long long seq_ = 0;
  bool stopping_ = false;
};

/// Opens the HTTP socket on --bind and --port (0: any free one), in --http-netns when
/// given: the port it listens on, or -1 after saying why, *rc the exit code (2: no
/// such namespace; 1: not allowed, or the address is taken).
int bind_http(GuardedServer& http, const ViewerOptions& o, int* rc);

/// GET / (the page), /state.json and /events (Server-Sent Events, in one of the
/// server's stream slots). A request from a peer `access` does not allow is answered
/// 401 before any route.
void add_routes(GuardedServer& http, Latest& latest, const AccessPolicy& access);

/// The URL to open: "http://HOST:PORT/", HOST this machine's loopback when listening on
/// every address, and "?token=TOKEN" when there is a token.
std::string viewer_url(const std::string& bind, int port, const std::string& token);

}  // namespace elaslam::viewer

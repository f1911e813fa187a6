// SPDX-License-Identifier: Apache-2.0
#include "http_service.hpp"

#include <fcntl.h>
#include <sched.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace elaslam::viewer {

extern const char* const kIndexHtml;  // viewer/web/index.html, embedded at build time

namespace {

/// Enter the network namespace at `path`: 0, or the exit code after saying why
/// (2: no such namespace, bad input; 1: not allowed to enter it).
int enter_netns(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    std::fprintf(stderr, "viewer: cannot open the network namespace %s: %s\n", path.c_str(), std::strerror(errno));
    return 2;
  }
  const int rc = ::setns(fd, CLONE_NEWNET);
  const int err = errno;
  ::close(fd);
  if (rc == 0) return 0;
  std::fprintf(stderr, "viewer: cannot enter the network namespace %s: %s\n", path.c_str(), std::strerror(err));
  return err == EINVAL ? 2 : 1;  // EINVAL: the file is not a network namespace
}

/// An event stream's chunks: only the newest state (a slow browser skips states, it
/// never queues them), a comment when none came for a second.
bool next_event(Latest& latest, long long* seen, httplib::DataSink& sink) {
  const auto json = latest.next(seen, std::chrono::milliseconds(1000));
  if (!json) {
    if (!sink.is_writable()) return false;
    static const char kKeepAlive[] = ": keep-alive\n\n";
    return sink.write(kKeepAlive, sizeof kKeepAlive - 1);
  }
  std::string event = "event: state\ndata: ";
  event += *json;
  event += "\n\n";
  return sink.write(event.data(), event.size());
}

}  // namespace

void Latest::put(std::string json) {
  {
    std::lock_guard<std::mutex> l(m_);
    json_ = std::make_shared<const std::string>(std::move(json));
    ++seq_;
  }
  cv_.notify_all();
}

std::shared_ptr<const std::string> Latest::next(long long* after, std::chrono::milliseconds wait) {
  std::unique_lock<std::mutex> l(m_);
  cv_.wait_for(l, wait, [&] { return seq_ > *after || stopping_; });
  if (stopping_ || seq_ <= *after) return nullptr;
  *after = seq_;
  return json_;
}

std::shared_ptr<const std::string> Latest::now() {
  std::lock_guard<std::mutex> l(m_);
  return json_;
}

void Latest::stop() {
  {
    std::lock_guard<std::mutex> l(m_);
    stopping_ = true;
  }
  cv_.notify_all();
}

int bind_http(GuardedServer& http, const ViewerOptions& o, int* rc) {
  // The HTTP socket in --http-netns, then back to our own namespace for LCM.
  const std::string own_netns = "/proc/self/ns/net";
  const int own = o.http_netns.empty() ? -1 : ::open(own_netns.c_str(), O_RDONLY | O_CLOEXEC);
  if (own < 0 && !o.http_netns.empty()) {
    std::fprintf(stderr, "viewer: cannot open %s: %s\n", own_netns.c_str(), std::strerror(errno));
    *rc = 1;
    return -1;
  }
  if (!o.http_netns.empty()) {
    if (const int entered = enter_netns(o.http_netns); entered != 0) {
      ::close(own);
      *rc = entered;
      return -1;
    }
  }
  const int bound = http.bind_port(o.bind, o.port);
  if (own >= 0) {
    const int back = ::setns(own, CLONE_NEWNET);
    ::close(own);
    if (back != 0) {
      std::perror("viewer: cannot return to its own network namespace");
      *rc = 1;
      return -1;
    }
  }
  if (bound <= 0) {
    std::fprintf(stderr, "viewer: cannot listen on %s:%d (in use? another --port)\n", o.bind.c_str(), o.port);
    *rc = 1;
    return -1;
  }
  return bound;
}

void add_routes(GuardedServer& http, Latest& latest, const AccessPolicy& access) {
  http.set_pre_routing_handler([&access](const httplib::Request& req, httplib::Response& res) {
    if (access.allows(req.remote_addr, req.get_header_value("Authorization"), req.get_param_value("token"))) {
      return httplib::Server::HandlerResponse::Unhandled;
    }
    res.status = 401;
    res.set_header("WWW-Authenticate", "Bearer realm=\"elaslam viewer\"");
    res.set_content("the viewer needs its access token from this address: Authorization: Bearer TOKEN, or ?token=TOKEN\n",
                    "text/plain");
    return httplib::Server::HandlerResponse::Handled;
  });
  http.Get("/", [](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    res.set_content(kIndexHtml, "text/html; charset=utf-8");
  });
  http.Get("/state.json", [&latest](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    res.set_content(*latest.now(), "application/json");
  });
  http.Get("/events", [&http, &latest](const httplib::Request&, httplib::Response& res) {
    if (!http.begin_event_stream()) {
      res.status = 503;
      res.set_header("Retry-After", "2");
      res.set_content("too many event streams\n", "text/plain");
      return;
    }
    res.set_header("Cache-Control", "no-store");
    auto seen = std::make_shared<long long>(0);
    res.set_chunked_content_provider("text/event-stream", [&latest, seen](std::size_t, httplib::DataSink& sink) {
      return next_event(latest, seen.get(), sink);
    });
  });
}

std::string viewer_url(const std::string& bind, int port, const std::string& token) {
  // Listening on every address: this machine's loopback is one of them.
  const std::string host = bind == "0.0.0.0" ? "127.0.0.1"
                           : bind == "::"    ? "[::1]"
                           : bind.find(':') != std::string::npos ? "[" + bind + "]"
                                                                 : bind;
  std::string url = "http://" + host + ":" + std::to_string(port) + "/";
  if (!token.empty()) url += "?token=" + token;
  return url;
}

}  // namespace elaslam::viewer

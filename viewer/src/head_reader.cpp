// SPDX-License-Identifier: Apache-2.0
#include "head_reader.hpp"

#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace elaslam::viewer {
namespace {

constexpr auto kExpiryPeriod = std::chrono::milliseconds(50);
constexpr auto kReportPeriod = std::chrono::seconds(10);

}  // namespace

HeadReader::HeadReader(const HttpLimits& limits, GuardCounters& counters, Dispatch dispatch)
    : limits_(limits), counters_(counters), dispatch_(std::move(dispatch)) {
  epoll_fd_ = ::epoll_create1(EPOLL_CLOEXEC);
  wake_fd_ = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (epoll_fd_ < 0 || wake_fd_ < 0) {
    if (epoll_fd_ >= 0) ::close(epoll_fd_);
    if (wake_fd_ >= 0) ::close(wake_fd_);
    throw std::runtime_error(std::string("the HTTP head reader: no epoll or eventfd: ") + std::strerror(errno));
  }
  epoll_event ev{};
  ev.events = EPOLLIN;
  ev.data.fd = wake_fd_;
  ::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, wake_fd_, &ev);
  next_report_ = GuardClock::now() + kReportPeriod;
  thread_ = std::thread([this] { run(); });
}

HeadReader::~HeadReader() {
  stop();
  ::close(epoll_fd_);
  ::close(wake_fd_);
}

void HeadReader::add(std::unique_ptr<Connection> c) {
  {
    std::lock_guard<std::mutex> l(m_);
    if (stopped_) return;  // c closes here
    inbox_.push_back(std::move(c));
  }
  const std::uint64_t one = 1;
  [[maybe_unused]] const ssize_t w = ::write(wake_fd_, &one, sizeof one);  // EAGAIN: a wake-up is pending already
}

void HeadReader::stop() {
  {
    std::lock_guard<std::mutex> l(m_);
    if (stopped_) return;
    stopped_ = true;
  }
  const std::uint64_t one = 1;
  [[maybe_unused]] const ssize_t w = ::write(wake_fd_, &one, sizeof one);
  if (thread_.joinable()) thread_.join();
  std::lock_guard<std::mutex> l(m_);
  inbox_.clear();
}

void HeadReader::run() {
  epoll_event events[64];
  for (;;) {
    const int n = ::epoll_wait(epoll_fd_, events, 64, 100);
    const auto now = GuardClock::now();
    {
      std::lock_guard<std::mutex> l(m_);
      if (stopped_) break;
    }
    for (int i = 0; i < n; ++i) {
      if (events[i].data.fd == wake_fd_) {
        std::uint64_t v = 0;
        [[maybe_unused]] const ssize_t r = ::read(wake_fd_, &v, sizeof v);
        take_inbox(now);
      } else {
        on_readable(events[i].data.fd, now);
      }
    }
    if (now >= next_expiry_) {
      expire(now);
      next_expiry_ = now + kExpiryPeriod;
    }
    report(now, false);
  }
  conns_.clear();  // closes every socket held
  lingering_.clear();
  report(GuardClock::now(), true);  // what the last period refused
}

void HeadReader::take_inbox(GuardClock::time_point now) {
  std::vector<std::unique_ptr<Connection>> in;
  {
    std::lock_guard<std::mutex> l(m_);
    in.swap(inbox_);
  }
  for (auto& c : in) watch(std::move(c), now);
}

void HeadReader::watch(std::unique_ptr<Connection> c, GuardClock::time_point now) {
  Connection& r = *c;
  const int fd = c->fd;
  epoll_event ev{};
  ev.events = EPOLLIN | EPOLLRDHUP;
  ev.data.fd = fd;
  if (::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, fd, &ev) != 0) return;  // c closes here
  conns_[fd] = std::move(c);
  if (r.refuse_status != 0) {
    refuse(r, r.refuse_status, r.refuse_why, now);
  } else if (r.between_requests) {
    r.deadline = now + limits_.keep_alive_timeout;
  } else if (!r.buf.empty()) {
    // What arrived beyond the last request (pipelined) may already be a whole one.
    r.deadline = now + limits_.request_timeout;
    check(r, now);
  }
}

void HeadReader::on_readable(int fd, GuardClock::time_point now) {
  const auto it = conns_.find(fd);
  if (it == conns_.end()) return;
  Connection& c = *it->second;
  char chunk[4096];
  // A refused client that keeps sending is drained at most 64 KB a wake-up, so that it
  // cannot keep this thread from the others (epoll reports it again).
  for (int drained = 0; drained < 16;) {
    const bool draining = lingering_.count(fd) != 0;
    // Never more than a whole request can be, and one byte: HeadScan sees the excess.
    const std::size_t bound = limits_.max_head_bytes + limits_.max_body_bytes + 1;
    const std::size_t room = draining ? sizeof chunk : std::min(sizeof chunk, bound - std::min(bound, c.buf.size()));
    if (room == 0) {
      refuse(c, 431, "the request is larger than the viewer takes", now);
      return;
    }
    const ssize_t got = ::recv(fd, chunk, room, 0);
    if (got < 0 && errno == EINTR) continue;
    if (got < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return;
    if (got <= 0) {  // the client closed, or an error
      forget(fd);
      return;
    }
    if (draining) {  // read and dropped: a refused client's bytes cost nothing
      ++drained;
      continue;
    }
    if (c.between_requests) {
      c.between_requests = false;
      c.deadline = now + limits_.request_timeout;
    }
    c.buf.append(chunk, static_cast<std::size_t>(got));
    if (check(c, now)) return;
  }
}

bool HeadReader::check(Connection& c, GuardClock::time_point now) {
  const HeadVerdict v = c.scan.scan(c.buf);
  if (v.kind == HeadVerdict::Kind::kMore) return false;
  if (v.kind == HeadVerdict::Kind::kRefuse) {
    counters_.bad_requests.fetch_add(1);
    return refuse(c, v.status, v.why, now);
  }
  const int fd = c.fd;
  ::epoll_ctl(epoll_fd_, EPOLL_CTL_DEL, fd, nullptr);
  auto node = conns_.extract(fd);
  node.mapped()->request_bytes = v.request_bytes;
  dispatch_(std::move(node.mapped()));
  return true;
}

bool HeadReader::refuse(Connection& c, int status, const char* why, GuardClock::time_point now) {
  const std::string answer = refusal_response(status, why);
  [[maybe_unused]] const ssize_t w = ::send(c.fd, answer.data(), answer.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
  ::shutdown(c.fd, SHUT_WR);
  c.buf.clear();
  c.buf.shrink_to_fit();
  // Closing with unread bytes would reset the connection, and the client could lose
  // the answer: drain it a while, unless too many are draining already.
  if (static_cast<int>(lingering_.size()) >= limits_.max_lingering) {
    forget(c.fd);
    return true;
  }
  lingering_[c.fd] = now + limits_.refusal_linger;
  return false;
}

void HeadReader::forget(int fd) {
  ::epoll_ctl(epoll_fd_, EPOLL_CTL_DEL, fd, nullptr);
  lingering_.erase(fd);
  conns_.erase(fd);  // the Connection closes the socket
}

void HeadReader::expire(GuardClock::time_point now) {
  std::vector<int> done;
  for (const auto& [fd, until] : lingering_) {
    if (now >= until) done.push_back(fd);
  }
  for (const int fd : done) forget(fd);
  std::vector<Connection*> late;
  for (const auto& [fd, c] : conns_) {
    if (lingering_.count(fd) == 0 && now >= c->deadline) late.push_back(c.get());
  }
  for (Connection* c : late) {
    if (c->between_requests) {
      forget(c->fd);  // an idle keep-alive connection: closed without a word
    } else {
      counters_.timed_out.fetch_add(1);
      refuse(*c, 408, "the request did not arrive in time", now);
    }
  }
}

void HeadReader::report(GuardClock::time_point now, bool last) {
  if (now < next_report_ && !last) return;
  next_report_ = now + kReportPeriod;
  const long long now_counts[6] = {counters_.over_caps.load(), counters_.bad_requests.load(),
                                   counters_.timed_out.load(),  counters_.slow_responses.load(),
                                   counters_.evicted.load(),    counters_.stalled.load()};
  static const char* const kWhat[6] = {"connections refused over the caps (503)",
                                       "requests refused by the header limits",
                                       "requests not whole in time (408)",
                                       "responses not written in time",
                                       "event streams evicted by a new one",
                                       "event streams closed: their reader took nothing"};
  std::string line;
  for (int i = 0; i < 6; ++i) {
    const long long d = now_counts[i] - reported_[i];
    reported_[i] = now_counts[i];
    if (d > 0) line += (line.empty() ? "" : ", ") + std::to_string(d) + " " + kWhat[i];
  }
  if (!line.empty()) {
    std::fprintf(stderr, "viewer: HTTP %s: %s\n", last ? "since the last report" : "in the last 10 s", line.c_str());
  }
}

}  // namespace elaslam::viewer

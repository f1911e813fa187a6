// SPDX-License-Identifier: Apache-2.0
#include "guarded_server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <mutex>
#include <thread>
#include <vector>

#include "head_reader.hpp"
#include "tcp_probe.hpp"

namespace elaslam::viewer {
namespace {

/// Workers beyond the event streams' slots: /, /state.json and the refusals are
/// answered whatever the streams do.
constexpr int kShortWorkers = 4;
/// A blocked write looks again this often (an eviction's shutdown wakes it at once).
constexpr int kWritePollMs = 100;

void numeric_address(const sockaddr_storage& ss, std::string* ip, int* port) {
  char text[INET6_ADDRSTRLEN] = "";
  if (ss.ss_family == AF_INET) {
    sockaddr_in a{};
    std::memcpy(&a, &ss, sizeof a);
    ::inet_ntop(AF_INET, &a.sin_addr, text, sizeof text);
    *port = ntohs(a.sin_port);
  } else if (ss.ss_family == AF_INET6) {
    sockaddr_in6 a{};
    std::memcpy(&a, &ss, sizeof a);
    if (IN6_IS_ADDR_V4MAPPED(&a.sin6_addr)) {  // a socket bound to :: takes IPv4 peers this way
      ::inet_ntop(AF_INET, &a.sin6_addr.s6_addr[12], text, sizeof text);
    } else {
      ::inet_ntop(AF_INET6, &a.sin6_addr, text, sizeof text);
    }
    *port = ntohs(a.sin6_port);
  }
  *ip = text;
}

const char* status_text(int status) {
  switch (status) {
    case 400: return "Bad Request";
    case 408: return "Request Timeout";
    case 411: return "Length Required";
    case 413: return "Payload Too Large";
    case 414: return "URI Too Long";
    case 431: return "Request Header Fields Too Large";
    case 503: return "Service Unavailable";
    default: return "Error";
  }
}

/// A request's bytes as httplib reads them (only those: it never waits on the
/// socket), and its answer written with a deadline: response_timeout for a response,
/// for an event stream the reader's progress (ReadProgress) instead.
class ConnStream final : public httplib::Stream, public Evictable {
 public:
  ConnStream(Connection& c, const HttpLimits& limits, const std::atomic<bool>& stopping, GuardCounters& counters)
      : c_(c), limits_(limits), stopping_(stopping), counters_(counters),
        deadline_(GuardClock::now() + limits.response_timeout), progress_(GuardClock::now()) {}

  bool is_readable() const override { return pos_ < c_.request_bytes; }
  bool is_writable() const override { return !ended(GuardClock::now()); }
  ssize_t read(char* ptr, size_t size) override {
    const std::size_t n = std::min(size, c_.request_bytes - pos_);
    std::memcpy(ptr, c_.buf.data() + pos_, n);
    pos_ += n;
    return static_cast<ssize_t>(n);  // 0 past the request: "the client closed" to httplib
  }
  ssize_t write(const char* ptr, size_t size) override;
  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    ip = c_.peer;
    port = c_.peer_port;
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    ip = c_.local;
    port = c_.local_port;
  }
  socket_t socket() const override { return c_.fd; }

  /// Under the slots' lock, from another worker: the next write fails at once.
  void evict() override {
    evicted_.store(true);
    ::shutdown(c_.fd, SHUT_RDWR);
  }
  bool become_event_stream(StreamSlots& slots) {
    const auto now = GuardClock::now();
    progress_ = ReadProgress(now);
    const StreamSlots::Admit a = slots.open(this, c_.peer, now);
    if (a == StreamSlots::Admit::kRefused) return false;
    if (a != StreamSlots::Admit::kOpened) counters_.evicted.fetch_add(1);
    slots_ = &slots;
    return true;
  }
  /// Before the connection closes (and this stream is destroyed).
  void leave_slot() {
    if (slots_ == nullptr) return;
    slots_->close(this);
    const bool stalled = progress_.stalled_for(GuardClock::now()) >= limits_.stream_stall_close;
    if (stalled && !evicted_.load() && !stopping_.load()) counters_.stalled.fetch_add(1);
  }
  bool is_event_stream() const { return slots_ != nullptr; }
  bool consumed_all() const { return pos_ == c_.request_bytes; }
  /// Evicted, stopping, or too slow: its reader took nothing for stream_stall_close
  /// (an event stream), or the answer is past response_timeout.
  bool ended(GuardClock::time_point now) const {
    if (evicted_.load() || stopping_.load()) return true;
    if (slots_ != nullptr) return progress_.stalled_for(now) >= limits_.stream_stall_close;
    return now >= deadline_;
  }

 private:
  void observe(GuardClock::time_point now);

  Connection& c_;
  const HttpLimits& limits_;
  const std::atomic<bool>& stopping_;
  GuardCounters& counters_;
  GuardClock::time_point deadline_;
  std::size_t pos_ = 0;
  StreamSlots* slots_ = nullptr;  // set: an event stream
  ReadProgress progress_;
  bool told_stalled_ = false;      // what the slots were last told
  bool counted_end_ = false;
  std::atomic<bool> evicted_{false};
};

ssize_t ConnStream::write(const char* ptr, size_t size) {
  for (;;) {
    const auto now = GuardClock::now();
    if (slots_ != nullptr) observe(now);
    if (ended(now)) {
      // An event stream's end is counted as it leaves its slot.
      if (!counted_end_ && slots_ == nullptr && !stopping_.load()) counters_.slow_responses.fetch_add(1);
      counted_end_ = true;
      return -1;
    }
    const ssize_t sent = ::send(c_.fd, ptr, size, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (sent >= 0) return sent;
    if (errno == EINTR) continue;
    if (errno != EAGAIN && errno != EWOULDBLOCK) return -1;
    pollfd p{c_.fd, POLLOUT, 0};
    ::poll(&p, 1, kWritePollMs);
  }
}

void ConnStream::observe(GuardClock::time_point now) {
  TcpSendState s;
  if (!probe_tcp_send(c_.fd, &s)) return;
  progress_.observe(s.unacked, s.acked, now);
  if (progress_.stalled() == told_stalled_) return;
  told_stalled_ = progress_.stalled();
  slots_->set_stalled(this, told_stalled_ ? std::optional(progress_.stalled_since()) : std::nullopt);
}

/// The stream of the request this worker thread is answering (begin_event_stream).
thread_local ConnStream* t_stream = nullptr;

/// httplib's accept loop hands each socket to its task queue: this one runs it at
/// once (process_and_close_socket only passes it on, never blocks).
class InlineQueue final : public httplib::TaskQueue {
 public:
  void enqueue(std::function<void()> fn) override { fn(); }
  void shutdown() override {}
};

}  // namespace

/// The workers: each takes a connection with a whole request and answers it.
class WorkerPool {
 public:
  WorkerPool(int n, std::function<void(std::unique_ptr<Connection>)> job) : job_(std::move(job)) {
    for (int i = 0; i < n; ++i) threads_.emplace_back([this] { run(); });
  }
  ~WorkerPool() { stop(); }

  void push(std::unique_ptr<Connection> c) {
    {
      std::lock_guard<std::mutex> l(m_);
      if (stopped_) return;  // closes
      queue_.push_back(std::move(c));  // at most the caps' connections
    }
    cv_.notify_one();
  }
  void stop() {
    {
      std::lock_guard<std::mutex> l(m_);
      stopped_ = true;
    }
    cv_.notify_all();
    for (auto& t : threads_) {
      if (t.joinable()) t.join();
    }
    queue_.clear();
  }

 private:
  void run() {
    for (;;) {
      std::unique_ptr<Connection> c;
      {
        std::unique_lock<std::mutex> l(m_);
        cv_.wait(l, [&] { return stopped_ || !queue_.empty(); });
        if (stopped_) return;
        c = std::move(queue_.front());
        queue_.pop_front();
      }
      job_(std::move(c));
    }
  }

  std::function<void(std::unique_ptr<Connection>)> job_;
  std::mutex m_;
  std::condition_variable cv_;
  std::deque<std::unique_ptr<Connection>> queue_;
  bool stopped_ = false;
  std::vector<std::thread> threads_;
};

Connection::Connection(int socket, const HttpLimits& limits) : fd(socket), scan(limits) {
  const int flags = ::fcntl(fd, F_GETFL);
  if (flags >= 0) ::fcntl(fd, F_SETFL, flags | O_NONBLOCK);
  sockaddr_storage ss{};
  socklen_t len = sizeof ss;
  if (::getpeername(fd, reinterpret_cast<sockaddr*>(&ss), &len) == 0) numeric_address(ss, &peer, &peer_port);
  len = sizeof ss;
  if (::getsockname(fd, reinterpret_cast<sockaddr*>(&ss), &len) == 0) numeric_address(ss, &local, &local_port);
}

Connection::~Connection() {
  if (caps != nullptr) caps->release(peer);
  ::shutdown(fd, SHUT_RDWR);
  ::close(fd);
}

std::string refusal_response(int status, const char* why) {
  const std::string body = std::string(why) + "\n";
  std::string r = "HTTP/1.1 " + std::to_string(status) + " " + status_text(status) + "\r\n";
  r += "Content-Type: text/plain\r\nContent-Length: " + std::to_string(body.size()) + "\r\n";
  if (status == 503) r += "Retry-After: 2\r\n";
  r += "Connection: close\r\n\r\n" + body;
  return r;
}

GuardedServer::GuardedServer(const HttpLimits& limits, int max_streams)
    : limits_(limits),
      caps_(limits.max_connections, limits.max_connections_per_address),
      slots_(max_streams, limits.stream_evict_after) {
  // httplib's own settings, kept equal to the guard's: it writes them in Keep-Alive
  // headers and checks the body against the payload bound again.
  set_keep_alive_max_count(static_cast<std::size_t>(limits.keep_alive_max_requests));
  set_keep_alive_timeout(std::chrono::duration_cast<std::chrono::seconds>(limits.keep_alive_timeout).count());
  set_payload_max_length(limits.max_body_bytes);
  new_task_queue = [] { return new InlineQueue; };
  workers_ = std::make_unique<WorkerPool>(max_streams + kShortWorkers,
                                          [this](std::unique_ptr<Connection> c) { serve(std::move(c)); });
  reader_ = std::make_unique<HeadReader>(limits_, counters_,
                                         [this](std::unique_ptr<Connection> c) { workers_->push(std::move(c)); });
}

GuardedServer::~GuardedServer() { shutdown(); }

void GuardedServer::shutdown() {
  stopping_.store(true);
  // httplib's stop() closes the listening socket only once its accept loop runs; a stop
  // that comes first (a signal at start-up) would leave listen_after_bind() waiting.
  const socket_t listening = svr_sock_.exchange(INVALID_SOCKET);
  if (listening != INVALID_SOCKET) {
    ::shutdown(listening, SHUT_RDWR);  // wakes accept()
    ::close(listening);
  }
  reader_->stop();   // every connection waiting for its request closes
  workers_->stop();  // answers in progress end (their writes see stopping_)
}

int GuardedServer::bind_port(const std::string& host, int port) {
  const int bound = port == 0 ? bind_to_any_port(host) : (bind_to_port(host, port) ? port : -1);
  // listen() again on a listening socket sets its backlog (Linux).
  if (bound > 0) ::listen(svr_sock_, limits_.max_connections);
  return bound;
}

bool GuardedServer::process_and_close_socket(socket_t sock) {
  auto c = std::make_unique<Connection>(sock, limits_);
  if (stopping_.load()) return false;  // closes
  if (caps_.admit(c->peer)) {
    c->caps = &caps_;
    c->deadline = GuardClock::now() + limits_.request_timeout;
  } else {
    counters_.over_caps.fetch_add(1);
    c->refuse_status = 503;
    c->refuse_why = "the viewer has as many connections as it serves (from this address or in all); try again";
  }
  reader_->add(std::move(c));
  return true;
}

void GuardedServer::serve(std::unique_ptr<Connection> c) {
  bool keep = false;
  {
    ConnStream strm(*c, limits_, stopping_, counters_);
    const bool last = ++c->served >= keep_alive_max_count_;
    bool closed = false;
    t_stream = &strm;
    const bool ok = process_request(strm, last, closed, nullptr);
    t_stream = nullptr;
    keep = ok && !closed && !last && !strm.is_event_stream() && strm.consumed_all() && !strm.ended(GuardClock::now());
    strm.leave_slot();  // before the stream is gone and the socket closed: an evictor may hold it
  }
  if (!keep || stopping_.load()) return;  // c closes
  c->buf.erase(0, c->request_bytes);
  c->request_bytes = 0;
  c->scan.reset();
  c->between_requests = c->buf.empty();
  reader_->add(std::move(c));
}

bool GuardedServer::begin_event_stream() {
  return t_stream != nullptr && t_stream->become_event_stream(slots_);
}

}  // namespace elaslam::viewer

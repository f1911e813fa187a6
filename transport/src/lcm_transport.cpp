// SPDX-License-Identifier: Apache-2.0
#include "elaslam/transport/lcm_transport.hpp"

#include <poll.h>

#include <cstdio>
#include <cstdlib>
#include <list>

#include <lcm/lcm-cpp.hpp>

#include "elaslam/common/log.hpp"
#include "elaslam/transport/udpm_receiver.hpp"

namespace elaslam::transport {
namespace {

bool is_udpm(const std::string& url) { return url.empty() || url.compare(0, 7, "udpm://") == 0; }

/// The URL liblcm opens: the given one, else $LCM_DEFAULT_URL, else LCM's default.
std::string effective(const std::string& url) {
  if (!url.empty()) return url;
  const char* env = std::getenv("LCM_DEFAULT_URL");
  return env != nullptr ? env : "";
}

}  // namespace

// udpm:// (every team between processes): liblcm publishes, UdpmReceiver receives
// (udpm_receiver.hpp says why), and subscriptions are matched here as LCM matches them
// (the pattern anchored at both ends, POSIX extended syntax). Other URLs (memq://,
// file://): liblcm both ways, each datagram checked as it is handed over.
struct LcmTransport::Impl {
  struct Sub {
    Impl* impl;
    int id;
    RawHandler handler;
    void* context;
    lcm::Subscription* lcm_sub = nullptr;  // liblcm's receive path
    int own_id = 0;                         // udpm: the dispatcher's subscription
  };

  Impl(const std::string& url_, std::string who_, std::FILE* log_)
      : url(effective(url_)), lc(url_), who(std::move(who_)), log(log_), dispatcher(who, log) {
    own_receive = is_udpm(url);
    if (own_receive && !parse_udpm_url(url, &address, &error)) lc_good = false;
  }

  static void dispatch(const lcm::ReceiveBuffer* rb, const std::string& channel, Sub* sub) {
    if (const char* why = malformed_message(channel, rb->data, rb->data_size))
      return sub->impl->refuse(channel, rb->data_size, why);
    sub->handler(RawMessage{channel, static_cast<const std::uint8_t*>(rb->data), rb->data_size, rb->recv_utime},
                 sub->context);
  }
  void refuse(const std::string& channel, std::size_t size, const char* why) {
    ++malformed;
    if (log == nullptr || (malformed > 20 && malformed % 1000 != 0)) return;
    char name[4 * contract::kMaxChannelBytes + 8];
    log::print(log, log::Priority::kWarning,
               "%s: refused a datagram on '%s' (size %zu): %s (%lld so far)\n", who.c_str(),
               printable_channel(channel, name), size, why, static_cast<long long>(malformed));
  }

  bool open_receiver() {
    if (rx || !error.empty()) return static_cast<bool>(rx);
    rx = UdpmReceiver::open(address, &error);
    if (!rx && log != nullptr) log::print(log, log::Priority::kErr,
                                          "%s: cannot receive on %s: %s\n", who.c_str(), url.c_str(), error.c_str());
    return static_cast<bool>(rx);
  }

  /// Read datagrams until one completes a message (dispatched: 1) or none waits (0).
  int receive_one() {
    for (int k = 0; k < 256; ++k) {  // bounded: a flood of fragments does not hold the caller
      bool message = false;
      if (!rx->read(&dispatcher, &message)) return 0;
      if (message) return 1;
    }
    return 0;
  }

  std::string url;
  lcm::LCM lc;
  bool lc_good = true;
  bool own_receive = false;
  UdpmAddress address;
  std::unique_ptr<UdpmReceiver> rx;  // opened at the first subscription, as liblcm opens its own
  std::string error;
  std::string who;
  std::FILE* log;
  DatagramDispatcher dispatcher;
  std::list<Sub> subs;  // stable addresses: liblcm holds a pointer to each
  int next_id = 1;
  std::int64_t malformed = 0;  // liblcm's path
};

LcmTransport::LcmTransport(const std::string& url, std::string who, std::FILE* log)
    : impl_(std::make_unique<Impl>(url, std::move(who), log)) {}
LcmTransport::~LcmTransport() {
  for (auto& s : impl_->subs)
    if (s.lcm_sub != nullptr) impl_->lc.unsubscribe(s.lcm_sub);
}

bool LcmTransport::good() const { return impl_->lc.good() && impl_->lc_good; }

bool LcmTransport::publish(const std::string& channel, const void* data, std::size_t size) {
  return impl_->lc.publish(channel, data, static_cast<unsigned int>(size)) == 0;
}

int LcmTransport::subscribe(const std::string& pattern, RawHandler handler, void* context, int queue_capacity) {
  Impl& m = *impl_;
  Impl::Sub& s = m.subs.emplace_back(Impl::Sub{&m, m.next_id, handler, context});
  if (m.own_receive) {
    // No per-subscription queue: datagrams wait in the socket's receive buffer (the
    // URL's recv_buf_size) until handle_timeout reads them.
    s.own_id = m.open_receiver() ? m.dispatcher.subscribe(pattern, handler, context) : 0;
    if (s.own_id == 0) {
      m.subs.pop_back();
      return 0;
    }
    return m.next_id++;
  }
  s.lcm_sub = m.lc.subscribeFunction(pattern, &Impl::dispatch, &s);
  if (s.lcm_sub == nullptr) {
    m.subs.pop_back();
    return 0;
  }
  if (queue_capacity >= 0) s.lcm_sub->setQueueCapacity(queue_capacity);
  return m.next_id++;
}

void LcmTransport::unsubscribe(int id) {
  for (auto it = impl_->subs.begin(); it != impl_->subs.end(); ++it) {
    if (it->id != id) continue;
    if (it->lcm_sub != nullptr) impl_->lc.unsubscribe(it->lcm_sub);
    if (it->own_id != 0) impl_->dispatcher.unsubscribe(it->own_id);
    impl_->subs.erase(it);
    return;
  }
}

TransportRefusals LcmTransport::refusals() const {
  const std::int64_t n = impl_->malformed + impl_->dispatcher.malformed();
  return {n, 0, n};
}

std::int64_t LcmTransport::dropped_fragments() const { return impl_->dispatcher.dropped_fragments(); }

int LcmTransport::handle_timeout(int timeout_ms) {
  Impl& m = *impl_;
  if (!m.own_receive) return m.lc.handleTimeout(timeout_ms);
  if (!m.rx) {  // nothing subscribed: wait as asked, as liblcm does
    if (timeout_ms > 0) ::poll(nullptr, 0, timeout_ms);
    return 0;
  }
  if (const int got = m.receive_one(); got > 0) return got;
  pollfd p{m.rx->fd(), POLLIN, 0};
  const int ready = ::poll(&p, 1, timeout_ms);
  if (ready < 0) return -1;  // also EINTR (a signal), as liblcm's handleTimeout
  return ready == 0 ? 0 : m.receive_one();
}

int LcmTransport::fileno() {
  Impl& m = *impl_;
  if (!m.own_receive) return m.lc.getFileno();
  return m.open_receiver() ? m.rx->fd() : -1;
}

}  // namespace elaslam::transport

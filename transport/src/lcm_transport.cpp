#include "elaslam/transport/lcm_transport.hpp"

#include <list>

#include <lcm/lcm-cpp.hpp>

namespace elaslam::transport {

struct LcmTransport::Impl {
  struct Sub {
    int id;
    RawHandler handler;
    void* context;
    lcm::Subscription* lcm_sub = nullptr;
  };

  explicit Impl(const std::string& url) : lc(url) {}

  static void dispatch(const lcm::ReceiveBuffer* rb, const std::string& channel, Sub* sub) {
    sub->handler(RawMessage{channel, static_cast<const std::uint8_t*>(rb->data), rb->data_size}, sub->context);
  }

  lcm::LCM lc;
  std::list<Sub> subs;  // stable addresses: LCM holds a pointer to each
  int next_id = 1;
};

LcmTransport::LcmTransport(const std::string& url) : impl_(std::make_unique<Impl>(url)) {}
LcmTransport::~LcmTransport() = default;

bool LcmTransport::good() const { return impl_->lc.good(); }

bool LcmTransport::publish(const std::string& channel, const void* data, std::size_t size) {
  return impl_->lc.publish(channel, data, static_cast<unsigned int>(size)) == 0;
}

int LcmTransport::subscribe(const std::string& pattern, RawHandler handler, void* context, int queue_capacity) {
  Impl::Sub& s = impl_->subs.emplace_back(Impl::Sub{impl_->next_id, handler, context});
  s.lcm_sub = impl_->lc.subscribeFunction(pattern, &Impl::dispatch, &s);
  if (s.lcm_sub == nullptr) {
    impl_->subs.pop_back();
    return 0;
  }
  if (queue_capacity >= 0) s.lcm_sub->setQueueCapacity(queue_capacity);
  return impl_->next_id++;
}

void LcmTransport::unsubscribe(int id) {
  for (auto it = impl_->subs.begin(); it != impl_->subs.end(); ++it) {
    if (it->id != id) continue;
    impl_->lc.unsubscribe(it->lcm_sub);
    impl_->subs.erase(it);
    return;
  }
}

int LcmTransport::handle_timeout(int timeout_ms) { return impl_->lc.handleTimeout(timeout_ms); }

int LcmTransport::fileno() { return impl_->lc.getFileno(); }

}  // namespace elaslam::transport

// The transport over LCM 1.3.1 (LCM.md): udpm:// between processes and hosts, also
// memq:// and file://. A thin layer: subscriptions go through subscribeFunction (1.3.1
// has no lambda subscriptions, and its member-function ones trip UBSan's vptr check
// under GCC 12), each with the queue bound the caller chose.
#pragma once

#include <memory>
#include <string>

#include "elaslam/transport/transport.hpp"

namespace elaslam::transport {

class LcmTransport final : public Transport {
 public:
  /// `url` "" means $LCM_DEFAULT_URL, else LCM's default (udpm://239.255.76.67:7667?ttl=0).
  explicit LcmTransport(const std::string& url);
  ~LcmTransport() override;

  bool good() const override;
  const char* kind() const override { return "LCM"; }
  bool publish(const std::string& channel, const void* data, std::size_t size) override;
  int subscribe(const std::string& pattern, RawHandler handler, void* context, int queue_capacity) override;
  void unsubscribe(int id) override;
  int handle_timeout(int timeout_ms) override;

  /// The descriptor that is readable when a message waits (LCM's getFileno; for udpm://
  /// it opens the receive socket): for a caller that polls several transports.
  int fileno();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace elaslam::transport

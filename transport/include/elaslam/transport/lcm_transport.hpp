// SPDX-License-Identifier: Apache-2.0
// The transport over LCM 1.3.1 (LCM.md): udpm:// between processes and hosts, also
// memq:// and file://. liblcm publishes. On udpm:// this transport receives itself
// (UdpmReceiver, udpm_receiver.hpp: liblcm's receive thread crashes on malformed
// datagrams) and matches subscriptions as LCM does, reading datagrams from the
// socket's buffer in handle_timeout (no per-subscription queue: the queue capacity is
// the URL's recv_buf_size). On memq:// and file:// liblcm receives, through
// subscribeFunction (1.3.1 has no lambda subscriptions, and its member-function ones
// trip UBSan's vptr check under GCC 12), each with the queue bound the caller chose.
// Every message is checked (malformed_message, transport.hpp) before a subscriber
// sees it; what fails is counted (refusals) and said on `log` at a bounded rate.
#pragma once

#include <cstdio>
#include <memory>
#include <string>

#include "elaslam/transport/transport.hpp"

namespace elaslam::transport {

class LcmTransport final : public Transport {
 public:
  /// `url` "" means $LCM_DEFAULT_URL, else LCM's default (udpm://239.255.76.67:7667?ttl=0).
  /// `who` prefixes the log lines about refused datagrams (`log` nullptr: counted only).
  explicit LcmTransport(const std::string& url, std::string who = "LCM", std::FILE* log = nullptr);
  ~LcmTransport() override;

  bool good() const override;
  const char* kind() const override { return "LCM"; }
  bool publish(const std::string& channel, const void* data, std::size_t size) override;
  int subscribe(const std::string& pattern, RawHandler handler, void* context, int queue_capacity) override;
  void unsubscribe(int id) override;
  int handle_timeout(int timeout_ms) override;
  TransportRefusals refusals() const override;
  /// udpm://: well-formed fragments of no message in progress (its first fragment
  /// lost, or out of order): their message is lost, as liblcm loses it.
  std::int64_t dropped_fragments() const;

  /// The descriptor that is readable when a message waits (udpm://: the receive socket,
  /// opened now if no subscription opened it; else LCM's getFileno): for a caller that
  /// polls several transports.
  int fileno();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace elaslam::transport

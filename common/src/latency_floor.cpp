// SPDX-License-Identifier: Apache-2.0
#include "elaslam/common/latency_floor.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>

#include "elaslam/common/contract.hpp"

namespace elaslam::latency_floor {

void write_payload(std::int64_t seq, std::int64_t sent_ns, std::vector<char>* buf) {
  std::memcpy(buf->data(), &seq, 8);
  std::memcpy(buf->data() + 8, &sent_ns, 8);
}

void Delays::on_message(const void* data, std::size_t size, std::int64_t now_ns) {
  if (size < 16 || size > static_cast<std::size_t>(contract::kMaxMessageBytes)) return;
  std::int64_t seq = 0, sent = 0;
  std::memcpy(&seq, data, 8);
  std::memcpy(&sent, static_cast<const char*>(data) + 8, 8);
  last_seq_ = std::max(last_seq_, seq);
  if (seq < kWarmup) return;
  ++received_;
  delays_ns_.push_back(now_ns - sent);
}

double Delays::quantile_us(double q) {
  const auto k = static_cast<std::size_t>(q * static_cast<double>(delays_ns_.size() - 1) + 0.5);
  std::nth_element(delays_ns_.begin(), delays_ns_.begin() + static_cast<std::ptrdiff_t>(k), delays_ns_.end());
  return static_cast<double>(delays_ns_[k]) / 1000.0;
}

double Delays::max_us() const {
  return static_cast<double>(*std::max_element(delays_ns_.begin(), delays_ns_.end())) / 1000.0;
}

std::string floor_line(double rate_hz, int size, int count, Delays& d) {
  const double p50 = d.quantile_us(0.5), p90 = d.quantile_us(0.9), p99 = d.quantile_us(0.99), max = d.max_us();
  char line[256];
  std::snprintf(line, sizeof line,
                "lcm_floor: %g Hz, %d B: %d of %d received, one-way p50 / p90 / p99 / max %.0f / %.0f / %.0f / %.0f us\n",
                rate_hz, size, d.received(), count, p50, p90, p99, max);
  return line;
}

}  // namespace elaslam::latency_floor

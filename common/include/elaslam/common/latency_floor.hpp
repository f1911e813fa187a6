// SPDX-License-Identifier: Apache-2.0
// lcm_floor's measurement (docs/benchmarks.md "Latency and LCM's floor"): the payload
// its sender publishes ([seq, int64][send time, int64 ns][zeros up to the size], host
// byte order: both ends are on one machine), the receiver's one-way delays after the
// warm-up messages, and the line it prints.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace elaslam::latency_floor {

constexpr int kWarmup = 20;  // first messages not counted (sockets, caches, LCM's queues)

/// seq and the send time into the first 16 bytes of `buf` (at least 16 long).
void write_payload(std::int64_t seq, std::int64_t sent_ns, std::vector<char>* buf);

/// What the receiver keeps: the delays of the messages past the warm-up, and the
/// highest sequence number seen (warm-up ones too: the receiver stops at the last).
class Delays {
 public:
  explicit Delays(int expected) { delays_ns_.reserve(static_cast<std::size_t>(expected)); }
  /// One message received at now_ns; a cut one (shorter than 16 bytes or longer than
  /// contract::kMaxMessageBytes) is ignored.
  void on_message(const void* data, std::size_t size, std::int64_t now_ns);
  std::int64_t last_seq() const { return last_seq_; }
  int received() const { return received_; }
  bool empty() const { return delays_ns_.empty(); }
  /// The delay [us] of rank round(q (n - 1)) in ascending order; n > 0.
  double quantile_us(double q);
  double max_us() const;

 private:
  std::vector<std::int64_t> delays_ns_;
  std::int64_t last_seq_ = -1;
  int received_ = 0;
};

/// "lcm_floor: 100 Hz, 200 B: 1998 of 2000 received, one-way p50 / p90 / p99 / max
/// 60 / 80 / 120 / 900 us"; `d` not empty.
std::string floor_line(double rate_hz, int size, int count, Delays& d);

}  // namespace elaslam::latency_floor

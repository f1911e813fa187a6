// SPDX-License-Identifier: Apache-2.0
// lcm_floor's measurement (common/latency_floor.hpp): the payload read back, warm-up
// and cut messages left out, the quantiles' ranks and the printed line.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "elaslam/common/latency_floor.hpp"

namespace elaslam::latency_floor {
namespace {

std::vector<char> payload(std::int64_t seq, std::int64_t sent_ns, std::size_t size = 32) {
  std::vector<char> buf(size, 0);
  write_payload(seq, sent_ns, &buf);
  return buf;
}

TEST(LatencyFloor, WarmupAndCutMessagesAreNotTimed) {
  Delays d(10);
  for (int seq = 0; seq < kWarmup; ++seq) d.on_message(payload(seq, 0).data(), 32, 5'000);
  EXPECT_TRUE(d.empty());
  EXPECT_EQ(d.last_seq(), kWarmup - 1);
  d.on_message(payload(kWarmup + 5, 0).data(), 15, 1'000);  // cut: shorter than its header
  EXPECT_EQ(d.last_seq(), kWarmup - 1);
  d.on_message(payload(kWarmup, 1'000'000).data(), 16, 1'250'000);  // 250 us
  EXPECT_EQ(d.received(), 1);
  EXPECT_EQ(d.last_seq(), kWarmup);
  EXPECT_DOUBLE_EQ(d.max_us(), 250.0);
}

TEST(LatencyFloor, QuantilesAndTheLine) {
  Delays d(100);
  // Delays 1..100 us, in a shuffled order.
  for (int i = 0; i < 100; ++i) {
    const int us = (i * 37) % 100 + 1;
    d.on_message(payload(kWarmup + i, 0).data(), 200, us * 1000);
  }
  EXPECT_EQ(d.received(), 100);
  EXPECT_DOUBLE_EQ(d.quantile_us(0.5), 51.0);  // rank round(0.5 x 99) = 50 (of 0..99)
  EXPECT_DOUBLE_EQ(d.quantile_us(0.9), 90.0);  // rank round(89.1) = 89
  EXPECT_EQ(floor_line(100.0, 200, 120, d),
            "lcm_floor: 100 Hz, 200 B: 100 of 120 received, one-way p50 / p90 / p99 / max 51 / 90 / 99 / 100 us\n");
}

}  // namespace
}  // namespace elaslam::latency_floor

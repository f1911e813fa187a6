// SPDX-License-Identifier: Apache-2.0
// The simulator's clock (docs/design.md section 6): frame k is due at t0 + k / F, every
// deadline from the same origin so that no drift accumulates. The world's work for a
// frame is done ahead of its deadline (the frame's processing time) and its messages
// go out at the deadline. ScheduleStats keeps what the schedule achieved.
#pragma once

#include <atomic>
#include <cstdint>

#include "elaslam/common/histogram.hpp"

namespace elaslam::sim {

constexpr std::int64_t kNsPerMs = 1000000;

/// CLOCK_MONOTONIC [ns].
std::int64_t mono_ns();

/// Sleep until the absolute CLOCK_MONOTONIC time `deadline_ns`, at most 50 ms at a time
/// so that a stop is noticed promptly even when its signal came just before the
/// sleep began. False when `stop` was set meanwhile.
bool sleep_until(std::int64_t deadline_ns, const std::atomic<bool>& stop);

class FrameSchedule {
 public:
  FrameSchedule(double rate_hz, std::int64_t t0_ns) : rate_hz_(rate_hz), t0_ns_(t0_ns) {}
  /// t0 + k / F [ns].
  std::int64_t deadline_ns(int k) const {
    return t0_ns_ + static_cast<std::int64_t>(static_cast<long double>(k) * 1e9L / rate_hz_);
  }
  std::int64_t period_ns() const { return static_cast<std::int64_t>(1e9 / rate_hz_); }
  double rate_hz() const { return rate_hz_; }

 private:
  double rate_hz_;
  std::int64_t t0_ns_;
};

struct ScheduleStats {
  /// A frame is late when it goes out more than this after its deadline: about the LCM
  /// messaging floor's worst case on this class of machine (LCM.md section 5) and 1 %
  /// of a 10 Hz period; at >= 1 kHz every late frame is also an overrun.
  static constexpr std::int64_t kLateNs = 1 * kNsPerMs;

  std::int64_t published = 0;
  std::int64_t late = 0;      // published > kLateNs after the deadline
  std::int64_t overruns = 0;  // published at or after the next frame's deadline
  std::int64_t max_late_ns = 0;
  std::int64_t first_pub_ns = 0, last_pub_ns = 0;
  int last_frame = -1;           // the last frame published
  DurationHistogram processing;  // [us] per frame: the world's step and its messages

  /// Frame k went out at `pub_ns`, due at `deadline_ns`; returns its lateness [ns].
  std::int64_t record(int k, std::int64_t pub_ns, std::int64_t deadline_ns, std::int64_t period_ns);
  /// Frames per second from the first publication to the last (0 before two).
  double achieved_hz() const;
};

}  // namespace elaslam::sim

// SPDX-License-Identifier: Apache-2.0
#include "elaslam/simulator/scheduler.hpp"

#include <time.h>

#include <algorithm>

namespace elaslam::sim {

std::int64_t mono_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

bool sleep_until(std::int64_t deadline_ns, const std::atomic<bool>& stop) {
  constexpr std::int64_t kSliceNs = 50 * kNsPerMs;
  while (!stop.load()) {
    const std::int64_t now = mono_ns();
    if (now >= deadline_ns) return true;
    const std::int64_t wake = std::min(deadline_ns, now + kSliceNs);
    timespec ts{};
    ts.tv_sec = static_cast<time_t>(wake / 1000000000LL);
    ts.tv_nsec = static_cast<long>(wake % 1000000000LL);
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);  // EINTR: the loop checks again
  }
  return false;
}

std::int64_t ScheduleStats::record(int k, std::int64_t pub_ns, std::int64_t deadline_ns, std::int64_t period_ns) {
  const std::int64_t late_ns = pub_ns - deadline_ns;
  if (late_ns > kLateNs) ++late;
  if (late_ns >= period_ns) ++overruns;
  max_late_ns = std::max(max_late_ns, late_ns);
  if (published == 0) first_pub_ns = pub_ns;
  last_pub_ns = pub_ns;
  last_frame = k;
  ++published;
  return late_ns;
}

double ScheduleStats::achieved_hz() const {
  const double span_s = static_cast<double>(last_pub_ns - first_pub_ns) * 1e-9;
  return (published > 1 && span_s > 0.0) ? static_cast<double>(published - 1) / span_s : 0.0;
}

}  // namespace elaslam::sim

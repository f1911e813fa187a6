// SPDX-License-Identifier: Apache-2.0
// Fixed-memory histogram of durations in microseconds, for p50 / p99 / max of
// per-frame processing times. 1 us buckets up to kLinearUs, then a single overflow
// bucket (the max is kept exactly). No allocation after construction.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "elaslam/common/quantile.hpp"

namespace elaslam {

class DurationHistogram {
 public:
  static constexpr int kLinearUs = 20000;

  DurationHistogram() : counts_(kLinearUs + 1, 0) {}

  void add(std::int64_t us) {
    us = std::max<std::int64_t>(us, 0);
    ++counts_[static_cast<std::size_t>(std::min<std::int64_t>(us, kLinearUs))];
    ++total_;
    max_ = std::max(max_, us);
  }
  std::int64_t count() const { return total_; }
  std::int64_t max() const { return max_; }
  /// The q-quantile (quantile.hpp's nearest rank), to the bucket: the smallest bucket
  /// value with at least ceil(q n) samples at or below it (0 < q <= 1).
  std::int64_t quantile(double q) const {
    if (total_ == 0) return 0;
    const auto need = static_cast<std::int64_t>(quantile_rank(q, static_cast<std::size_t>(total_))) + 1;
    std::int64_t seen = 0;
    for (std::size_t i = 0; i < counts_.size(); ++i) {
      seen += counts_[i];
      if (seen >= need) return i == static_cast<std::size_t>(kLinearUs) ? max_ : static_cast<std::int64_t>(i);
    }
    return max_;
  }
  void clear() {
    std::fill(counts_.begin(), counts_.end(), 0);
    total_ = 0;
    max_ = 0;
  }

 private:
  std::vector<std::int64_t> counts_;
  std::int64_t total_ = 0;
  std::int64_t max_ = 0;
};

}  // namespace elaslam

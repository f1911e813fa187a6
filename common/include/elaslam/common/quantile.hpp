// SPDX-License-Identifier: Apache-2.0
// The one quantile convention of the project (latency and processing-time
// percentiles, miss-run statistics): the nearest rank. The q-quantile of n samples
// is the ceil(q n)-th smallest (1-based), so p50 of 1..100 is 50, p99 is 99 and
// p100 the maximum; never an interpolated value that no sample had.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace elaslam {

/// 0-based index of the q-quantile in n sorted samples (n > 0, q in (0, 1]).
inline std::size_t quantile_rank(double q, std::size_t n) {
  // 1e-9 absorbs q * n landing a hair above an integer (0.99 * 100 = 99.000000000000014).
  const double k = std::ceil(q * static_cast<double>(n) - 1e-9);
  return static_cast<std::size_t>(std::clamp(k, 1.0, static_cast<double>(n))) - 1;
}

/// The q-quantile of `v` (copied and partially sorted); T() when empty.
template <typename T>
T quantile(std::vector<T> v, double q) {
  if (v.empty()) return T();
  const auto k = static_cast<std::ptrdiff_t>(quantile_rank(q, v.size()));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[static_cast<std::size_t>(k)];
}

}  // namespace elaslam

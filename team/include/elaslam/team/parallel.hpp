// SPDX-License-Identifier: Apache-2.0
// Independent runs of the team on several threads (the sweep's grid, run_dataset's
// modes): each index once, the first failure reported.
#pragma once

#include <cstddef>
#include <functional>

namespace elaslam {

/// job(i) for every i in [0, n), on min(threads, n) threads (at least one), each
/// index taken once in ascending order. The first exception any job throws stops
/// the threads from taking new indices and is rethrown once all have joined.
void run_parallel(std::size_t n, int threads, const std::function<void(std::size_t)>& job);

}  // namespace elaslam

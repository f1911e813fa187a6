// SPDX-License-Identifier: Apache-2.0
// run_parallel: every index once whatever the thread count, and a job's exception
// rethrown after the join with the remaining indices left untaken.
#include "elaslam/team/parallel.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <vector>

namespace elaslam {
namespace {

TEST(RunParallel, EveryIndexRunsOnceWhateverTheThreadCount) {
  for (int threads : {0, 1, 3, 64}) {
    std::vector<std::atomic<int>> seen(37);
    run_parallel(seen.size(), threads, [&](std::size_t i) { ++seen[i]; });
    for (std::size_t i = 0; i < seen.size(); ++i) EXPECT_EQ(seen[i], 1) << "index " << i << ", threads " << threads;
  }
  run_parallel(0, 4, [](std::size_t) { FAIL() << "no index to run"; });
}

TEST(RunParallel, AFailureIsRethrownAndStopsNewIndices) {
  std::atomic<int> ran{0};
  EXPECT_THROW(run_parallel(1000, 1, [&](std::size_t i) {
                 ++ran;
                 if (i == 5) throw std::runtime_error("job 5");
               }),
               std::runtime_error);
  EXPECT_EQ(ran, 6);  // one thread: indices 0..5, then no more
}

}  // namespace
}  // namespace elaslam

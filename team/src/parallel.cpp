// SPDX-License-Identifier: Apache-2.0
#include "elaslam/team/parallel.hpp"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace elaslam {

void run_parallel(std::size_t n, int threads, const std::function<void(std::size_t)>& job) {
  std::atomic<std::size_t> next{0};
  std::mutex failed;
  std::exception_ptr failure;  // the first exception of any worker, rethrown after the join
  auto worker = [&] {
    try {
      for (std::size_t i; (i = next++) < n;) job(i);
    } catch (...) {  // escaping a thread would std::terminate the process
      std::lock_guard<std::mutex> lock(failed);
      if (!failure) failure = std::current_exception();
      next = n;
    }
  };
  const auto count = static_cast<int>(std::min<std::size_t>(n, static_cast<std::size_t>(std::max(threads, 1))));
  std::vector<std::thread> pool;
  for (int t = 0; t < count; ++t) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
}

}  // namespace elaslam

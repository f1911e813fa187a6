// SPDX-License-Identifier: Apache-2.0
#include "elaslam/transport/incarnation.hpp"

#include <time.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

#include <sodium.h>

#include "elaslam/common/atomic_file.hpp"

namespace elaslam::transport {
namespace {

constexpr std::int64_t kMaxCount = (std::int64_t{1} << (62 - kIncarnationRandomBits)) - 1;

std::int64_t boot_ms() {
  timespec t{};
  clock_gettime(CLOCK_BOOTTIME, &t);
  return std::int64_t{t.tv_sec} * 1000 + t.tv_nsec / 1000000;
}

std::int64_t with_random_bits(std::int64_t count) {
  if (sodium_init() < 0) std::abort();
  const std::int64_t r = static_cast<std::int64_t>(randombytes_uniform(1u << kIncarnationRandomBits));
  return (count << kIncarnationRandomBits) | r;
}

/// The count in `text` (decimal digits, a newline after), or -1.
std::int64_t parse_count(const std::string& text) {
  std::string t = text;
  if (!t.empty() && t.back() == '\n') t.pop_back();
  if (t.empty() || t.size() > 18 || t.find_first_not_of("0123456789") != std::string::npos) return -1;
  const long long v = std::strtoll(t.c_str(), nullptr, 10);
  return v >= 0 && v < kMaxCount ? v : -1;
}

}  // namespace

std::int64_t start_incarnation(const std::string& state_path, std::string* note) {
  std::string why;
  if (!state_path.empty()) {
    const std::string path = state_path + ".starts";
    std::string text;
    bool missing = false;
    std::int64_t count = 0;
    if (files::read_all(path, &text, &why, &missing, 64)) {
      count = parse_count(text);
      if (count < 0) why = path + " does not hold a start count";
    } else if (missing) {
      why.clear();
    }
    if (count >= 0 && why.empty()) {
      ++count;
      if (files::write_atomic(path, std::to_string(count) + "\n", &why)) {
        if (note != nullptr) *note = "start " + std::to_string(count) + " (" + path + ")";
        return with_random_bits(count);
      }
    }
  }
  const std::int64_t ms = boot_ms();
  if (note != nullptr)
    *note = (why.empty() ? std::string() : why + "; ") + "start count: milliseconds since boot (" + std::to_string(ms) + ")";
  return with_random_bits(ms > 0 ? ms : 1);
}

}  // namespace elaslam::transport

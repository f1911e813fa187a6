// A sender's sequence numbers (1, 2, 3, ...; DESIGN.md section 3: every stream that
// must not silently lose data carries a per-sender seq): how many messages were lost
// before each one. The place for incarnation tracking (a restarted sender starting at
// 1 again) and replay windows when the streams are authenticated.
#pragma once

#include <cstdint>

namespace elaslam::transport {

class SequenceGaps {
 public:
  /// Messages missing between the newest seq so far and `seq` (0 for the first, the
  /// next, a repeat or an older one).
  std::int64_t observe(std::int64_t seq) {
    const std::int64_t gap = (newest_ > 0 && seq > newest_ + 1) ? seq - newest_ - 1 : 0;
    if (seq > newest_) newest_ = seq;
    return gap;
  }
  std::int64_t newest() const { return newest_; }

 private:
  std::int64_t newest_ = 0;
};

}  // namespace elaslam::transport

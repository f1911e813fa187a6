// SPDX-License-Identifier: Apache-2.0
// A sender's sequence numbers (1, 2, 3, ...; docs/design.md section 2: every stream that
// must not silently lose data carries a per-sender seq): how many messages were lost
// before each one. A sender that restarts without its state starts at 1 again with a
// new incarnation (landmark_event_t): the count starts over.
#pragma once

#include <cstdint>

namespace elaslam::transport {

class SequenceGaps {
 public:
  /// Messages missing between the newest seq so far and `seq` (0 for the first, the
  /// next, a repeat or an older one).
  std::int64_t observe(std::int64_t seq, std::int64_t incarnation = 0) {
    if (incarnation != incarnation_) {
      incarnation_ = incarnation;
      newest_ = 0;
    }
    const std::int64_t gap = (newest_ > 0 && seq > newest_ + 1) ? seq - newest_ - 1 : 0;
    if (seq > newest_) newest_ = seq;
    return gap;
  }
  std::int64_t newest() const { return newest_; }

 private:
  std::int64_t newest_ = 0;
  std::int64_t incarnation_ = 0;
};

}  // namespace elaslam::transport

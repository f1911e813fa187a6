// SPDX-License-Identifier: Apache-2.0
// Opening a file that must be a regular file (a configuration, a secret): the steps
// both readers take, each reader phrasing what failed in its own terms.
#pragma once

#include <sys/stat.h>

#include <string>

namespace elaslam::files {

/// A descriptor, closed on every way out.
struct Fd {
  Fd() = default;
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  ~Fd();
  int fd = -1;
};

/// The step of open_regular that failed, or kDone.
enum class OpenStep { kDone, kOpen, kStat, kNotRegular };

/// Opens `path` read-only without waiting on a FIFO or taking a terminal (O_RDONLY |
/// O_CLOEXEC | O_NOCTTY | O_NONBLOCK | `extra_flags`) into *f and fstat's it into *st:
/// kDone when it is a regular file, else the step that failed with its errno in *error
/// (0 for kNotRegular, where *st says what it is).
OpenStep open_regular(const std::string& path, int extra_flags, Fd* f, struct stat* st, int* error);

}  // namespace elaslam::files

// SPDX-License-Identifier: Apache-2.0
// Files that survive a crash at any instant: a reader (the next start) sees the old
// content or the new one, never half of either. Used for the processes' state files.
#pragma once

#include <cstddef>
#include <limits>
#include <string>

namespace elaslam::files {

/// Replace `path` by `data` atomically: a temporary file in the same directory,
/// created by mkstemp (an unpredictable name, O_CREAT | O_EXCL: never an existing
/// file or a symbolic link planted there), written, fsync'ed, renamed over `path`,
/// then the directory fsync'ed. On any failure the temporary file is removed,
/// `path` is left as it was and `why` says what failed (with errno's text).
bool write_atomic(const std::string& path, const std::string& data, std::string* why);

/// No limit on the size read_all accepts.
constexpr std::size_t kNoSizeLimit = std::numeric_limits<std::size_t>::max();

/// The whole content of a regular file. false with `why` when it cannot be read;
/// `missing` (optional) tells whether it does not exist at all. A file of more than
/// `max_bytes` is refused before any of it is read (its size, by fstat on the open
/// file), and so is one that grows past it while being read (`*out` cleared; at most
/// max_bytes + 64 KiB were held). A FIFO or device is refused without blocking in open.
bool read_all(const std::string& path, std::string* out, std::string* why, bool* missing = nullptr,
              std::size_t max_bytes = kNoSizeLimit);

}  // namespace elaslam::files

// SPDX-License-Identifier: Apache-2.0
#include "file_open.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>

namespace elaslam::files {

Fd::~Fd() {
  if (fd >= 0) ::close(fd);
}

OpenStep open_regular(const std::string& path, int extra_flags, Fd* f, struct stat* st, int* error) {
  *error = 0;
  f->fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOCTTY | O_NONBLOCK | extra_flags);
  if (f->fd < 0) {
    *error = errno;
    return OpenStep::kOpen;
  }
  if (::fstat(f->fd, st) != 0) {
    *error = errno;
    return OpenStep::kStat;
  }
  return S_ISREG(st->st_mode) ? OpenStep::kDone : OpenStep::kNotRegular;
}

}  // namespace elaslam::files

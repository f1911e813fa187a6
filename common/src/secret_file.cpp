// SPDX-License-Identifier: Apache-2.0
#include "elaslam/common/secret_file.hpp"

#include "file_open.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace elaslam::files {
namespace {

std::string mode_text(mode_t m) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "%04o", static_cast<unsigned>(m & 07777));
  return buf;
}

}  // namespace

bool in_credentials_directory(const std::string& path) {
  const char* dir = std::getenv("CREDENTIALS_DIRECTORY");
  if (dir == nullptr || *dir != '/') return false;
  std::string d = dir;
  while (d.size() > 1 && d.back() == '/') d.pop_back();
  return path.size() > d.size() + 1 && path.compare(0, d.size(), d) == 0 && path[d.size()] == '/' &&
         path.find('/', d.size() + 1) == std::string::npos;
}

bool read_secret_file(const std::string& path, const std::string& what, std::uint8_t* out, std::size_t capacity,
                      std::size_t* n, bool* more, std::string* why) {
  const std::string where = what + " " + path + ": ";
  *n = 0;
  *more = false;
  struct stat link {};
  if (::lstat(path.c_str(), &link) != 0) {
    *why = where + std::strerror(errno);
    return false;
  }
  if (S_ISLNK(link.st_mode)) {
    *why = where + "is a symbolic link; give the real file (a link could be redirected by whoever can change it)";
    return false;
  }
  Fd f;
  struct stat st {};
  int error = 0;
  if (const OpenStep step = open_regular(path, O_NOFOLLOW, &f, &st, &error); step != OpenStep::kDone) {
    *why = where + (step == OpenStep::kNotRegular ? "is not a regular file" : std::strerror(error));
    return false;
  }
  if (in_credentials_directory(path)) {
    // Passed by systemd (LoadCredential=): a read-only copy that only this service's
    // user can read, made by systemd, whose owner and mode bits (an ACL for a
    // DynamicUser=, root shown as nobody under PrivateUsers=) say nothing more.
  } else if (st.st_uid != ::geteuid() && st.st_uid != 0) {
    *why = where + "is owned by uid " + std::to_string(st.st_uid) + ", neither this user (uid " +
           std::to_string(::geteuid()) + ") nor root";
    return false;
  } else if ((st.st_mode & 077) != 0) {
    *why = where + "has mode " + mode_text(st.st_mode) +
           ": group or others may access it; a secret must be readable by its owner only (chmod 600 " + path + ")";
    return false;
  }
  ssize_t got = 0;
  while (*n < capacity && (got = ::read(f.fd, out + *n, capacity - *n)) > 0) *n += static_cast<std::size_t>(got);
  if (got < 0) {
    *why = where + std::strerror(errno);
    return false;
  }
  if (*n == capacity) {
    std::uint8_t extra = 0;
    *more = ::read(f.fd, &extra, 1) > 0;
  }
  return true;
}

}  // namespace elaslam::files

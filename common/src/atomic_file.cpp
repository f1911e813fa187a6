// SPDX-License-Identifier: Apache-2.0
#include "elaslam/common/atomic_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <vector>

namespace elaslam::files {
namespace {

std::string errno_text(const std::string& what, const std::string& path) {
  return what + " " + path + ": " + std::strerror(errno);
}

std::string directory_of(const std::string& path) {
  const auto slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : path.substr(0, slash);
}

bool write_fully(int fd, const std::string& data) {
  std::size_t done = 0;
  while (done < data.size()) {
    const ssize_t n = ::write(fd, data.data() + done, data.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

}  // namespace

bool write_atomic(const std::string& path, const std::string& data, std::string* why) {
  std::string tmp = path + ".tmp.XXXXXX";
  std::vector<char> name(tmp.begin(), tmp.end());
  name.push_back('\0');
  const int fd = ::mkstemp(name.data());  // O_CREAT | O_EXCL, mode 0600
  if (fd < 0) {
    if (why) *why = errno_text("cannot create a temporary file for", path);
    return false;
  }
  tmp.assign(name.data());
  std::string failed;
  if (!write_fully(fd, data)) {
    failed = errno_text("cannot write", tmp);
  } else if (::fsync(fd) != 0) {
    failed = errno_text("cannot fsync", tmp);
  }
  if (::close(fd) != 0 && failed.empty()) failed = errno_text("cannot close", tmp);
  if (failed.empty() && ::rename(tmp.c_str(), path.c_str()) != 0) failed = errno_text("cannot rename over", path);
  if (!failed.empty()) {
    ::unlink(tmp.c_str());
    if (why) *why = failed;
    return false;
  }
  // The rename itself is durable once the directory is.
  const int dir = ::open(directory_of(path).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir >= 0) {
    ::fsync(dir);
    ::close(dir);
  }
  return true;
}

bool read_all(const std::string& path, std::string* out, std::string* why, bool* missing, std::size_t max_bytes) {
  if (missing) *missing = false;
  // O_NONBLOCK: open(2) of a FIFO would wait for a writer; on a regular file it changes nothing.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) {
    if (missing) *missing = errno == ENOENT;
    if (why) *why = errno_text("cannot open", path);
    return false;
  }
  struct stat st{};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    if (why) *why = path + " is not a regular file";
    return false;
  }
  const auto size = static_cast<std::uint64_t>(st.st_size);
  if (size > max_bytes) {  // before any read: a huge file costs nothing
    ::close(fd);
    if (why) *why = path + " is " + std::to_string(size) + " bytes, more than the " + std::to_string(max_bytes) + " accepted";
    return false;
  }
  out->clear();
  out->reserve(static_cast<std::size_t>(size));
  char buf[65536];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      if (why) *why = errno_text("cannot read", path);
      ::close(fd);
      return false;
    }
    if (n == 0) break;
    out->append(buf, static_cast<std::size_t>(n));
    if (out->size() > max_bytes) {  // it grew while being read
      ::close(fd);
      if (why) *why = path + " grew past the " + std::to_string(max_bytes) + " bytes accepted while being read";
      out->clear();
      return false;
    }
  }
  ::close(fd);
  return true;
}

}  // namespace elaslam::files

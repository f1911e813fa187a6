#include "elaslam/transport/team_key.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include <sodium.h>

namespace elaslam::transport {
namespace {

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

std::string mode_text(mode_t m) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "%04o", static_cast<unsigned>(m & 07777));
  return buf;
}

/// Is `path` a file directly in $CREDENTIALS_DIRECTORY (a systemd service's credentials)?
bool in_credentials_directory(const std::string& path) {
  const char* dir = std::getenv("CREDENTIALS_DIRECTORY");
  if (dir == nullptr || *dir != '/') return false;
  std::string d = dir;
  while (d.size() > 1 && d.back() == '/') d.pop_back();
  return path.size() > d.size() + 1 && path.compare(0, d.size(), d) == 0 && path[d.size()] == '/' &&
         path.find('/', d.size() + 1) == std::string::npos;
}

/// Closes a descriptor and wipes a buffer on every way out.
struct Scratch {
  int fd = -1;
  std::uint8_t buf[160] = {};
  ~Scratch() {
    if (fd >= 0) close(fd);
    sodium_memzero(buf, sizeof buf);
  }
};

}  // namespace

TeamKey::~TeamKey() { sodium_memzero(bytes_.data(), bytes_.size()); }

bool load_team_key(const std::string& path, TeamKey* key, std::string* why) {
  const std::string where = "team key file " + path + ": ";
  struct stat link {};
  if (lstat(path.c_str(), &link) != 0) {
    *why = where + std::strerror(errno);
    return false;
  }
  if (S_ISLNK(link.st_mode)) {
    *why = where + "is a symbolic link; give the real file (a link could be redirected by whoever can change it)";
    return false;
  }
  Scratch s;
  // O_NOFOLLOW: the file checked above cannot be swapped for a link meanwhile;
  // O_NONBLOCK: a FIFO put in its place does not hang the program.
  s.fd = open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  if (s.fd < 0) {
    *why = where + std::strerror(errno);
    return false;
  }
  struct stat st {};
  if (fstat(s.fd, &st) != 0) {
    *why = where + std::strerror(errno);
    return false;
  }
  if (!S_ISREG(st.st_mode)) {
    *why = where + "is not a regular file";
    return false;
  }
  if (in_credentials_directory(path)) {
    // Passed by systemd (LoadCredential=): a read-only copy that only this service's
    // user can read, made by systemd, whose owner and mode bits (an ACL for a
    // DynamicUser=, root shown as nobody under PrivateUsers=) say nothing more.
  } else if (st.st_uid != geteuid() && st.st_uid != 0) {
    *why = where + "is owned by uid " + std::to_string(st.st_uid) + ", neither this user (uid " +
           std::to_string(geteuid()) + ") nor root";
    return false;
  } else if ((st.st_mode & 077) != 0) {
    *why = where + "has mode " + mode_text(st.st_mode) +
           ": group or others may access it; a team key must be readable by its owner only (chmod 600 " + path + ")";
    return false;
  }
  ssize_t n = 0, got = 0;
  while ((got = read(s.fd, s.buf + n, sizeof s.buf - static_cast<std::size_t>(n))) > 0) {
    n += got;
    if (n == static_cast<ssize_t>(sizeof s.buf)) break;
  }
  if (got < 0) {
    *why = where + std::strerror(errno);
    return false;
  }
  std::array<std::uint8_t, TeamKey::kBytes> bytes{};
  const auto wipe = [&] { sodium_memzero(bytes.data(), bytes.size()); };
  std::size_t len = static_cast<std::size_t>(n);
  if (len == TeamKey::kBytes) {
    std::memcpy(bytes.data(), s.buf, len);
  } else {
    if (len == 2 * TeamKey::kBytes + 1 && s.buf[len - 1] == '\n') --len;
    if (len != 2 * TeamKey::kBytes) {
      *why = where + "has " + std::to_string(n) + (n == static_cast<ssize_t>(sizeof s.buf) ? " or more" : "") +
             " bytes; a team key is 32 random bytes, raw or as 64 hexadecimal characters (make one with "
             "tools/make_team_key.sh)";
      return false;
    }
    for (std::size_t i = 0; i < TeamKey::kBytes; ++i) {
      const int hi = hex_value(static_cast<char>(s.buf[2 * i])), lo = hex_value(static_cast<char>(s.buf[2 * i + 1]));
      if (hi < 0 || lo < 0) {
        wipe();
        *why = where + "has 64 characters that are not all hexadecimal digits";
        return false;
      }
      bytes[i] = static_cast<std::uint8_t>(hi * 16 + lo);
    }
  }
  if (sodium_is_zero(bytes.data(), bytes.size())) {
    *why = where + "is all zeros: not a key (make one with tools/make_team_key.sh)";
    return false;
  }
  *key = TeamKey(bytes);
  wipe();
  return true;
}

}  // namespace elaslam::transport

// SPDX-License-Identifier: Apache-2.0
#include "elaslam/viewer/access_token.hpp"

#include <fcntl.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "elaslam/common/secret_file.hpp"
#include "elaslam/viewer/http_guard.hpp"

namespace elaslam::viewer {
namespace {

bool is_hex(char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F'); }

/// Wipes the bytes read on every way out.
struct Scratch {
  std::array<std::uint8_t, kTokenMaxHex + 2> buf{};
  ~Scratch() {
    volatile std::uint8_t* p = buf.data();
    for (std::size_t i = 0; i < buf.size(); ++i) p[i] = 0;
  }
};

/// The token's text in s.buf[0, n) (a final newline dropped); "" when it is one.
std::string check_text(const char* text, std::size_t* n, bool more) {
  if (*n > 0 && text[*n - 1] == '\n') --*n;
  if (more || *n < kTokenMinHex || *n > kTokenMaxHex || *n % 2 != 0) {
    return "has " + std::string(more ? "too many" : std::to_string(*n)) +
           " characters; a token is 32 to 128 random bytes as 64 to 256 hexadecimal digits (make one with "
           "viewer --make-token FILE)";
  }
  bool zero = true;
  for (std::size_t i = 0; i < *n; ++i) {
    if (!is_hex(text[i])) return "holds a character that is not a hexadecimal digit";
    zero = zero && text[i] == '0';
  }
  if (zero) return "is all zeros: not a token (make one with viewer --make-token FILE)";
  return "";
}

}  // namespace

bool load_access_token(const std::string& path, std::string* token, std::string* why) {
  const std::string where = "token file " + path + ": ";
  Scratch s;
  std::size_t n = 0;
  bool more = false;
  // The checks of every secret file (common/secret_file.hpp): a regular file, not a
  // link, the owner's only, a systemd credential exempt; O_NONBLOCK: a FIFO put in
  // its place does not hang the viewer.
  if (!files::read_secret_file(path, "token file", s.buf.data(), s.buf.size(), &n, &more, why)) return false;
  const char* text = reinterpret_cast<const char*>(s.buf.data());
  // A full buffer: more than the longest token and its newline.
  if (std::string bad = check_text(text, &n, more || n == s.buf.size()); !bad.empty()) {
    *why = where + bad;
    return false;
  }
  token->assign(text, n);
  return true;
}

bool make_access_token(const std::string& path, std::string* why) {
  const std::string where = "cannot make the token file " + path + ": ";
  std::array<unsigned char, 32> bytes{};
  if (::getrandom(bytes.data(), bytes.size(), 0) != static_cast<ssize_t>(bytes.size())) {
    *why = where + "no random bytes from the kernel (" + std::strerror(errno) + ")";
    return false;
  }
  std::string text;
  static const char kDigits[] = "0123456789abcdef";
  for (const unsigned char b : bytes) {
    text += kDigits[b >> 4];
    text += kDigits[b & 15];
  }
  text += '\n';
  bytes.fill(0);
  // O_EXCL with O_CREAT: fails on any existing name, a symbolic link included (a
  // dangling one too), and never follows one.
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
  if (fd < 0) {
    *why = where + std::strerror(errno) +
           (errno == EEXIST ? " (a token file is never overwritten: remove it first to make a new one)" : "");
    return false;
  }
  const bool ok = ::fchmod(fd, 0600) == 0 && ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  const int err = errno;
  std::fill(text.begin(), text.end(), '\0');
  if (::close(fd) != 0 || !ok) {
    ::unlink(path.c_str());
    *why = where + std::strerror(ok ? errno : err);
    return false;
  }
  return true;
}

bool tokens_equal(std::string_view expected, std::string_view given) {
  if (expected.empty()) return false;
  // Every byte of `given` is compared, against the expected one at its place (or a
  // wrapped one past its end): no early exit, no branch on the secret.
  volatile unsigned char diff = expected.size() == given.size() ? 0 : 1;
  for (std::size_t i = 0; i < given.size(); ++i) {
    diff = static_cast<unsigned char>(diff | (static_cast<unsigned char>(given[i]) ^
                                              static_cast<unsigned char>(expected[i % expected.size()])));
  }
  return diff == 0;
}

std::string_view bearer_token(std::string_view authorization) {
  constexpr std::string_view kScheme = "bearer ";
  if (authorization.size() <= kScheme.size()) return {};
  for (std::size_t i = 0; i < kScheme.size(); ++i) {
    const char c = authorization[i];
    if ((c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c) != kScheme[i]) return {};
  }
  std::string_view t = authorization.substr(kScheme.size());
  while (!t.empty() && t.front() == ' ') t.remove_prefix(1);
  while (!t.empty() && t.back() == ' ') t.remove_suffix(1);
  return t;
}

bool AccessPolicy::allows(std::string_view peer, std::string_view authorization, std::string_view token_param) const {
  if (is_loopback_address(peer)) return true;
  if (token_.empty()) return false;
  const std::string_view bearer = bearer_token(authorization);
  // Both looked at whatever the first says: the time does not tell which one was right.
  const bool by_header = tokens_equal(token_, bearer);
  const bool by_param = tokens_equal(token_, token_param);
  return by_header || by_param;
}

}  // namespace elaslam::viewer

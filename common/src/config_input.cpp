// SPDX-License-Identifier: Apache-2.0
#include "config_input.hpp"

#include "file_open.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <map>

#include "elaslam/common/config.hpp"

namespace elaslam::config::input {
namespace {

const std::string kLimit = "the limit of " + std::to_string(kMaxFileBytes) + " bytes (1 MiB) for a configuration file";

std::string kind_of(const struct stat& st) {
  if (S_ISDIR(st.st_mode)) return "a directory";
  if (S_ISFIFO(st.st_mode)) return "a FIFO";
  if (S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode)) return "a device";
  if (S_ISSOCK(st.st_mode)) return "a socket";
  return "not a file";
}

/// "line L, column C" of byte `pos` of `text` (both from 1).
std::string where(const std::string& text, std::size_t pos) {
  std::size_t line = 1, column = 1;
  for (std::size_t i = 0; i < pos; ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(column);
}

/// Length of the UTF-8 sequence at text[i], 0 when it is not one (overlong forms,
/// surrogates and code points above U+10FFFF are not: RFC 3629).
std::size_t utf8_length(const std::string& text, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char c = byte(i);
  if (c < 0x80) return 1;
  std::size_t n = 0;
  unsigned char lo = 0x80, hi = 0xBF;  // the allowed range of the second byte
  if (c >= 0xC2 && c <= 0xDF) {
    n = 2;
  } else if (c >= 0xE0 && c <= 0xEF) {
    n = 3;
    if (c == 0xE0) lo = 0xA0;  // overlong
    if (c == 0xED) hi = 0x9F;  // surrogates
  } else if (c >= 0xF0 && c <= 0xF4) {
    n = 4;
    if (c == 0xF0) lo = 0x90;  // overlong
    if (c == 0xF4) hi = 0x8F;  // above U+10FFFF
  } else {
    return 0;
  }
  if (i + n > text.size()) return 0;
  if (byte(i + 1) < lo || byte(i + 1) > hi) return 0;
  for (std::size_t k = 2; k < n; ++k)
    if (byte(i + k) < 0x80 || byte(i + k) > 0xBF) return 0;
  return n;
}

std::string kind_of(const YAML::Node& n) {
  if (n.IsSequence()) return "a list";
  if (n.IsMap()) return "a map";
  if (n.IsNull()) return "null";
  return "a scalar";
}

std::string line_of(const YAML::Node& n) {
  const YAML::Mark m = n.Mark();
  if (m.is_null()) return "";
  return " at line " + std::to_string(m.line + 1) + ", column " + std::to_string(m.column + 1);
}

/// The depth-first walk of structure_problems: bounded in depth and in nodes visited.
class Walk {
 public:
  explicit Walk(std::vector<std::string>* problems) : problems_(problems) {}

  void node(const YAML::Node& n, const std::string& path, int depth) {
    if (stopped_) return;
    if (++nodes_ > kMaxNodes) {
      stop("more than " + std::to_string(kMaxNodes) + " values once aliases are expanded: not a configuration");
      return;
    }
    if (depth > kMaxDepth) {
      stop(label(path) + "nested deeper than " + std::to_string(kMaxDepth) + " levels: not a configuration");
      return;
    }
    if (n.IsMap()) {
      map(n, path, depth);
    } else if (n.IsSequence()) {
      std::size_t i = 0;
      for (const auto& item : n) node(item, path + "[" + std::to_string(i++) + "]", depth + 1);
    }
  }

 private:
  static std::string label(const std::string& path) { return path.empty() ? "" : path + ": "; }

  void map(const YAML::Node& n, const std::string& path, int depth) {
    std::map<std::string, YAML::Node> seen;
    for (const auto& kv : n) {
      if (stopped_) return;
      if (!kv.first.IsScalar()) {
        problems_->push_back(label(path) + "a non-scalar key (" + kind_of(kv.first) + ")" + line_of(kv.first) +
                             ": keys are plain names");
        continue;
      }
      const std::string& key = kv.first.Scalar();
      const std::string child = path.empty() ? key : path + "." + key;
      const auto [first, fresh] = seen.emplace(key, kv.first);
      if (!fresh)
        problems_->push_back(child + ": duplicate key (lines " + line_number(first->second) + " and " +
                             line_number(kv.first) + "): YAML would keep only one of them; remove the other");
      node(kv.second, child, depth + 1);
    }
  }

  static std::string line_number(const YAML::Node& key) {
    const YAML::Mark m = key.Mark();
    return m.is_null() ? "?" : std::to_string(m.line + 1);
  }

  void stop(const std::string& what) {
    problems_->push_back(what);
    stopped_ = true;
  }

  std::vector<std::string>* problems_;
  std::size_t nodes_ = 0;
  bool stopped_ = false;
};

}  // namespace

bool read_file(const std::string& path, std::string* text, std::string* why) {
  files::Fd f;
  struct stat st {};
  int e = 0;
  switch (files::open_regular(path, 0, &f, &st, &e)) {
    case files::OpenStep::kDone: break;
    case files::OpenStep::kOpen:
      *why = std::string("cannot open the file: ") + (e == ENOENT ? "no such file" : std::strerror(e));
      return false;
    case files::OpenStep::kStat: *why = std::string("cannot read the file: ") + std::strerror(e); return false;
    case files::OpenStep::kNotRegular:
      *why = "not a regular file (" + kind_of(st) + "): a configuration is a YAML file";
      return false;
  }
  if (static_cast<std::size_t>(st.st_size) > kMaxFileBytes) {
    *why = "the file has " + std::to_string(st.st_size) + " bytes, larger than " + kLimit;
    return false;
  }
  text->clear();
  char buf[16384];
  for (;;) {
    const ssize_t n = ::read(f.fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      *why = std::string("cannot read the file: ") + std::strerror(errno);
      return false;
    }
    if (n == 0) return true;
    if (text->size() + static_cast<std::size_t>(n) > kMaxFileBytes) {  // it grew while read (or lies about its size)
      *why = "the file is larger than " + kLimit;
      return false;
    }
    text->append(buf, static_cast<std::size_t>(n));
  }
}

std::vector<std::string> text_problems(const std::string& text) {
  std::vector<std::string> out;
  const std::size_t nul = text.find('\0');
  if (nul != std::string::npos)
    out.push_back("a NUL byte at " + where(text, nul) + ": a configuration is text, not binary data");
  for (std::size_t i = 0; i < text.size();) {
    const std::size_t n = utf8_length(text, i);
    if (n == 0) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "0x%02x", static_cast<unsigned>(static_cast<unsigned char>(text[i])));
      out.push_back("not valid UTF-8 at " + where(text, i) + " (byte " + hex + "): a configuration is UTF-8 text");
      break;
    }
    i += n;
  }
  // Control characters other than tab, line feed and carriage return (C0, DEL) are
  // not YAML (its c-printable set), and yaml-cpp 0.7 never returns from some of
  // them: 738 bytes of a config with a run of 0x03 in a comment kept it allocating for
  // over a minute (found by fuzz_config). Refused before the parser sees them.
  for (std::size_t i = 0; i < text.size(); ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == 0 || c == '\t' || c == '\n' || c == '\r' || (c >= 0x20 && c != 0x7f)) continue;
    char hex[8];
    std::snprintf(hex, sizeof hex, "0x%02x", static_cast<unsigned>(c));
    out.push_back("a control character (byte " + std::string(hex) + ") at " + where(text, i) +
                  ": not allowed in YAML; a configuration is text");
    break;
  }
  return out;
}

std::vector<std::string> structure_problems(const YAML::Node& root) {
  std::vector<std::string> out;
  Walk(&out).node(root, "", 0);
  return out;
}

}  // namespace elaslam::config::input

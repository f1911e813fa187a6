// SPDX-License-Identifier: Apache-2.0
#include "elaslam/common/log.hpp"

#include <sys/stat.h>
#include <systemd/sd-daemon.h>  // SD_ERR, SD_WARNING, ... (macros only: nothing to link)

#include <cinttypes>
#include <cstdarg>
#include <cstdlib>
#include <cstring>

namespace elaslam::log {

bool is_journal(std::FILE* f) {
  const char* stream = std::getenv("JOURNAL_STREAM");
  if (f == nullptr || stream == nullptr) return false;
  std::uintmax_t dev = 0, ino = 0;
  char tail = 0;
  if (std::sscanf(stream, "%ju:%ju%c", &dev, &ino, &tail) != 2) return false;
  struct stat st {};
  const int fd = fileno(f);
  return fd >= 0 && fstat(fd, &st) == 0 && static_cast<std::uintmax_t>(st.st_dev) == dev &&
         static_cast<std::uintmax_t>(st.st_ino) == ino;
}

const char* prefix(std::FILE* f, Priority p) {
  if (!is_journal(f)) return "";
  switch (p) {
    case Priority::kErr: return SD_ERR;
    case Priority::kWarning: return SD_WARNING;
    case Priority::kNotice: return SD_NOTICE;
    case Priority::kInfo: return SD_INFO;
    case Priority::kDebug: return SD_DEBUG;
  }
  return "";
}

void print(std::FILE* f, Priority p, const char* format, ...) {
  if (f == nullptr) return;
  char text[4096];
  va_list args;
  va_start(args, format);
  const int n = std::vsnprintf(text, sizeof text, format, args);
  va_end(args);
  if (n < 0) return;
  const char* pre = prefix(f, p);
  if (pre[0] == '\0') {
    std::fputs(text, f);
    return;
  }
  // Every line its prefix: journald reads the priority per line.
  for (const char* line = text; *line != '\0';) {
    const char* end = std::strchr(line, '\n');
    const std::size_t len = end ? static_cast<std::size_t>(end - line + 1) : std::strlen(line);
    std::fputs(pre, f);
    std::fwrite(line, 1, len, f);
    line += len;
  }
}

}  // namespace elaslam::log

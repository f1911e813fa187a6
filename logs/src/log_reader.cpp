// SPDX-License-Identifier: Apache-2.0
#include "elaslam/logs/log_reader.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace elaslam {
namespace {

constexpr unsigned char kLcmMagic[4] = {0xED, 0xA1, 0xDA, 0x01};  // every LCM log event starts with it
constexpr std::int64_t kEventHeaderBytes = 4 + 8 + 8 + 4 + 4;     // magic, eventnum, timestamp, lengths
constexpr std::int32_t kMaxChannelBytes = 1000;                    // liblcm's own sanity bound

std::uint64_t be(const unsigned char* p, int n) {
  std::uint64_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 8) | p[i];
  return v;
}

// Throws unless `path` is a readable file that is empty or starts with an LCM event.
std::int64_t check_log_file(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st)) throw std::runtime_error("cannot open the log " + path + ": no such file");
  if (fs::is_directory(st)) throw std::runtime_error("cannot open the log " + path + ": it is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open the log " + path + " for reading (permissions?)");
  const auto size = static_cast<std::int64_t>(fs::file_size(path, ec));
  if (ec) throw std::runtime_error("cannot read the size of the log " + path + ": " + ec.message());
  unsigned char head[4] = {0, 0, 0, 0};
  in.read(reinterpret_cast<char*>(head), 4);
  const auto got = in.gcount();
  if (got == 0) return size;  // an empty log: a recorder that saw no message
  if (got < 4 || !std::equal(head, head + 4, kLcmMagic)) {
    char first[64];
    std::snprintf(first, sizeof first, "%02x %02x %02x %02x", head[0], head[1], head[2], head[3]);
    throw std::runtime_error(path + " is not an LCM log: an LCM log starts with the event marker ed a1 da 01, this "
                             "file starts with " + std::string(first, static_cast<std::size_t>(3 * got - 1)));
  }
  return size;
}

}  // namespace

LogReader::LogReader(const std::string& path) : size_(check_log_file(path)) {
  f_ = std::fopen(path.c_str(), "rb");
  if (!f_) throw std::runtime_error("cannot open the log " + path + " for reading");
}

LogReader::~LogReader() {
  if (f_) std::fclose(f_);
}

bool LogReader::next(LogEvent* ev) {
  if (pos_ >= size_) return false;
  std::int64_t at = pos_;
  while (!event_at(at, ev)) {
    at = find_magic(at + 1);
    if (at < 0) return false;
  }
  skipped_ += at - pos_;
  pos_ = at + kEventHeaderBytes + static_cast<std::int64_t>(ev->channel.size()) +
         static_cast<std::int64_t>(ev->data.size());
  return true;
}

// A whole, plausible event at `off` (read into *ev), else false.
bool LogReader::event_at(std::int64_t off, LogEvent* ev) {
  unsigned char h[kEventHeaderBytes];
  if (off + kEventHeaderBytes > size_ || fseeko(f_, off, SEEK_SET) != 0 || std::fread(h, 1, sizeof h, f_) != sizeof h)
    return false;
  if (!std::equal(h, h + 4, kLcmMagic)) return false;
  const auto channel_len = static_cast<std::int32_t>(be(h + 20, 4));
  const auto data_len = static_cast<std::int32_t>(be(h + 24, 4));
  if (channel_len <= 0 || channel_len >= kMaxChannelBytes || data_len < 0 ||
      off + kEventHeaderBytes + channel_len + data_len > size_)
    return false;
  ev->timestamp = static_cast<std::int64_t>(be(h + 12, 8));
  ev->channel.resize(static_cast<std::size_t>(channel_len));
  ev->data.resize(static_cast<std::size_t>(data_len));
  return std::fread(ev->channel.data(), 1, ev->channel.size(), f_) == ev->channel.size() &&
         std::fread(ev->data.data(), 1, ev->data.size(), f_) == ev->data.size();
}

// Offset of the next event marker at or after `from`, -1 when none.
std::int64_t LogReader::find_magic(std::int64_t from) {
  if (from >= size_ || fseeko(f_, from, SEEK_SET) != 0) return -1;
  std::uint32_t window = 0;
  const std::uint32_t magic = 0xEDA1DA01u;
  for (std::int64_t off = from; off < size_; ++off) {
    const int c = std::fgetc(f_);
    if (c == EOF) return -1;
    window = (window << 8) | static_cast<std::uint32_t>(c);
    if (off - from >= 3 && window == magic) return off - 3;
  }
  return -1;
}

}  // namespace elaslam

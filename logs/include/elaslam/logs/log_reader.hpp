// SPDX-License-Identifier: Apache-2.0
// Reading a recorded LCM log (lcm-logger's format) robustly: every whole event is
// returned, bytes between events that are not one are skipped and counted, and a
// truncated or corrupt tail ends the read. Used by log_info and evaluate.
//
// The LCM log format (lcm-proj.github.io/lcm "Log file format"): events back to back,
// each a big-endian header {0xEDA1DA01, int64 eventnum, int64 timestamp [us], int32
// channel length, int32 data length}, the channel name, the data. Read here rather
// than with lcm::LogFile because liblcm 1.3.1 drops the event *before* any stray
// bytes, stops there and prints to stderr.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace elaslam {

struct LogEvent {
  std::int64_t timestamp = 0;  // [us] receive time (the recorder's clock)
  std::string channel;
  std::vector<std::uint8_t> data;
};

class LogReader {
 public:
  /// Throws std::runtime_error unless `path` is a readable file that is empty (a log
  /// of no events) or starts with an LCM event, naming what is wrong.
  explicit LogReader(const std::string& path);
  ~LogReader();
  LogReader(const LogReader&) = delete;
  LogReader& operator=(const LogReader&) = delete;

  /// The next whole event; false at the end of the file or when the rest of it holds
  /// no whole event (a truncated or corrupt tail).
  bool next(LogEvent* ev);

  std::int64_t size() const { return size_; }                   // [bytes] of the file
  std::int64_t end_of_last_event() const { return pos_; }       // [bytes] where the read stands
  std::int64_t skipped() const { return skipped_; }             // [bytes] between events, not an event
  bool complete() const { return pos_ >= size_; }               // the read reached the end of the file

 private:
  bool event_at(std::int64_t off, LogEvent* ev);
  std::int64_t find_magic(std::int64_t from);

  std::FILE* f_ = nullptr;
  std::int64_t size_ = 0;
  std::int64_t pos_ = 0;      // end of the last event read
  std::int64_t skipped_ = 0;  // bytes between events that were not an event
};

}  // namespace elaslam

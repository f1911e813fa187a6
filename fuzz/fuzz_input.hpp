// SPDX-License-Identifier: Apache-2.0
// Shared by the libFuzzer targets (fuzz/): the fuzzer's bytes as a sequence of
// messages, each for one of a target's channels:
//   [channel selector: 1 byte][length: 2 bytes, little-endian][payload: length bytes]
// repeated; a selector picks channels[selector % n]; a length beyond the rest of the
// input takes the rest. So one input is a burst of messages a node receives in order,
// as over the wire (fuzz/make_corpus.py writes real recordings in this form).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace elaslam::fuzz {

struct Record {
  std::size_t channel;         // index into the target's channel list
  const std::uint8_t* data;
  std::size_t size;
};

/// Calls fn(record) for each record of `data`; at most `max_records` (a bound on one
/// input's cost).
template <class Fn>
void for_each_record(const std::uint8_t* data, std::size_t size, std::size_t num_channels, Fn fn,
                     std::size_t max_records = 4096) {
  std::size_t at = 0, n = 0;
  while (at < size && n < max_records) {
    const std::size_t channel = data[at] % num_channels;
    std::size_t len = 0;
    if (at + 3 <= size) len = static_cast<std::size_t>(data[at + 1]) | (static_cast<std::size_t>(data[at + 2]) << 8);
    at = at + 3 <= size ? at + 3 : size;
    if (len > size - at) len = size - at;
    fn(Record{channel, data + at, len});
    at += len;
    ++n;
  }
}

/// The project's source tree (for config/*.yaml): ELASLAM_SOURCE_DIR, set by CMake.
inline std::string source_dir() { return ELASLAM_SOURCE_DIR; }

}  // namespace elaslam::fuzz

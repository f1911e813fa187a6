// SPDX-License-Identifier: Apache-2.0
// mrclam_import's recording: the frames of a FrameSource as the system's messages, in
// the order a log holds them (RUN_INFO about once a second of log time before its
// frame's messages, as the simulator does; GROUND_TRUTH; SENSOR_<id> per robot), each
// encoded and handed to a writer (the program's LCM log file); and its summary table.
#pragma once

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <string>

#include "elaslam/dataset/mrclam.hpp"
#include "elaslam/run_info_t.hpp"

namespace elaslam::mrclam {

/// RUN_INFO of an imported recording: no seed, dynamism or speed (real data); the
/// effective config with the dataset section's values as run (`o`: the command line's
/// overrides recorded).
run_info_t import_run_info(const FrameSource& src, const Options& o, const std::string& dataset_dir,
                           const std::string& effective_yaml);

/// Writes one encoded message of the log: false when it could not.
using LogWriter = std::function<bool(const std::string& channel, std::int64_t utime, const std::uint8_t* data,
                                     int size)>;

/// Every frame through `write` (RUN_INFO every max(1, floor(rate_hz)) frames, stamped
/// with the frame's time and frame k - 1). False at the first message that could not
/// be encoded or written; *failed_frame says its frame.
bool write_import_log(const FrameSource& src, const run_info_t& info, double rate_hz, const LogWriter& write,
                      int* failed_frame);

/// The per-robot table of the source's statistics and the frames' line, as
/// mrclam_import prints them.
void print_import_stats(std::ostream& os, const Stats& s, double rate_hz);

}  // namespace elaslam::mrclam

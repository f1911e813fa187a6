// SPDX-License-Identifier: Apache-2.0
// The command-line options that override a recording's dataset: section (the
// window and the robots), for the programs that read one (mrclam_import,
// run_dataset). Header-only: the programs link CLI11, the library does not.
#pragma once

#include <optional>
#include <string>
#include <utility>

#include <CLI/CLI.hpp>

#include "elaslam/common/cli.hpp"
#include "elaslam/dataset/mrclam.hpp"

namespace elaslam::mrclam {

struct DatasetOverrides {
  // Set only when given on the command line; the parser's callbacks fill them, so
  // nothing here refers to the parser once it is gone.
  std::optional<double> rate, start, duration;
  std::string robots;  // e.g. "1,2,3,4,5"; empty when not given
};

/// --rate, --start, --duration and --robots, each checked against mrclam::limits.
inline void add_options(CLI::App& app, DatasetOverrides* d) {
  app.add_option_function<double>("--rate", [d](double v) { d->rate = v; },
                                  "frames per second (default dataset.rate_hz)")
      ->check(cli::range(limits::kRateMinHz, limits::kRateMaxHz));
  app.add_option_function<double>("--start", [d](double v) { d->start = v; },
                                  "[s] first frame after the common start (default dataset.start_s)")
      ->check(cli::range(0.0, limits::kStartMaxS));
  app.add_option_function<double>("--duration", [d](double v) { d->duration = v; },
                                  "[s] length, 0 = to the common end (default dataset.duration_s)")
      ->check(cli::range(0.0, limits::kDurationMaxS));
  app.add_option("--robots", d->robots, "robots to use, e.g. 1,2,3,4,5 (default dataset.robots)");
}

/// The overrides given, into `o` (after parsing); false with the reason in `why`
/// when --robots is not a valid list (then `o` is unchanged).
inline bool apply(const DatasetOverrides& d, Options* o, std::string* why) {
  Options out = *o;
  if (!d.robots.empty() && !parse_robot_list(d.robots, &out.robots, why)) return false;
  if (d.rate) out.rate_hz = *d.rate;
  if (d.start) out.start_s = *d.start;
  if (d.duration) out.duration_s = *d.duration;
  *o = std::move(out);
  return true;
}

}  // namespace elaslam::mrclam

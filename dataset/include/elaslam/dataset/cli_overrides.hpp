// SPDX-License-Identifier: Apache-2.0
// The command-line options that override a recording's dataset: section (the
// window and the robots), for the programs that read one (mrclam_import,
// run_dataset). Header-only: the programs link CLI11, the library does not.
#pragma once

#include <string>
#include <utility>

#include <CLI/CLI.hpp>

#include "elaslam/common/cli.hpp"
#include "elaslam/dataset/mrclam.hpp"

namespace elaslam::mrclam {

struct DatasetOverrides {
  double rate = 0.0, start = 0.0, duration = 0.0;
  std::string robots;  // e.g. "1,2,3,4,5"
  // Set by add_options; an option given on the command line overrides the config.
  CLI::Option* rate_option = nullptr;
  CLI::Option* start_option = nullptr;
  CLI::Option* duration_option = nullptr;
};

/// --rate, --start, --duration and --robots, each checked against mrclam::limits.
inline void add_options(CLI::App& app, DatasetOverrides* d) {
  d->rate_option = app.add_option("--rate", d->rate, "frames per second (default dataset.rate_hz)")
                       ->check(cli::range(limits::kRateMinHz, limits::kRateMaxHz));
  d->start_option =
      app.add_option("--start", d->start, "[s] first frame after the common start (default dataset.start_s)")
          ->check(cli::range(0.0, limits::kStartMaxS));
  d->duration_option =
      app.add_option("--duration", d->duration, "[s] length, 0 = to the common end (default dataset.duration_s)")
          ->check(cli::range(0.0, limits::kDurationMaxS));
  app.add_option("--robots", d->robots, "robots to use, e.g. 1,2,3,4,5 (default dataset.robots)");
}

/// The overrides given, into `o` (after parsing); false with the reason in `why`
/// when --robots is not a valid list (then `o` is unchanged).
inline bool apply(const DatasetOverrides& d, Options* o, std::string* why) {
  Options out = *o;
  if (!d.robots.empty() && !parse_robot_list(d.robots, &out.robots, why)) return false;
  if (d.rate_option != nullptr && d.rate_option->count() > 0) out.rate_hz = d.rate;
  if (d.start_option != nullptr && d.start_option->count() > 0) out.start_s = d.start;
  if (d.duration_option != nullptr && d.duration_option->count() > 0) out.duration_s = d.duration;
  *o = std::move(out);
  return true;
}

}  // namespace elaslam::mrclam

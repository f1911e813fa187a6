// SPDX-License-Identifier: Apache-2.0
// mrclam_stats' report: the noise of a recording against Vicon (noise_stats.hpp)
// as the text tables it prints and the JSON it writes (docs/data_dictionary.md).
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "elaslam/dataset/mrclam.hpp"

namespace elaslam::mrclam {

struct StatsOptions {
  std::string dataset_dir;           // as given: the JSON's "dataset"
  std::vector<int> ids;              // the robots, in order
  double rate = 10.0;                // frames for the odometry, detection and calibration [Hz]
  double calibration_window_s = 5.0; // fit_odometry's windows [s]
  double detect_range = 3.5, detect_half_deg = 17.0;  // in view for the detection statistics [m], [deg]
  std::string config_path;           // empty: no frame residuals, calibration frames imported without a config
  Options frame_options;             // the config's dataset section
};

/// Every section in order (sensor residuals per robot and overall, range scale and
/// odometry lag, the frames' residuals when there is a config, detection, odometry
/// noise and the suggested values, the odometer calibration), printed to `out`;
/// returns the same numbers as JSON. Throws what FrameSource throws on bad options.
nlohmann::json noise_report(const Dataset& d, const StatsOptions& o, std::FILE* out);

}  // namespace elaslam::mrclam

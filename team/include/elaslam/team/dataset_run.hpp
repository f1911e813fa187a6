// SPDX-License-Identifier: Apache-2.0
// The team on recorded data (UTIAS MRCLAM) instead of the simulator: the same
// in-process run as run_scenario, fed by the dataset importer's frames.
// Config: config/mrclam.yaml (`dataset:`, `robot:`, `main:` sections).
#pragma once

#include <string>
#include <vector>

#include "elaslam/dataset/mrclam.hpp"
#include "elaslam/team/team_run.hpp"

namespace elaslam {

struct DatasetConfig {
  mrclam::Options dataset;
  RobotOptions robot;
  GlobalMapOptions main;
  std::string effective_yaml;
  std::string source;
};

/// Throws config::ConfigError listing every problem (also cross-section ones: the
/// filter must accept every subject id of the dataset).
DatasetConfig load_dataset_config(const std::string& path);

/// mrclam::FrameSource as the team's frame provider.
class DatasetFrames : public FrameProvider {
 public:
  explicit DatasetFrames(const mrclam::FrameSource& src) : src_(src) {}
  int num_frames() const override { return src_.num_frames(); }
  int num_robots() const override { return static_cast<int>(src_.robot_ids().size()); }
  int robot_id(int i) const override { return src_.robot_ids()[static_cast<std::size_t>(i)]; }
  void frame(int k, ground_truth_t* gt, std::vector<sensor_frame_t>* sensors) override {
    src_.frame(k, gt, sensors);
  }

 private:
  const mrclam::FrameSource& src_;
};

/// Dead reckoning (the odometer readings) against ground truth, per robot of the
/// source: position error mean and RMS over the frames [m].
struct DeadReckoning {
  int id = 0;
  double error_mean = 0.0, error_rms = 0.0;
};
std::vector<DeadReckoning> dead_reckoning(const mrclam::FrameSource& src);

}  // namespace elaslam

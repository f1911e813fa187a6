// SPDX-License-Identifier: Apache-2.0
#include "elaslam/team/dataset_run.hpp"

#include <cmath>

#include "elaslam/team/team_config.hpp"

namespace elaslam {

DatasetConfig load_dataset_config(const std::string& path) {
  config::Document doc = config::Document::from_file(path);
  DatasetConfig c;
  doc.section("dataset", [&](config::Reader& r) { mrclam::parse(r, &c.dataset); });
  read_robot_and_main(doc, &c.robot, &c.main);
  // Subjects 1..20 are the ids on the wire (robots 1-5, landmarks 6-20).
  constexpr int kMaxSubject = 20;
  if (c.robot.ekf.max_landmark_id <= kMaxSubject)
    throw config::ConfigError(path, {"robot.filter.max_landmark_id must exceed 20 (MRCLAM subject ids are 1-20)"});
  if (c.main.max_landmark_id <= kMaxSubject)
    throw config::ConfigError(path, {"main.max_landmark_id must exceed 20 (MRCLAM subject ids are 1-20)"});
  c.effective_yaml = doc.effective_yaml();
  c.source = path;
  return c;
}

std::vector<DeadReckoning> dead_reckoning(const mrclam::FrameSource& src) {
  std::vector<DeadReckoning> out;
  for (std::size_t i = 0; i < src.robot_ids().size(); ++i) {
    DeadReckoning d;
    d.id = src.robot_ids()[i];
    double sum = 0.0, sq = 0.0;
    for (int k = 0; k < src.num_frames(); ++k) {
      const double e = (src.odometer(static_cast<int>(i), k).translation() -
                        src.true_pose(static_cast<int>(i), k).translation()).norm();
      sum += e;
      sq += e * e;
    }
    const int n = src.num_frames();
    d.error_mean = n > 0 ? sum / n : 0.0;
    d.error_rms = n > 0 ? std::sqrt(sq / n) : 0.0;
    out.push_back(d);
  }
  return out;
}

}  // namespace elaslam

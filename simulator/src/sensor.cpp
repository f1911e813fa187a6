// SPDX-License-Identifier: Apache-2.0
#include "elaslam/common/contract.hpp"
#include "elaslam/simulator/sensor.hpp"

#include <algorithm>
#include <cmath>

namespace elaslam::sim {

// Smallest range ever reported [m]: a noisy range is clamped here so that
// range > 0 always holds (sensor_frame_t). Reached only when a landmark at about
// min_range_m gets a negative noise draw larger than min_range_m (2 sigma with the
// defaults 0.1 m and 0.05 m), which is rare; it biases nothing else.
constexpr double kRangeFloorM = 1e-3;

Observation true_observation(const Pose2& T_WB, const Eigen::Vector2d& p_LinW, std::int32_t id) {
  const Eigen::Vector2d p_LinB = transform_to(T_WB, p_LinW);
  Observation z;
  z.landmark_id = id;
  z.range_m = p_LinB.norm();
  z.bearing_rad = std::atan2(p_LinB.y(), p_LinB.x());
  return z;
}

Sensor::Sensor(const SensorOptions& options, int num_landmarks, Rng noise, Rng detection)
    : options_(options), noise_(noise), detection_(detection) {
  candidates_.reserve(static_cast<std::size_t>(std::max(num_landmarks, 0)));
}

int Sensor::observe(const Pose2& T_WB, const std::vector<Eigen::Vector2d>& p_LinW, ObservationArray* out,
                    int* truncated) {
  const double sigma_b = deg2rad(options_.bearing_sigma_deg);
  candidates_.clear();
  for (std::size_t i = 0; i < p_LinW.size(); ++i) {
    // Draw first, always (see the header): 2 normals + 1 uniform per landmark.
    const double n_r = noise_.normal(), n_b = noise_.normal();
    const double u_detect = detection_.uniform();
    const Observation z = true_observation(T_WB, p_LinW[i], static_cast<std::int32_t>(i));
    if (z.range_m > options_.max_range_m() || z.range_m < options_.min_range_m) continue;
    if (u_detect >= options_.detection_probability) continue;
    Candidate c{z.range_m, z};
    c.obs.range_m = std::max(z.range_m + options_.range_sigma_m * n_r, kRangeFloorM);
    c.obs.bearing_rad = wrap_angle(z.bearing_rad + sigma_b * n_b);
    candidates_.push_back(c);
  }
  const auto kCap = static_cast<std::size_t>(options_.max_observations);
  *truncated = 0;
  if (candidates_.size() > kCap) {
    std::nth_element(candidates_.begin(), candidates_.begin() + kCap, candidates_.end(),
                     [](const Candidate& a, const Candidate& b) {
                       return a.true_range_m < b.true_range_m ||
                              (a.true_range_m == b.true_range_m && a.obs.landmark_id < b.obs.landmark_id);
                     });
    *truncated = static_cast<int>(candidates_.size() - kCap);
    candidates_.resize(kCap);
  }
  std::sort(candidates_.begin(), candidates_.end(),
            [](const Candidate& a, const Candidate& b) { return a.obs.landmark_id < b.obs.landmark_id; });
  if (out->size() < candidates_.size()) out->resize(candidates_.size());
  for (std::size_t k = 0; k < candidates_.size(); ++k) (*out)[k] = candidates_[k].obs;
  return static_cast<int>(candidates_.size());
}

}  // namespace elaslam::sim

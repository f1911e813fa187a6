// SPDX-License-Identifier: Apache-2.0
// The range-bearing sensor (paper Fig. 1 and eq 7): every landmark within D/2 of
// the robot centre, full 360 degrees, known ids, Gaussian range and bearing noise.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "elaslam/common/contract.hpp"
#include "elaslam/common/geometry.hpp"
#include "elaslam/simulator/random.hpp"
#include "elaslam/simulator/scenario.hpp"

namespace elaslam::sim {

struct Observation {
  std::int32_t landmark_id = 0;  // 0..N-1
  double range_m = 0.0;          // [m] noisy, > 0
  double bearing_rad = 0.0;      // [rad] noisy, robot frame B, in [-pi, pi)
};

/// A frame's observations: first num_obs valid (World sizes it for
/// sensor.max_observations once; observe() grows it only when it is smaller).
using ObservationArray = std::vector<Observation>;

/// Noise-free range and bearing of p_LinW seen from T_WB.
Observation true_observation(const Pose2& T_WB, const Eigen::Vector2d& p_LinW, std::int32_t id);

/// The observation model with its random streams and scratch memory (allocated once).
class Sensor {
 public:
  /// noise and detection are this robot's own streams.
  Sensor(const SensorOptions& options, int num_landmarks, Rng noise, Rng detection);

  /// Observe every landmark in view from T_WB. Writes at most
  /// options.max_observations observations sorted by landmark id and returns their
  /// number; when more are in view the nearest are kept and *truncated counts the rest.
  /// For every landmark, in id order, it draws two normals and one uniform whether
  /// or not the landmark is in view, so the draws of one landmark do not depend on
  /// where the others are (moving landmarks do not perturb the static ones' noise).
  int observe(const Pose2& T_WB, const std::vector<Eigen::Vector2d>& p_LinW, ObservationArray* out,
              int* truncated);

 private:
  struct Candidate {
    double true_range_m;
    Observation obs;
  };
  SensorOptions options_;
  Rng noise_;
  Rng detection_;
  std::vector<Candidate> candidates_;  // capacity num_landmarks, reused every frame
};

}  // namespace elaslam::sim

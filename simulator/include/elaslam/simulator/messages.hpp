// The LCM messages of one frame (lcmtypes/*.lcm). The caller supplies utime
// (wall clock at publish, microseconds since the epoch).
#pragma once

#include <cstdint>

#include "elaslam/ground_truth_t.hpp"
#include "elaslam/sensor_frame_t.hpp"
#include "elaslam/simulator/world.hpp"

namespace elaslam::sim {

/// SENSOR_<robot_id>: odometer reading, noise model and observations.
elaslam::sensor_frame_t to_message(const SensorFrame& f, std::int64_t utime);

/// GROUND_TRUTH: true robot poses (in the order of the scenario's robots) and true
/// landmark positions with the moving flags, for the world's current frame.
elaslam::ground_truth_t to_message(const World& w, std::int64_t utime);

}  // namespace elaslam::sim

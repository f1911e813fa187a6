// SPDX-License-Identifier: Apache-2.0
// The LCM messages of one frame (lcmtypes/*.lcm). The caller supplies utime
// (wall clock at publish, microseconds since the epoch).
#pragma once

#include <cstdint>
#include <string>

#include "elaslam/ground_truth_t.hpp"
#include "elaslam/run_info_t.hpp"
#include "elaslam/sensor_frame_t.hpp"
#include "elaslam/simulator/world.hpp"

namespace elaslam::sim {

/// SENSOR_<robot_id>: odometer reading, noise model and observations.
elaslam::sensor_frame_t to_message(const SensorFrame& f, std::int64_t utime);
/// The same into `m`, reusing its observation array (no allocation once it has
/// held sensor.max_observations observations): a frame source's per-frame path.
void to_message(const SensorFrame& f, std::int64_t utime, elaslam::sensor_frame_t* m);

/// GROUND_TRUTH: true robot poses (in the order of the scenario's robots) and true
/// landmark positions with the moving flags, for the world's current frame.
elaslam::ground_truth_t to_message(const World& w, std::int64_t utime);
/// The same into `m`, reusing its arrays (no allocation once they have held the
/// world's robots and landmarks).
void to_message(const World& w, std::int64_t utime, elaslam::ground_truth_t* m);

/// RUN_INFO of a simulated run: the scenario's facts and its effective configuration.
/// `effective_yaml` is the config file's scenario section as read; the values a
/// command line can override (frames, rate, seed, dynamism, speed) are written over
/// it from `o`, so the recorded config is the one that ran. `scenario` names the
/// config file; `mode` is the robots' mode when known ("" otherwise). frame = -1.
elaslam::run_info_t to_run_info(const ScenarioOptions& o, const std::string& scenario, const std::string& effective_yaml,
                                const std::string& mode, std::int64_t utime);

}  // namespace elaslam::sim

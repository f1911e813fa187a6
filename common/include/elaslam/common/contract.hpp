// The message contract's capacities (the array sizes of lcmtypes/*.lcm), in one
// place, checked against the generated types at compile time. Every bound on a
// count field and every error message about one is built from these constants.
#pragma once

#include <string>
#include <type_traits>

#include "elaslam/global_map_t.hpp"
#include "elaslam/ground_truth_t.hpp"
#include "elaslam/lmap_snapshot_t.hpp"
#include "elaslam/run_info_t.hpp"
#include "elaslam/sensor_frame_t.hpp"

namespace elaslam::contract {

constexpr int kMaxObsPerFrame = 64;           // sensor_frame_t.obs
constexpr int kMaxRobots = 8;                 // ground_truth_t.robot_ids / robots, run_info_t.robot_ids
constexpr int kMaxLandmarksPerMessage = 256;  // ground_truth_t.landmarks, global_map_t.landmarks / moving_ids,
                                              // lmap_snapshot_t.landmarks

static_assert(std::extent_v<decltype(sensor_frame_t::obs)> == kMaxObsPerFrame);
static_assert(std::extent_v<decltype(ground_truth_t::robot_ids)> == kMaxRobots);
static_assert(std::extent_v<decltype(ground_truth_t::robots)> == kMaxRobots);
static_assert(std::extent_v<decltype(run_info_t::robot_ids)> == kMaxRobots);
static_assert(std::extent_v<decltype(ground_truth_t::landmarks)> == kMaxLandmarksPerMessage);
static_assert(std::extent_v<decltype(global_map_t::landmarks)> == kMaxLandmarksPerMessage);
static_assert(std::extent_v<decltype(global_map_t::moving_ids)> == kMaxLandmarksPerMessage);
static_assert(std::extent_v<decltype(lmap_snapshot_t::landmarks)> == kMaxLandmarksPerMessage);

/// "<field> outside [0, <capacity>]": the refusal of a count field, from the constant.
inline std::string count_outside(const char* field, int capacity) {
  return std::string(field) + " outside [0, " + std::to_string(capacity) + "]";
}

/// min(count, capacity), and never below 0: a loop bound over a message's array for
/// code that reads messages it has not validated (tools reading logs).
inline int bounded(int count, int capacity) { return count < 0 ? 0 : (count > capacity ? capacity : count); }

}  // namespace elaslam::contract

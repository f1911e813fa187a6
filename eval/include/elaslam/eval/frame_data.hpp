// SPDX-License-Identifier: Apache-2.0
// From the team's messages to the metrics' FrameData (metrics.hpp): the one adapter
// shared by the in-process run (team/team_run.cpp) and the evaluation of a recording
// (log_frames.hpp), so both read the messages the same way by construction.
// Every loop is bounded by the contract's capacities (a recording is not trusted).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "elaslam/common/limits.hpp"
#include "elaslam/eval/metrics.hpp"
#include "elaslam/global_map_t.hpp"
#include "elaslam/ground_truth_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/sensor_frame_t.hpp"

namespace elaslam {

/// GROUND_TRUTH: frame, robot ids and true poses (in the message's order), true
/// landmark positions and moving flags indexed by landmark id (negative ids skipped).
void set_truth(const ground_truth_t& gt, FrameData* f);

/// Size the estimate fields for `robots` robots with nothing estimated yet, and
/// clear the observed ids.
void clear_estimates(std::size_t robots, FrameData* f);

/// POSE_<r> of the robot at `index` in the frame's robot order.
void set_pose(std::size_t index, const pose_estimate_t& p, FrameData* f);

/// SENSOR_<r>: its observed landmark ids, appended to `observed` (FrameData::observed:
/// for detection recall).
void add_observed(const sensor_frame_t& s, std::vector<int>* observed);

/// GLOBAL_MAP as assembled by GlobalMapAssembly: its static landmarks (id, estimate)
/// and moving ids (FrameData's map_landmarks and map_moving), replacing what the
/// vectors held.
void read_map(const global_map_t& g, std::vector<std::pair<int, Eigen::Vector2d>>* landmarks, std::vector<int>* moving);

/// The chunks of one GLOBAL_MAP publication (global_map_t: they share utime,
/// incarnation, version and frame) put back together, for tools that need the whole
/// map: add() every chunk received; when one completes a publication, map() holds it
/// as one message covering every id (num_chunks 1). A chunk of another publication
/// starts over: a publication with a lost chunk is never complete.
class GlobalMapAssembly {
 public:
  /// True when `chunk` completed a publication (map() then holds it). Chunks that
  /// contradict themselves (counts, chunk index) are ignored.
  bool add(const global_map_t& chunk);
  const global_map_t& map() const { return complete_; }

 private:
  global_map_t building_{}, complete_{};
  std::vector<bool> received_;
  int count_ = 0;
};

/// The receivers' checks for a recorded message: what a node would have
/// refused is not evaluated either. "" when it holds, else the problem (`reason`
/// its kind). A POSE's source_utime must not be after `received_us` (more than
/// kClockSlackUs): a forged stamp in the future made a negative latency.
constexpr std::int64_t kClockSlackUs = 100000;  // [us] skew allowed between the sender's and the recorder's clocks
std::string check_logged(const pose_estimate_t& p, std::int64_t received_us, const MessageLimits& l, Refusal* reason);
std::string check_logged(const sensor_frame_t& s, const MessageLimits& l, Refusal* reason);
/// One GLOBAL_MAP chunk: the check robot_node applies (limits.hpp, check_global_map),
/// with ids bounded by the contract.
std::string check_logged(const global_map_t& g, const MessageLimits& l, Refusal* reason);

}  // namespace elaslam

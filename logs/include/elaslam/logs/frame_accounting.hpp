// SPDX-License-Identifier: Apache-2.0
// Frame accounting: what happened to each frame of a recorded run, for one robot
// (logged, not yet started, dropped by the robot, processed but lost by the
// recorder), from the POSEs' frames_processed counts and the robots' STATUS. Used by
// evaluate and log_info (log_summary.hpp); the rules are those of account_frames.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace elaslam {

/// A POSE_<r> in the log: its frame and pose_estimate_t.frames_processed (frames the
/// node processed since it started, this one included).
struct PoseCheckpoint {
  int frame;
  std::int64_t frames_processed;
};

/// A STATUS_ROBOT_<r> in the log: frame = last frame processed, frames = frames
/// processed so far, frames_dropped = the node's own count of lost/refused frames.
struct StatusCheckpoint {
  int frame;
  std::int64_t frames;
  std::int64_t frames_dropped;
};

/// What happened to each frame of [first_frame, last_frame] for one robot.
/// Invariant: poses_logged + not_started + dropped + missing_from_log == frames_in_run.
struct RobotFrameAccount {
  int robot_id = 0;
  int frames_in_run = 0;     // last_frame - first_frame + 1 (0 when last < first)
  int poses_logged = 0;      // frames with a POSE in the log
  int not_started = 0;       // frames before the robot's first processed frame (it joined late)
  int dropped = 0;           // frames the robot did not process (lost, refused, or it was down)
  int missing_from_log = 0;  // frames the robot processed whose POSE the recorder lost
  int restarts = 0;          // times frames_processed went back (the node was restarted)
  std::vector<std::pair<int, int>> missing_pose_ranges;    // [from, to] runs of frames without a logged POSE
  bool sensor_recorded = false;                            // any SENSOR frame given at all
  int sensors_logged = 0;                                  // distinct SENSOR frames in [first, last]
  std::vector<std::pair<int, int>> missing_sensor_ranges;  // same for SENSOR; empty when !sensor_recorded
  std::int64_t node_reported_dropped = -1;                 // frames_dropped of the latest STATUS, -1 when none
};

/// Accounts for every frame of [first_frame, last_frame] of robot `robot_id`.
///
/// POSEs are sorted by frame; of several POSEs of one frame the first given is kept;
/// POSEs outside [first_frame, last_frame] are ignored. With (f, n) = (frame,
/// frames_processed) of the kept POSEs, in frame order:
/// - Between consecutive POSEs (f_a, n_a) and (f_b, n_b): g = f_b - f_a - 1 frames
///   have no POSE. When n_b > n_a the robot processed p = clamp(n_b - n_a - 1, 0, g)
///   of them; when n_b <= n_a the node restarted in between (restarts += 1) and
///   processed p = clamp(n_b - 1, 0, g) since its restart. missing_from_log += p,
///   dropped += g - p.
/// - Before the first POSE (f_0, n_0): the robot processed q = clamp(n_0 - 1, 0,
///   f_0 - first_frame) of first_frame..f_0-1, whose POSEs the recorder lost
///   (missing_from_log += q); the others are not_started (it joined late; not a drop).
/// - After the last POSE (f_L, n_L): the STATUS with the largest frame > f_L (the
///   later one given on a tie) tells how many more frames the robot processed:
///   a = clamp(frames - n_L, 0, last_frame - f_L), or clamp(frames, 0, ...) when
///   frames < n_L (a restart, restarts += 1). missing_from_log += a, dropped += the
///   rest of f_L+1..last_frame (the robot stopped, or lost them). No such STATUS:
///   all of them are dropped.
/// - No POSE at all: the latest STATUS (largest frame) with frames > 0 gives
///   missing_from_log = clamp(frames, 0, frames_in_run); the rest, or every frame
///   when there is no such STATUS, are not_started.
/// Which frames were processed is not known, only how many: the ranges list every
/// frame without a POSE, whatever its class. `sensor_frames` are the robot's SENSOR
/// frames in the log (any order, duplicates allowed); empty means no SENSOR was
/// recorded (e.g. a log of the robots' outputs only): then sensor_recorded is false
/// and no SENSOR range is reported. `statuses` may be in any order. A run longer than
/// INT_MAX / 2 frames (only a damaged log has one) is cut to that length.
RobotFrameAccount account_frames(int robot_id, int first_frame, int last_frame, std::vector<PoseCheckpoint> poses,
                                 const std::vector<StatusCheckpoint>& statuses, const std::vector<int>& sensor_frames);

/// Maximal runs [from, to] of frames in [first, last] that are not in `present`
/// (sorted ascending, without duplicates).
std::vector<std::pair<int, int>> absent_ranges(int first, int last, const std::vector<int>& present);

/// "2, 40-42" for {{2, 2}, {40, 42}}; "none" when empty.
std::string format_ranges(const std::vector<std::pair<int, int>>& ranges);

}  // namespace elaslam

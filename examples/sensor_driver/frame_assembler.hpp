// SPDX-License-Identifier: Apache-2.0
// Frames from a real robot's timestamped readings: the part of a sensor driver that
// keeps the SENSOR_<r> contract (docs/sensor_driver.md). Readings arrive in time
// order from the robot's drivers (wheel odometry integrated by the base; landmark
// detections with ids, e.g. AprilTags); frame k covers [t0 + k/F, t0 + (k+1)/F) and
// is complete once a reading at or past its end arrives. Every frame is emitted,
// empty ones included (frame indices stay consecutive: a robot_node counts a
// missing index as a lost frame), with the latest odometer reading at its end.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "elaslam/sensor_frame_t.hpp"

namespace elaslam::examples {

struct AssemblerOptions {
  int robot_id = 1;
  double rate_hz = 10.0;                // F: frames per second the robot_node is configured for
  int max_landmark_id = 1024;           // ids at or above are dropped (robot.filter.max_landmark_id)
  int max_observations = 64;            // per frame; the nearest kept (robot.filter.max_observations)
  double max_range_m = 1e4;
  // The odometer's noise model (sensor_frame_t): variances per metre / radian moved.
  double odom_var_trans_per_m = 0.0025;
  double odom_var_rot_per_rad = 0.0025;
  double odom_var_rot_per_m = 0.0;
};

/// What the assembler dropped, by reason (a driver prints them at exit).
struct AssemblerCounters {
  std::int64_t frames = 0;              // emitted
  std::int64_t empty_frames = 0;        // emitted without a detection
  std::int64_t frames_without_odometry = 0;  // emitted before any odometer reading: odometer at 0, 0, 0
  std::int64_t detections = 0;          // in emitted frames
  std::int64_t bad_lines = 0;           // unreadable input lines
  std::int64_t out_of_order = 0;        // readings older than the frame being filled
  std::int64_t bad_detections = 0;      // id outside [0, max_landmark_id), range not in (0, max], not finite
  std::int64_t repeated_in_frame = 0;   // a landmark seen twice in one frame: the later reading kept
  std::int64_t over_capacity = 0;       // beyond max_observations: the farthest dropped
};

class FrameAssembler {
 public:
  using Emit = std::function<void(const sensor_frame_t&)>;
  FrameAssembler(const AssemblerOptions& options, Emit emit);

  /// The cumulative odometer pose at time t [s] (the base's integrated odometry).
  void odometry(double t, double x, double y, double theta);
  /// A landmark seen at time t [s]: range [m] and bearing [rad] in the robot frame.
  void detection(double t, int id, double range, double bearing);
  /// One input line: "odom T X Y THETA" or "det T ID RANGE BEARING" ('#' comments
  /// and blank lines ignored). False (and counted) when it cannot be read.
  bool line(const std::string& text);
  /// Emits the frame being filled (end of input).
  void flush();

  const AssemblerCounters& counters() const { return counters_; }

 private:
  void advance_to(double t);  // emit every frame that ends at or before t
  double frame_start(std::int64_t k) const;  // [s]
  bool take_time(double t);  // false (counted) for a reading older than the frame being filled
  void emit_current();

  AssemblerOptions options_;
  Emit emit_;
  AssemblerCounters counters_;
  bool started_ = false;
  double t0_ = 0.0;            // start of frame 0 [s]
  std::int64_t frame_ = 0;     // the frame being filled
  bool have_odom_ = false;
  double odom_[3] = {0.0, 0.0, 0.0};
  std::vector<range_bearing_t> obs_;
  sensor_frame_t msg_;
};

}  // namespace elaslam::examples

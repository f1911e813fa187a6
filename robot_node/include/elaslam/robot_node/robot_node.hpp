// The robot node's message layer, without I/O: validates incoming messages, keeps
// frame order, runs the Robot, and fills the outgoing messages (POSE, LMAP_EVENT
// with a per-robot seq, LMAP_SNAPSHOT, STATUS_ROBOT). The robot_node process and
// the in-process team run both drive this class, so both behave the same.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "elaslam/common/histogram.hpp"
#include "elaslam/dynamic_notice_t.hpp"
#include "elaslam/landmark_event_t.hpp"
#include "elaslam/lmap_snapshot_t.hpp"
#include "elaslam/node_status_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/robot_node/robot.hpp"
#include "elaslam/sensor_frame_t.hpp"

namespace elaslam {

struct RobotNodeCounters {
  std::int64_t frames = 0;            // frames processed
  std::int64_t frames_gap = 0;        // frames never received (gaps bridged by the odometer)
  std::int64_t frames_duplicate = 0;  // refused: same frame again
  std::int64_t frames_out_of_order = 0;  // refused: older than the last processed
  std::int64_t rejected_inputs = 0;   // messages that failed validation
  std::int64_t decode_errors = 0;     // messages that could not be decoded (counted by the I/O shell)
  std::int64_t queue_drops = 0;       // messages lost before the handler (counted by the I/O shell)
  std::int64_t filter_faults = 0;     // filter operations refused by its health checks
  std::int64_t events_sent = 0;
  std::int64_t notices_applied = 0;   // dynamic notices that removed a landmark here
  std::int64_t notices_ignored = 0;   // notices about landmarks this robot did not hold / its own
  std::int64_t notices_deferred = 0;  // notices for a frame this robot had not processed yet: held until it has
};

class RobotNode {
 public:
  enum class Verdict { kProcessed, kDuplicate, kOutOfOrder, kInvalid };

  RobotNode(const RobotOptions& options, int robot_id);

  /// One sensor frame. On kProcessed the outputs below hold this frame's messages.
  /// `now_utime` stamps the outgoing messages; `why` gets the reason of a refusal.
  Verdict on_sensor(const sensor_frame_t& msg, std::int64_t now_utime, std::string* why = nullptr);

  /// A dynamic notice from main_robot. Returns false when it was invalid.
  /// A notice about frame f takes effect after this robot has processed its own
  /// frame f, whatever the order of arrival (another robot's detection in frame f
  /// may reach this robot before its own SENSOR frame f does): it is held until
  /// then, so the live team does what the in-process run does (notices of frame k
  /// between frames k and k + 1). Held at most node.max_frame_gap frames ahead.
  bool on_notice(const dynamic_notice_t& msg, std::string* why = nullptr);

  void count_decode_error() { ++counters_.decode_errors; }
  void count_queue_drops(std::int64_t n) { counters_.queue_drops += n; }

  // ---- outputs of the last processed frame -----------------------------------------
  const pose_estimate_t& pose_msg() const { return pose_; }
  const std::vector<landmark_event_t>& event_msgs() const { return events_; }
  /// True when this frame also produced a snapshot (every snapshot_period_frames).
  bool snapshot_ready() const { return snapshot_ready_; }
  const lmap_snapshot_t& snapshot_msg() const { return snapshot_; }
  /// Fill a snapshot now (e.g. on start-up or on request).
  const lmap_snapshot_t& make_snapshot(std::int64_t now_utime);

  node_status_t status_msg(std::int64_t now_utime) const;
  const RobotNodeCounters& counters() const { return counters_; }
  const Robot& robot() const { return robot_; }
  const DurationHistogram& processing() const { return processing_; }
  int robot_id() const { return robot_id_; }

  /// Check a sensor frame against the contract (robot id, counts, finite values,
  /// ranges, ids within capacity). Empty string when valid.
  std::string validate(const sensor_frame_t& msg) const;

 private:
  void fill_pose(const sensor_frame_t& msg, std::int64_t now_utime, const FrameSummary& s, std::int64_t us);
  void fill_events(std::int64_t now_utime);
  void apply_notice(const dynamic_notice_t& msg);

  RobotOptions options_;
  int robot_id_;
  Robot robot_;
  FrameInput input_;
  RobotNodeCounters counters_;
  DurationHistogram processing_;
  int last_frame_ = -1;
  std::int64_t seq_ = 0;
  pose_estimate_t pose_{};
  std::vector<landmark_event_t> events_;
  lmap_snapshot_t snapshot_{};
  bool snapshot_ready_ = false;
  std::vector<std::uint8_t> id_seen_;  // duplicate-id check within a frame
  std::vector<dynamic_notice_t> held_;  // notices for frames not processed yet (fixed capacity)
};

}  // namespace elaslam

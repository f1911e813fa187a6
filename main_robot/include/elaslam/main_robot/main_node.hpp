// main_robot's message layer, without I/O: validates LMAP_EVENT / LMAP_SNAPSHOT,
// applies them to the GlobalMap, and fills GLOBAL_MAP, DYNAMIC_NOTICE and
// STATUS_MAIN. The main_robot process and the in-process team run share it.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "elaslam/dynamic_notice_t.hpp"
#include "elaslam/global_map_t.hpp"
#include "elaslam/landmark_event_t.hpp"
#include "elaslam/lmap_snapshot_t.hpp"
#include "elaslam/main_robot/global_map.hpp"
#include "elaslam/node_status_t.hpp"

namespace elaslam {

struct MainCounters {
  std::int64_t events = 0;           // events applied
  std::int64_t snapshots = 0;        // snapshots applied
  std::int64_t duplicates = 0;       // duplicate / stale events ignored
  std::int64_t gaps = 0;             // seq gaps seen (repaired by snapshots)
  std::int64_t rejected_inputs = 0;  // messages that failed validation
  std::int64_t decode_errors = 0;    // counted by the I/O shell
  std::int64_t notices_sent = 0;
  std::int64_t maps_published = 0;
};

class MainNode {
 public:
  explicit MainNode(const GlobalMapOptions& options);

  /// Returns false (and counts it) when the message is invalid; `why` says why.
  bool on_event(const landmark_event_t& msg, std::string* why = nullptr);
  bool on_snapshot(const lmap_snapshot_t& msg, std::string* why = nullptr);
  void count_decode_error() { ++counters_.decode_errors; }

  /// Notices produced since the last call, as messages (seq assigned); clears them.
  const std::vector<dynamic_notice_t>& take_notices(std::int64_t now_utime);

  /// Robot `robot_id` has finished frame `frame` (its POSE arrived; it publishes its
  /// events before its POSE). Returns the newest frame that every robot seen so far
  /// has finished when that advanced with this call, else -1: the moment to publish
  /// GLOBAL_MAP for that frame.
  int on_robot_frame(int robot_id, int frame);

  /// The global map as a message (at most 256 static landmarks, 256 moving ids),
  /// stamped with `frame` (default: the newest frame every robot has finished, or
  /// before any POSE was seen, the newest frame of any event).
  const global_map_t& global_map_msg(std::int64_t now_utime, int frame = -1);
  node_status_t status_msg(std::int64_t now_utime) const;

  GlobalMap& map() { return map_; }
  const GlobalMap& map() const { return map_; }
  const MainCounters& counters() const { return counters_; }

  std::string validate(const landmark_event_t& msg) const;
  std::string validate(const lmap_snapshot_t& msg) const;

 private:
  GlobalMap map_;
  MainCounters counters_;
  std::vector<Notice> pending_;
  std::vector<dynamic_notice_t> notices_;
  std::int64_t notice_seq_ = 0;
  std::array<int, kMaxTeamRobots> robot_frame_;  // last finished frame per robot, -1: never seen
  int completed_frame_ = -1;
  global_map_t msg_{};
  std::vector<std::pair<int, RobotEstimate>> snap_lms_;
  std::vector<int> snap_moving_;
};

}  // namespace elaslam

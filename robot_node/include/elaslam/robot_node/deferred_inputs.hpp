// SPDX-License-Identifier: Apache-2.0
// main_robot's inputs to a robot that take effect at a set point of the robot's own
// frames, whatever their order of arrival, so that the live team does what the
// in-process run does:
// - what the team knows moves (MovingReport: a DYNAMIC_NOTICE, or an entry of
//   GLOBAL_MOVING's lists whose notice this robot never had), after this robot's own
//   frame of the finding;
// - the team's map without this robot (TEAM_MAP_<r>), after this robot's frame that
//   follows the map's.
// It decides what is news and when it is due; RobotNode applies it to the Robot. Its
// buffers are sized at construction.
#pragma once

#include <cstdint>
#include <vector>

#include "elaslam/global_map_t.hpp"
#include "elaslam/robot_node/robot.hpp"

namespace elaslam {

/// Landmark `landmark_id` found moving in `frame` by robot `detected_by`.
struct MovingReport {
  int landmark_id = 0;
  int frame = 0;
  int detected_by = 0;
};

class DeferredInputs {
 public:
  static constexpr std::size_t kMaxHeldMoving = 256;  // reports held for frames not processed yet

  explicit DeferredInputs(const RobotOptions& options);

  /// Something new: not had already (a report of this frame or a later one for the
  /// landmark), and not older than this robot's own view of it (it saw the landmark
  /// again and took it back after).
  bool is_news(const MovingReport& m, const LMap& lmap) const;

  enum class Take { kStale, kHeld, kNow };
  /// A valid report of another robot: kStale when not news (a duplicated or late
  /// datagram: applying it would undo newer state); else it is had, and kHeld when it
  /// is ahead of this robot's frames (until release_moving; at most node.max_frame_gap
  /// ahead and kMaxHeldMoving of them), or kNow (a fresh node, one far behind, or a
  /// full buffer: a report is never lost).
  Take take_moving(const MovingReport& m, const LMap& lmap, int last_frame);
  /// The held reports of `last_frame` or earlier, in arrival order, to `apply`.
  template <class Apply>
  void release_moving(int last_frame, Apply apply) {
    std::size_t kept = 0;
    for (std::size_t i = 0; i < held_.size(); ++i) {
      if (held_[i].frame <= last_frame)
        apply(held_[i]);
      else
        held_[kept++] = held_[i];
    }
    held_.resize(kept);
  }

  /// A valid TEAM_MAP_<r> chunk: false (ignored) when older than one taken (a lower
  /// version of main's incarnation, or an earlier incarnation: a datagram delayed past
  /// main's restart); else its estimates are held, replacing older ones per landmark.
  bool take_team_map(const global_map_t& msg);
  /// The held team estimates whose map's frame is before `last_frame`, no longer held;
  /// empty when none.
  const std::vector<TeamEstimate>& due_team_estimates(int last_frame);

 private:
  friend struct RobotStateAccess;  // the state file saves and restores what is held

  struct TeamPending {  // a team estimate waiting for this robot's frame after its map's frame
    bool valid = false;
    int frame = 0;
    Eigen::Vector2d position = Eigen::Vector2d::Zero();
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  };

  int max_frame_gap_;
  std::vector<MovingReport> held_;  // reports for frames not processed yet (fixed capacity)
  std::vector<int> report_frame_;   // per landmark id: frame of the newest report had, -1: none
  std::int64_t team_map_incarnation_ = 0, team_map_version_ = -1;  // newest TEAM_MAP_<r> taken
  std::vector<TeamPending> team_pending_;  // per landmark id (robot.team_map.fuse only)
  std::vector<TeamEstimate> team_due_;     // scratch: those due now
  int team_pending_count_ = 0;
};

}  // namespace elaslam

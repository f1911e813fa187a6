// SPDX-License-Identifier: Apache-2.0
// The team's global map (paper section 3.3.2; docs/design.md section 5). Per landmark id:
// the latest estimate from each robot, a fused estimate, the contributing robots,
// a status (STATIC, MOVING) and the frame it last changed. Fixed capacity.
//
// Events are idempotent and ordered per robot by seq: duplicates and stale ones
// are ignored; a gap is noted and repaired by the robot's snapshot chunks, each of
// which replaces that robot's contribution within its range of ids; the gap counts
// as repaired once chunks taken after it have covered every id. Each robot's stream
// belongs to one incarnation of it (landmark_event_t): a newer one (a restart
// without state) starts the stream over, an older one is a replay or a second sender
// with the same id (observe_incarnation). No I/O.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "elaslam/common/config.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/common/limits.hpp"
#include "elaslam/common/main_options.hpp"

namespace elaslam {

constexpr int kMaxTeamRobots = contract::kMaxRobots;

/// GlobalMap::check_team's verdict on one robot's map.
struct TeamCheck {
  int shared = 0;     // STATIC landmarks it and another robot hold a usable estimate of
  int disagree = 0;   // ... whose estimate the others' fusion refuses
  std::int64_t rounds_left_out = 0;  // rounds of team maps it was left out of, since start
};
/// The fewest shared landmarks on which a robot's map is judged (as the robot's own
/// "lost" rule, Robot::apply_team_map).
constexpr int kTeamCheckMinShared = 3;

enum class GlobalStatus : std::uint8_t { kAbsent = 0, kStatic = 1, kMoving = 2 };

struct RobotEstimate {
  bool valid = false;
  Eigen::Vector2d position = Eigen::Vector2d::Zero();  // [m] W
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();        // [m^2]
  int frame = -1;
};

struct GlobalEntry {
  GlobalStatus status = GlobalStatus::kAbsent;
  int status_frame = -1;   // frame of the last status change
  int moving_by = 0;       // robot whose MOVING event made it moving
  // Moving only by the moving list of a snapshot taken after a gap, from a robot that
  // held no estimate of it here: an opinion of unknown age (a robot keeps listing a
  // landmark as moving until it sees it again, also after another robot's RETURN).
  // No notice went out for it; a robot holding it static in a snapshot of the same
  // or a later frame takes it back. Persisted (optional key).
  bool moving_unconfirmed = false;
  // First known from a robot whose stream had a gap (a snapshot after a gap, or an
  // event before the snapshot that repairs the gap, e.g. right after a restart), so
  // whether it moved before is unknown here. Persisted (optional key).
  bool history_unknown = false;
  std::array<RobotEstimate, kMaxTeamRobots> by_robot{};
  Eigen::Vector2d fused = Eigen::Vector2d::Zero();
  Eigen::Matrix2d fused_cov = Eigen::Matrix2d::Zero();
  int contributors() const;  // bit r-1 set when robot r has an estimate
};

/// Incoming map change (mirrors landmark_event_t; validated by the caller).
struct GlobalEvent {
  int robot_id = 0;        // 1..kMaxTeamRobots
  std::int64_t seq = 0;
  int frame = 0;
  int kind = 0;            // landmark_event_t::ADD / UPDATE / MOVING / RETURN
  int landmark_id = -1;
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
};

/// A notice to send to every robot.
struct Notice {
  int landmark_id = -1;
  int detected_by = 0;
  int frame = 0;
};

enum class EventResult { kApplied, kAppliedAfterGap, kDuplicate, kStale };
const char* to_string(EventResult r);

enum class IncarnationVerdict {
  kCurrent,    // the robot's current incarnation (or its first one)
  kRestarted,  // a newer one: the robot restarted without its state; its stream starts over
  kStale,      // an older one: a replay, or a second live sender with this id (refuse)
};

struct RobotStream {
  std::int64_t incarnation = 0;  // the robot's current incarnation, 0: none seen yet
  std::int64_t previous_incarnation = 0;
  std::int64_t last_seq = 0;   // highest seq applied (or covered by a snapshot)
  std::int64_t snapshot_seq = 0;  // seq of the newest snapshot chunk applied
  int snapshot_frame = -1;        // and its frame: chunks are ordered by (seq, frame)
  bool gap_pending = false;    // a gap was seen and snapshot chunks have not covered every id since
  std::int64_t repair_seq = 0; // chunks with at least this seq repair the pending gap
  std::vector<std::uint8_t> covered;  // per landmark id: covered by such a chunk (sized max_landmark_id)
  int covered_ids = 0;         // how many
  std::int64_t gaps = 0;       // gaps seen
  std::int64_t duplicates = 0; // duplicate or stale events ignored
  std::int64_t restarts = 0;   // new incarnations after the first
  std::int64_t stale_incarnation = 0;  // messages of an older incarnation refused
  std::int64_t previous_heard = 0;     // of those, of previous_incarnation since it was replaced, each with
                                       // a frame newer than any before (it kept working: a second sender)
  int incarnation_frame = -1;          // the newest frame of any message of the current incarnation
  int previous_frame = -1;             // ... of previous_incarnation: as it was when replaced, then as heard
  int duplicate_until_frame = -1;      // a second live sender was seen: flagged until this frame
  int last_frame = -1;
  // Another incarnation, older than the one followed, heard: a replay, a second
  // sender, or the robot restarted with its start count reset (a lost state
  // directory, another computer), which is followed once its frames run on past the
  // followed incarnation's while that one is not heard (observe_incarnation).
  std::int64_t challenger = 0;
  int challenger_frame = -1;            // its newest frame
  int challenger_heard = 0;             // its messages, each with a newer frame than any before
  bool restarted_back = false;          // the last restart took an older incarnation

  /// A gap: chunks with a seq of at least `seq` must cover every id again (a pending
  /// repair that needs older chunks only is kept).
  void start_repair(std::int64_t seq) {
    if (!gap_pending || seq > repair_seq) restart_repair(seq);
    gap_pending = true;
  }
  /// The same, unconditionally (a new incarnation: any of its snapshots repairs).
  void restart_repair(std::int64_t seq);
  /// A chunk with seq `seq` covered ids [id_begin, id_end).
  void cover(std::int64_t seq, int id_begin, int id_end);
};

class GlobalMap {
 public:
  explicit GlobalMap(const GlobalMapOptions& options);

  /// Apply one event; a MOVING that changes the map appends a notice to `notices`.
  EventResult apply(const GlobalEvent& e, std::vector<Notice>* notices);

  /// Replace robot r's contribution with a snapshot: its static landmarks, and the
  /// ids it holds as moving (applied only while a gap is pending for r).
  void apply_snapshot(int robot_id, std::int64_t seq, int frame, const std::vector<std::pair<int, RobotEstimate>>& lms,
                      const std::vector<int>& moving_ids, std::vector<Notice>* notices) {
    apply_snapshot(robot_id, seq, frame, 0, max_landmark_id(), lms, moving_ids, {}, notices);
  }
  /// The same within the ids [id_begin, id_end) only (one chunk of a snapshot); `lms`
  /// and `moving_ids` lie in that range; `moving_frames` (when given, one per moving
  /// id) the frame the robot found each one moving: newer than this map's last
  /// status change, it stands in for a lost MOVING event even when another robot
  /// still holds the landmark. A chunk older than the robot's newest applied snapshot
  /// is ignored (returns false): one with a lower seq, or the same seq and an older
  /// frame (a replay of an older snapshot would roll the map back).
  bool apply_snapshot(int robot_id, std::int64_t seq, int frame, int id_begin, int id_end,
                      const std::vector<std::pair<int, RobotEstimate>>& lms, const std::vector<int>& moving_ids,
                      const std::vector<int>& moving_frames, std::vector<Notice>* notices);

  /// Robot r's messages carry `incarnation`; `frame` is the message's frame. A newer
  /// incarnation than the current one starts r's stream over (its seq restarts at 1,
  /// a gap is pending until its snapshot has covered every id); an older one is
  /// refused, and when it is the one just replaced, counted as a second live sender
  /// (flagged for 50 frames from the third such message).
  /// An older incarnation never seen before is followed (kRestarted, stream.restarted_back) once three of
  /// its messages with newer frames came and its newest frame is more than
  /// kQuietFrames past the followed incarnation's newest: the robot restarted with
  /// its start count or clock reset, and the old one is no longer heard. A live
  /// followed incarnation keeps up (then it is a second sender); a replay of old
  /// messages never gets past it.
  IncarnationVerdict observe_incarnation(int robot_id, std::int64_t incarnation, int frame);
  static constexpr int kQuietFrames = 3;
  /// True while a second live sender with robot r's id is flagged.
  bool duplicate_sender(int robot_id) const;

  /// Landmark `id`'s fusion without robot r's estimate (the other robots' own
  /// information, for r's team map). False, outputs unchanged, when no other robot
  /// holds a usable estimate.
  /// Robots left out by the last check_team are left out here too: r's team map
  /// carries neither its own information nor a robot whose map the others refuse.
  bool fused_without(int id, int robot_id, Eigen::Vector2d* position, Eigen::Matrix2d* cov) const;

  /// One round of team maps begins: each robot's map against the fusion of the
  /// others' (team_map_check_probability; a no-op that leaves nobody out when 0).
  /// Leave-one-out, not pairwise: one robot against the rest, so a robot that agrees
  /// with most of the team is not blamed for one that does not. Returns the robots
  /// left out (bit r-1). O(landmarks x robots^2) 2x2 solves, no allocation.
  unsigned check_team();
  /// The robots the last check_team left out (bit r-1).
  unsigned left_out() const { return left_out_; }
  bool is_left_out(int robot_id) const {
    return robot_id >= 1 && robot_id <= kMaxTeamRobots && ((left_out_ >> (robot_id - 1)) & 1u) != 0;
  }
  /// Rounds of team maps a robot was left out of, summed over the robots (main_robot's
  /// final line).
  std::int64_t rounds_left_out() const;
  const TeamCheck& team_check(int robot_id) const { return team_check_[static_cast<std::size_t>(robot_id - 1)]; }

  /// Robot `robot_id` reported its position (`position`, covariance `cov` [m^2]) at
  /// `frame`. A STATIC landmark cannot be where a robot's body is: every STATIC one
  /// whose fused position lies within body_radius_m of it, the two estimates together
  /// resolving that distance (sqrt(trace(cov + fused_cov) / 2) < body_radius_m), is
  /// deleted as moving, found by that robot at `frame` (a notice goes out). MRCLAM's
  /// robots carry barcodes: another robot standing still is mapped as a landmark, and
  /// steers poses once it drives off (docs/adr/0046-body-radius.md). Returns how many; 0 while
  /// body_radius_m is 0 (off). No allocation beyond
  /// `notices`.
  int occupy(int robot_id, int frame, const Eigen::Vector2d& position, const Eigen::Matrix2d& cov,
             std::vector<Notice>* notices);

  const GlobalEntry& entry(int id) const { return entries_[static_cast<std::size_t>(id)]; }
  int max_landmark_id() const { return static_cast<int>(entries_.size()); }
  std::int64_t version() const { return version_; }
  int newest_frame() const { return newest_frame_; }
  /// Robot `robot_id`'s events up to `seq` should have come and have not (its POSE
  /// said so): a gap, repaired by snapshot chunks with a seq of at least `seq`. The
  /// stream's last_seq stays: a late event still applies. False when they are all in.
  bool missed_events(int robot_id, std::int64_t seq);
  const RobotStream& stream(int robot_id) const { return streams_[static_cast<std::size_t>(robot_id - 1)]; }
  int count(GlobalStatus s) const;
  const GlobalMapOptions& options() const { return options_; }

  /// The map as JSON text, and back: the body of main_robot's state file (map_state.hpp
  /// seals it, bounds it and moves it to and from the file; both live in
  /// map_state.cpp). from_json returns false with `why` on malformed input, on values
  /// a message could not carry either (positions beyond limits.world_bound_m,
  /// covariances outside limits.cov_*, seq beyond 2^62, ids outside the team, frames
  /// outside [0, INT32_MAX]), and on a landmark id or a robot's estimate listed twice
  /// (refused, never merged), and leaves the map unchanged. The state file's tighter
  /// bounds (seq <= 2^40, incarnation <= 2^62) are map_state_out_of_bounds'.
  std::string to_json() const;
  bool from_json(std::string_view text, std::string* why);

 private:
  /// g's fused estimate from its robots' estimates; false (the last one kept) when none is usable.
  bool fuse(GlobalEntry& g) const;
  /// Delete landmark `id` from the map as moving (every robot's estimate of it is
  /// dropped), record who found it, and queue a notice unless `unconfirmed` (a
  /// snapshot's opinion of unknown age). Idempotent.
  void remove_as_moving(int id, int robot_id, int frame, std::vector<Notice>* notices, bool unconfirmed = false);

  GlobalMapOptions options_;
  std::vector<GlobalEntry> entries_;
  std::array<RobotStream, kMaxTeamRobots> streams_{};
  std::int64_t version_ = 0;
  int newest_frame_ = -1;
  double team_check_d2_ = 0.0;  // the chi-square quantile of team_map_check_probability (0: off)
  unsigned left_out_ = 0;
  std::array<TeamCheck, kMaxTeamRobots> team_check_{};
};

}  // namespace elaslam

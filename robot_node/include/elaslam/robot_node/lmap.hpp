// SPDX-License-Identifier: Apache-2.0
// The robot's local map, L-map (paper section 3.3, Algorithm 1; docs/design.md section 4):
// everything the robot keeps per landmark id (status, last world position and
// covariance from the inverse observation g(R, y), sightings, streaks, the drift
// sums), and each landmark's lifecycle as named transitions, the only code that
// changes an entry:
//
//   (unknown) --anchor_candidate--> CANDIDATE --candidate_consistent x N, confirm--> STATIC  (ADD)
//   CANDIDATE --candidate_inconsistent x moving_after--> reported moving, re-anchored        (MOVING)
//   CANDIDATE --drop_candidate (unseen)--> streak lost (leaves the filter)
//   STATIC --outside_ela x moving_after / missed x missing_needed--> found_moving:
//            MOVING, or a CANDIDATE re-anchored where it is seen now                        (MOVING)
//   any --told_moving (dynamic notice)--> MOVING when it was in the filter                   (no event)
//   CANDIDATE that has moved --confirm after return_frames sightings--> STATIC              (RETURN)
//
// Every way of becoming moving goes through one step (was_moving, reported_moving,
// times_moving: lmap.cpp, become_moving). The filter operations that go with a
// transition (add, remove, correct) are the robot's; the L-map does not know the
// filter. Fixed capacity: one entry per possible id, allocated at construction.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "elaslam/robot_node/robot_options.hpp"

namespace elaslam {

enum class LandmarkStatus : std::uint8_t {
  kUnknown = 0,  // never seen
  kCandidate,    // seen, not yet trusted: in the filter as an inert state (corrects nothing)
  kStatic,       // in the filter
  kMoving,       // found moving; out of the filter until it is seen again
};
const char* to_string(LandmarkStatus s);

struct LMapEntry {
  LandmarkStatus status = LandmarkStatus::kUnknown;
  Eigen::Vector2d position = Eigen::Vector2d::Zero();  // [m] p_LinW from g(R, y) at the last sighting
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();        // [m^2] its covariance (pose and measurement)
  int last_seen_frame = -1;
  int consistent_sightings = 0;  // consecutive sightings consistent with `position`
  int outside_streak = 0;        // consecutive out-of-ELA verdicts (STATIC) / inconsistent sightings (CANDIDATE)
  int missing_frames = 0;        // consecutive frames expected in view but not seen
  int status_frame = -1;         // frame of the last status change
  int reported_frame = -1000000; // frame of the last ADD / UPDATE / RETURN sent for it
  int moved_frame = -1;          // frame at which a STATIC landmark was last found moving
  int moving_frame = -1;         // frame of the newest finding or notice that it moves (any status)
  bool was_moving = false;       // it has been MOVING before: re-adding it is a RETURN
  bool reported_moving = false;  // this robot's MOVING event went out and no ADD / RETURN since
  /// STATIC, but evicted from the full filter (Robot::make_room): `position` and
  /// `cov` hold its last filter estimate, which the robot's snapshots keep listing.
  /// Any status change clears it.
  bool archived = false;
  int times_moving = 0;          // how often it has been found (or told) moving
  /// STATIC, and since it was (re)confirmed judged consistent together with another
  /// landmark in the same frame (not alone): robot.ela.lone_needs_check lets only
  /// such a landmark correct the pose when it is the only one in view.
  bool checked = false;
  // A candidate's whitened innovations summed over its consistent sightings: white
  // for a static landmark (|sum|^2 / n is chi-square, 2 dof), drifting for a slow
  // mover that each single test would let through.
  Eigen::Vector2d innovation_sum = Eigen::Vector2d::Zero();
  int innovations = 0;
  // A STATIC landmark's whitened innovations, exponentially weighted (drift test).
  Eigen::Vector2d drift = Eigen::Vector2d::Zero();
};

/// The lifecycle's thresholds (RobotOptions, docs/design.md section 4).
struct LifecycleRules {
  int confirm_frames = 3;       // consistent sightings before a new candidate becomes STATIC
  int confirm_frames_few = 0;   // the same while the robot has few static landmarks (set_few_static), 0: off
  int return_frames = 6;        // the same for a landmark that has been moving
  bool return_backoff = false;  // return_frames doubles with every further time it is found moving
  int moving_after = 2;         // consecutive out-of-ELA verdicts / inconsistent sightings before MOVING
  int missing_needed = 3;       // consecutive expected-but-unseen frames before MOVING
};

/// The rules of a robot's options (missing_needed: missing_frames, or more for a
/// sensor with detection_probability < 1).
LifecycleRules lifecycle_rules(const RobotOptions& o);

class LMap {
 public:
  explicit LMap(int max_landmark_id, const LifecycleRules& rules = {});
  void clear();
  bool valid_id(int id) const { return id >= 0 && id < static_cast<int>(entries_.size()); }
  const LMapEntry& operator[](int id) const { return entries_[static_cast<std::size_t>(id)]; }
  int size() const { return static_cast<int>(entries_.size()); }
  int count(LandmarkStatus s) const;
  const LifecycleRules& rules() const { return rules_; }

  // ---- sightings ---------------------------------------------------------------------
  /// Observed in `frame` (every observation, before the frame's steps).
  void seen(int id, int frame) { at(id).last_seen_frame = frame; }
  /// The world position of this sighting, g(R, y), and its covariance.
  void record_sighting(int id, const Eigen::Vector2d& p_LinW, const Eigen::Matrix2d& cov);
  /// An ADD, RETURN or UPDATE for it went out in `frame` (rate limit of UPDATEs).
  void reported(int id, int frame) { at(id).reported_frame = frame; }

  // ---- candidates --------------------------------------------------------------------
  /// New, back after moving or after a gap, or inconsistent: a CANDIDATE anchored at
  /// this sighting, with a streak of one.
  void anchor_candidate(int id, int frame);
  /// A consistent sighting; true when the streak has earned STATIC (confirm_frames,
  /// or return_frames after it has moved).
  bool candidate_consistent(int id);
  /// This frame's robot had fewer than 3 static landmarks to correct it.
  void set_few_static(bool few) { few_static_ = few; }
  /// An inconsistent sighting; true when this one makes it MOVING (moving_after in a
  /// row) and no MOVING has been reported for it yet: report it now.
  bool candidate_inconsistent(int id);
  /// Unseen too long: it left the filter; its streak starts over.
  void drop_candidate(int id);
  /// A STATIC landmark evicted from the filter keeps its last estimate here (archived).
  void archive(int id, const Eigen::Vector2d& position, const Eigen::Matrix2d& cov);
  /// An archived landmark back in the filter: STATIC as before.
  void unarchive(int id) { at(id).archived = false; }
  /// CANDIDATE -> STATIC. Returns true when it comes back after moving (a RETURN).
  bool confirm(int id, int frame);
  /// The candidate drift test's sum: adds one whitened innovation.
  const LMapEntry& add_innovation(int id, const Eigen::Vector2d& whitened);

  // ---- mapped (STATIC) landmarks -----------------------------------------------------
  /// An inside-ELA verdict: the out-of-ELA streak ends. `with_others`: judged with
  /// other landmarks of the frame that agree (eq 16, the clique), not alone.
  void inside_ela(int id, bool with_others) {
    LMapEntry& e = at(id);
    e.outside_streak = 0;
    e.checked = e.checked || with_others;
  }
  /// An out-of-ELA verdict; true when it is the moving_after-th in a row.
  bool outside_ela(int id) { return ++at(id).outside_streak >= rules_.moving_after; }
  /// Expected in view (and not seen) or not; true when it has been missing for
  /// missing_needed frames in a row.
  bool missed(int id, bool expected);
  /// The drift test's sum, s <- lambda s + w; returns the new sum.
  const Eigen::Vector2d& add_drift(int id, double lambda, const Eigen::Vector2d& whitened);
  /// A STATIC landmark found moving (ELA or missing): it left the filter; MOVING, or
  /// re-anchored as a CANDIDATE where it is seen now (`reanchored`).
  void found_moving(int id, int frame, bool reanchored);

  // ---- modes ekf and gated -----------------------------------------------------------
  /// Mapped at its first sighting, without the candidate step.
  void map_at_once(int id, int frame) { set_status(id, LandmarkStatus::kStatic, frame); }

  // ---- main_robot ---------------------------------------------------------------------
  /// A dynamic notice: coming back needs return_frames sightings even when this
  /// robot does not hold it; MOVING when it `left_filter` for it.
  void told_moving(int id, int frame, bool left_filter);

  // ---- the whole map ------------------------------------------------------------------
  /// Every recorded position (last sightings, archived estimates) carried by the
  /// rigid motion p -> R(rotation) p + translation, covariances turned with it
  /// (Robot::relocalise moves the filters by the same motion).
  void apply_rigid_motion(double rotation, const Eigen::Vector2d& translation);

  // ---- state file (robot_state.cpp, which validates the entry) ------------------------
  void restore(int id, const LMapEntry& e) { at(id) = e; }

 private:
  LMapEntry& at(int id) { return entries_[static_cast<std::size_t>(id)]; }
  void set_status(int id, LandmarkStatus s, int frame);
  static void restart_streak(LMapEntry* e, int sightings);
  static void become_moving(LMapEntry* e, int frame, bool reported);
  int sightings_to_confirm(const LMapEntry& e) const;

  LifecycleRules rules_;
  bool few_static_ = false;
  std::vector<LMapEntry> entries_;
};

}  // namespace elaslam

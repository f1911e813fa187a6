// SPDX-License-Identifier: Apache-2.0
#include "elaslam/robot_node/lmap.hpp"

#include "elaslam/common/geometry.hpp"

#include <algorithm>
#include <cmath>

namespace elaslam {

const char* to_string(LandmarkStatus s) {
  switch (s) {
    case LandmarkStatus::kUnknown: return "unknown";
    case LandmarkStatus::kCandidate: return "candidate";
    case LandmarkStatus::kStatic: return "static";
    case LandmarkStatus::kMoving: return "moving";
  }
  return "?";
}

LifecycleRules lifecycle_rules(const RobotOptions& o) {
  LifecycleRules r;
  r.confirm_frames = o.confirm_frames;
  r.confirm_frames_few = o.confirm_frames_few;
  r.return_frames = o.return_frames;
  r.return_backoff = o.return_backoff;
  r.moving_after = o.moving_after;
  // A sensor that misses landmarks (detection_probability < 1) must miss one n
  // frames in a row before it counts: (1 - p_d)^n <= 1 - the ELA gate probability.
  r.missing_needed = o.missing_frames;
  if (o.detection_probability < 1.0 && o.missing_frames > 0) {
    const double n = std::log(1.0 - o.ela_gate_probability) / std::log(1.0 - o.detection_probability);
    r.missing_needed = std::max(r.missing_needed, static_cast<int>(std::ceil(n)));
  }
  return r;
}

LMap::LMap(int max_landmark_id, const LifecycleRules& rules)
    : rules_(rules), entries_(static_cast<std::size_t>(std::max(max_landmark_id, 0))) {}

void LMap::clear() { std::fill(entries_.begin(), entries_.end(), LMapEntry{}); }

int LMap::count(LandmarkStatus s) const {
  return static_cast<int>(std::count_if(entries_.begin(), entries_.end(),
                                        [s](const LMapEntry& e) { return e.status == s; }));
}

void LMap::set_status(int id, LandmarkStatus s, int frame) {
  LMapEntry& e = at(id);
  if (e.status != s) e.status_frame = frame;
  e.status = s;
  e.archived = false;  // whatever it becomes, it is handled in the filter from now on
  e.checked = false;   // and has not been judged with another since
}

void LMap::restart_streak(LMapEntry* e, int sightings) {
  e->consistent_sightings = sightings;
  e->innovation_sum.setZero();
  e->innovations = 0;
}

// The one step every way of becoming moving shares (a STATIC landmark out of its ELA
// or missing, a candidate inconsistent moving_after times, a dynamic notice): from
// now on it needs return_frames consistent sightings to come back, and coming back
// is a RETURN. `reported`: this robot's own finding, which its stream reports as
// MOVING (a notice is another robot's: see told_moving).
void LMap::become_moving(LMapEntry* e, int frame, bool reported) {
  e->was_moving = true;
  if (reported) e->reported_moving = true;
  e->moving_frame = frame;
  ++e->times_moving;
}

// Sightings a candidate needs: confirm_frames when new; return_frames after it
// has moved, doubled for every further time it was found moving when
// return_backoff is on (a landmark that stops and goes again and again, such as a
// robot, earns less trust each time).
int LMap::sightings_to_confirm(const LMapEntry& e) const {
  if (!e.was_moving)
    return few_static_ && rules_.confirm_frames_few > 0 ? std::min(rules_.confirm_frames, rules_.confirm_frames_few)
                                                        : rules_.confirm_frames;
  if (!rules_.return_backoff) return rules_.return_frames;
  return rules_.return_frames << std::min(std::max(e.times_moving - 1, 0), 10);
}

void LMap::record_sighting(int id, const Eigen::Vector2d& p_LinW, const Eigen::Matrix2d& cov) {
  LMapEntry& e = at(id);
  e.position = p_LinW;
  e.cov = cov;
}

void LMap::anchor_candidate(int id, int frame) {
  set_status(id, LandmarkStatus::kCandidate, frame);
  restart_streak(&at(id), 1);
}

bool LMap::candidate_consistent(int id) {
  LMapEntry& e = at(id);
  e.outside_streak = 0;
  return ++e.consistent_sightings >= sightings_to_confirm(e);
}

bool LMap::candidate_inconsistent(int id) {
  LMapEntry& e = at(id);
  if (++e.outside_streak < rules_.moving_after || e.reported_moving) return false;
  become_moving(&e, e.last_seen_frame, true);  // seen in this frame (seen() comes first)
  return true;
}

void LMap::drop_candidate(int id) { restart_streak(&at(id), 0); }

void LMap::archive(int id, const Eigen::Vector2d& position, const Eigen::Matrix2d& cov) {
  LMapEntry& e = at(id);
  e.archived = true;
  e.position = position;
  e.cov = cov;
  e.missing_frames = 0;
  e.outside_streak = 0;
}

void LMap::apply_rigid_motion(double rotation, const Eigen::Vector2d& translation) {
  const Eigen::Matrix2d R = elaslam::rotation(rotation);
  for (LMapEntry& e : entries_) {
    if (e.status == LandmarkStatus::kUnknown) continue;
    e.position = R * e.position + translation;
    e.cov = R * e.cov * R.transpose();
  }
}

bool LMap::confirm(int id, int frame) {
  set_status(id, LandmarkStatus::kStatic, frame);
  LMapEntry& e = at(id);
  e.missing_frames = 0;
  e.drift.setZero();
  e.reported_moving = false;
  e.outside_streak = 0;
  return e.was_moving;
}

const LMapEntry& LMap::add_innovation(int id, const Eigen::Vector2d& whitened) {
  LMapEntry& e = at(id);
  e.innovation_sum = e.innovation_sum + whitened;
  e.innovations = e.innovations + 1;
  return e;
}

bool LMap::missed(int id, bool expected) {
  LMapEntry& e = at(id);
  if (!expected) {
    e.missing_frames = 0;
    return false;
  }
  return ++e.missing_frames >= rules_.missing_needed;
}

const Eigen::Vector2d& LMap::add_drift(int id, double lambda, const Eigen::Vector2d& whitened) {
  LMapEntry& e = at(id);
  e.drift = lambda * e.drift + whitened;
  return e.drift;
}

void LMap::found_moving(int id, int frame, bool reanchored) {
  LMapEntry& e = at(id);
  become_moving(&e, frame, true);
  e.missing_frames = 0;
  e.outside_streak = 0;
  e.moved_frame = frame;
  if (reanchored) {
    anchor_candidate(id, frame);
  } else {
    set_status(id, LandmarkStatus::kMoving, frame);
  }
}

// A notice is another robot's finding: this robot's stream has not said MOVING, so
// its own later finding is still reported (were a notice to set reported_moving,
// this robot's MOVING would be silenced for good once another robot had RETURNed
// the landmark at main).
void LMap::told_moving(int id, int frame, bool left_filter) {
  LMapEntry& e = at(id);
  become_moving(&e, frame, false);
  if (!left_filter) return;
  set_status(id, LandmarkStatus::kMoving, frame);
  restart_streak(&e, 0);
  e.missing_frames = 0;
  e.outside_streak = 0;
}

}  // namespace elaslam

// The robot's local map, L-map (paper section 3.3, Algorithm 1; DESIGN.md section 5):
// per landmark id its status, last world position and covariance from the inverse
// observation g(R, y), last frame seen and consecutive consistent sightings.
// Fixed capacity: one entry per possible id, allocated at construction.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

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
  int missing_frames = 0;        // consecutive frames expected in view but not seen
  int status_frame = -1;         // frame of the last status change
  int reported_frame = -1000000; // frame of the last ADD / UPDATE / RETURN sent for it
  bool was_moving = false;       // it has been MOVING before: re-adding it is a RETURN
  bool reported_moving = false;  // a MOVING event went out and no ADD / RETURN since
  int times_moving = 0;          // how often it has been found (or told) moving
  // A candidate's whitened innovations summed over its consistent sightings: white
  // for a static landmark (|sum|^2 / n is chi-square, 2 dof), drifting for a slow
  // mover that each single test would let through.
  Eigen::Vector2d innovation_sum = Eigen::Vector2d::Zero();
  int innovations = 0;
  // A STATIC landmark's whitened innovations, exponentially weighted (drift test).
  Eigen::Vector2d drift = Eigen::Vector2d::Zero();

  /// A candidate's streak starts over with `sightings` consistent sightings.
  void restart_streak(int sightings) {
    consistent_sightings = sightings;
    innovation_sum.setZero();
    innovations = 0;
  }
};

class LMap {
 public:
  explicit LMap(int max_landmark_id);
  void clear();
  bool valid_id(int id) const { return id >= 0 && id < static_cast<int>(entries_.size()); }
  LMapEntry& operator[](int id) { return entries_[static_cast<std::size_t>(id)]; }
  const LMapEntry& operator[](int id) const { return entries_[static_cast<std::size_t>(id)]; }
  void set_status(int id, LandmarkStatus s, int frame);
  int size() const { return static_cast<int>(entries_.size()); }
  int count(LandmarkStatus s) const;

 private:
  std::vector<LMapEntry> entries_;
};

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// A robot's tracks of its moving landmarks (docs/tracking.md): a pool of MoverTrack
// slots, sized at construction, and which landmark holds which. Robot starts a track
// when it finds a landmark moving (or sees one it was told moves), feeds it the
// sightings that the map keeps out, and ends it when the landmark is STATIC again
// or has gone unseen for `lost_after_s`. A full pool is counted (`full`), as every
// capacity of the robot is. No allocation after construction.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "elaslam/common/contract.hpp"
#include "elaslam/robot_node/mover_track.hpp"

namespace elaslam {

/// robot.tracking (the optional config section).
struct TrackingOptions {
  bool enabled = true;
  int max_tracks = contract::kDefaultTrackPool;  // tracks held at once (the pool's slots)
  double lost_after_s = 3.0;  // [s] a track unseen this long ends
  /// A candidate with a track returns to the map (RETURN) only once its track finds
  /// it stopped, not as soon as return_frames sightings agree (a slow mover does).
  bool return_when_stopped = false;
  /// A candidate whose track is validated and likeliest static or bounded is
  /// followed: its state in the filter moves as the track predicts, and its
  /// sightings correct the robot (Robot::follow_movers); other movers stay
  /// consider states. A followed mover returns to the map only once its track
  /// finds it stopped.
  bool correct_pose = false;
  MoverTrackOptions track;
};

/// One operation of a frame on the tracks (Robot queues them while it judges the
/// frame's sightings and applies them at the frame's end, MoverTracks::apply).
struct TrackOp {
  enum class Kind : std::uint8_t { kBegin, kSee, kEnd } kind = Kind::kSee;
  int id = -1;
  RangeBearing z;
  Eigen::Vector2d anchor = Eigen::Vector2d::Zero();  // kBegin; kSee: where a new track anchors
  bool may_begin = false;  // kSee: the landmark was found or told moving before
};

struct TrackCounters {
  std::int64_t started = 0;   // tracks started
  std::int64_t returned = 0;  // ... ended because the landmark became STATIC again
  std::int64_t lost = 0;      // ... ended unseen for lost_after_s
  std::int64_t ended = 0;     // ... ended otherwise (a reset of the robot's map, a relocalisation)
  std::int64_t updates = 0;   // sightings fed to tracks
  std::int64_t outliers = 0;  // sightings no model explained, held back (MoverTrack::update)
  std::int64_t restarts = 0;  // ... a second in a row that agreed with the first: the track started again
  std::int64_t full = 0;      // tracks not started: every slot taken
};

class MoverTracks {
 public:
  /// Throws std::invalid_argument naming a bad option (MoverTrack's, max_tracks).
  MoverTracks(const TrackingOptions& options, int max_landmark_id);

  bool enabled() const { return options_.enabled; }
  const TrackingOptions& options() const { return options_; }

  /// Starts (or starts again) landmark id's track at the sighting, anchored at
  /// `anchor` (its last static position), at time t [s]. False when tracking is off,
  /// the id is out of range or no slot is free (counted in `full`).
  bool begin(int id, const TrackSighting& s, const Eigen::Vector2d& anchor, double t);
  /// Predicts id's track to t and corrects it with the sighting; false when id has
  /// no track.
  bool see(int id, const TrackSighting& s, double t);
  /// Predicts id's track to t [s] (nothing when id has no track, or t is not
  /// later than its time): its estimate before a sighting at t.
  void predict(int id, double t);
  /// Ends id's track (`returned`: the landmark is STATIC again).
  void end(int id, bool returned);
  /// Ends every track unseen since before t - lost_after_s.
  void expire(double t);
  /// Ends every track (counted in `ended`).
  void clear();
  /// Applies one frame's operations in order at time t [s], each sighting taken
  /// with `base`'s pose, pose covariance and noise (its z replaced by the op's);
  /// then the tracks unseen lately end (expire) and every other one is predicted
  /// to t: a track's estimate is always of the last frame's time.
  void apply(const std::vector<TrackOp>& ops, const TrackSighting& base, double t);

  bool has(int id) const { return slot_of(id) >= 0; }
  /// id's track; has(id) must hold.
  const MoverTrack& track(int id) const { return pool_[static_cast<std::size_t>(slot_of(id))]; }
  /// The landmarks with a track, in the order their tracks started.
  const std::vector<int>& ids() const { return ids_; }
  const TrackCounters& counters() const { return counters_; }

 private:
  int slot_of(int id) const {
    return id >= 0 && id < static_cast<int>(slot_.size()) ? slot_[static_cast<std::size_t>(id)] : -1;
  }
  void release(int id);

  TrackingOptions options_;
  std::vector<MoverTrack> pool_;     // max_tracks slots
  std::vector<double> last_seen_;    // [s] per slot
  std::vector<int> free_;            // free slots (a stack)
  std::vector<int> slot_;            // per landmark id: its slot, -1 without a track
  std::vector<int> ids_;             // landmarks with a track (reserved: max_tracks)
  TrackCounters counters_;
};

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// Options of one robot node: the `robot:` section of a config file.
#pragma once

#include <string>

#include "elaslam/common/config.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/common/limits.hpp"
#include "elaslam/robot_node/ekf_slam.hpp"
#include "elaslam/robot_node/mover_tracks.hpp"

namespace elaslam {

enum class Mode { kEkf, kGated, kEla, kConsensus };
const char* to_string(Mode m);
/// Parse "ekf" | "gated" | "ela" | "consensus"; false when unknown.
bool parse_mode(const std::string& s, Mode* m);

struct RobotOptions {
  Mode mode = Mode::kEla;
  EkfOptions ekf;  // robot.filter, and robot.odometry_calibration (ekf.calibration)
  TrackingOptions tracking;  // robot.tracking: the moving landmarks' tracks (docs/tracking.md)
  /// Observations a SENSOR frame may carry (robot.filter.max_observations; a frame
  /// with more is refused). Sizes the frame buffers at start-up.
  int max_observations = contract::kMaxObsPerFrame;
  double initial_sigma_xy = 0.001;     // [m]   prior std dev of the known initial position
  double initial_sigma_theta = 0.001;  // [rad] prior std dev of the known initial heading

  // ELA gate and L-map rules (docs/design.md section 4).
  double ela_gate_probability = 0.99;   // chi-square probability of the ELA / consensus tests
  int confirm_frames = 3;               // consistent sightings before a candidate becomes STATIC
  /// When fewer than 3 STATIC landmarks corrected the robot in this frame, a new
  /// candidate needs only this many (0: off; the robot needs landmarks more than
  /// it fears a mover).
  int confirm_frames_few = 0;
  int return_frames = 6;                // the same for a landmark that has been MOVING
  /// return_frames doubles with every further time a landmark is found moving.
  bool return_backoff = false;
  /// Consistent candidate sightings refine the candidate's own estimate (a
  /// landmark-only "consider" update) while the robot's pose stays untouched.
  bool candidate_updates = true;
  /// Also test the running sum of a candidate's whitened innovations (a slow mover
  /// drifts consistently; a static landmark's innovations average out).
  bool candidate_drift_test = false;
  /// Frames of filter history kept (FilterHistory, modes ela and consensus; 0: off):
  /// when a candidate is confirmed, its sightings of the last N frames correct the
  /// robot and the map as they would have had it been trusted from the start
  /// (docs/adr/0007-candidate-history.md).
  int candidate_history_frames = 0;
  /// Drift test of STATIC landmarks: their whitened innovations summed with this
  /// forgetting factor (0: off); the sum's chi-square test failing counts as an
  /// out-of-ELA verdict.
  double drift_memory = 0.0;
  double drift_gate_probability = 0.9999;  // the sum is tested every frame: a stricter gate
  /// A candidate unseen for this many frames starts over (1: it must be seen in
  /// every frame; a sensor that reports a landmark only every few frames needs more).
  int candidate_gap_frames = 1;
  /// The consistency monitor (consistency.hpp; the optional `consistency:` map):
  /// the NIS of the corrections over this many frames against its quantile at
  /// `consistency_probability` (0 frames: off). When it fails, the robot says so
  /// (FAULT_INCONSISTENT in STATUS, an alert) and, with `consistency_recover`,
  /// widens its pose covariance by recovery_sigma_xy / _theta so that the landmarks
  /// in view can pull the pose back (a relocalisation in its own map).
  int consistency_window_frames = 0;
  double consistency_probability = 0.9999;
  bool consistency_recover = false;
  double recovery_sigma_xy = 0.5;             // [m]
  double recovery_sigma_theta = 10.0 * kPi / 180.0;  // [rad]
  /// The team's map back to the robot (team_aid.hpp; the optional `team_map:` map).
  /// With `fuse`, the robot runs a second ("aided") filter: the same observations,
  /// plus the other robots' map from main_robot's TEAM_MAP_<r>, fused without double
  /// counting. The aided filter gives the robot's pose (POSE); the own filter, which
  /// holds the robot's own data only, gives its events and snapshots, and the ELA
  /// gate and the lifecycle judge against it (so that what the robot reports never
  /// depends on what the team sent: docs/adr/0031-no-verdict-on-a-drifted-filter.md).
  bool team_map_fuse = false;
  double team_map_min_gain = 0.05;  // TeamChannel: fuse an increment when tr(P_ll dY) >= this
  /// A team estimate is fused only when it agrees with the aided filter's estimate
  /// of the landmark: (g - l)^T (P_ll + G)^-1 (g - l) within the chi-square
  /// quantile of this probability (2 dof). 1: no test.
  double team_map_gate_probability = 0.9999;
  /// The gauge test (Robot::apply_team_map): a robot whose map is right in itself
  /// but wrong as a whole moves onto the team map by one rigid motion.
  bool team_map_gauge_test = true;
  /// No gate on a drifted filter: a frame in which the own filter's pose is beyond
  /// its covariance from the aided filter's (pose_drifted, 3 dof at
  /// team_map_gate_probability) finds no mover (ELA or missing).
  bool team_map_drift_check = true;
  /// A candidate's team estimate (Robot::hold_team_estimate): tested and held in the
  /// aided filter's history as nothing; fused as of its team map if the candidate is
  /// confirmed within the history's window (candidate_history_frames > 0), dropped
  /// otherwise: the aided filter becomes the one that had trusted the landmark from
  /// its first sighting, team map included.
  bool team_map_hold_candidates = false;
  int moving_after = 2;                 // consecutive out-of-ELA sightings before MOVING
  /// Whether a mapped landmark that fails its test while it is the only one in view
  /// (the innovation fallback) counts towards MOVING. Off: it is skipped only.
  bool lone_verdicts = true;
  /// Whether a mapped landmark judged alone (the only one in view, or the only one
  /// left) corrects the pose only once it has been judged consistent with another
  /// landmark in some frame since it was (re)confirmed (LMapEntry::checked). On: a
  /// landmark only ever seen alone cannot tell its own slow motion from the
  /// robot's, and dragged the pose along (a robot driving at 0.06 m/s in MRCLAM).
  bool lone_needs_check = false;
  int missing_frames = 3;               // expected-but-unseen frames before MOVING (0: rule off)
  double sensor_range = 4.0;            // [m] radius of the field of view (D / 2)
  double fov_margin = 0.5;              // [m] "well inside the field of view": range < sensor_range - margin
  double fov_half_angle = kPi;          // [rad] a cone sensor's half-angle (pi: all around)
  /// Probability that a landmark in view is reported in a frame; below 1 the
  /// expected-but-missing rule waits until a miss streak that long is as unlikely
  /// as a false alarm of the ELA gate.
  double detection_probability = 1.0;

  // Node behaviour.
  int snapshot_period_frames = 10;      // LMAP_SNAPSHOT every N frames
  int update_period_frames = 1;         // at most one UPDATE event per landmark per N frames
  /// CANDIDATES_<r> (for the viewer) every N frames while the robot has candidates,
  /// and once when the last one left; 0: never.
  int candidates_period_frames = 1;
  /// A frame's events go to main_robot in LMAP_EVENTS messages (lmap_events_t, up to
  /// contract::kMaxBatchEvents each) rather than one LMAP_EVENT per event: one
  /// datagram where there were ~10, the same events in the same order.
  bool batch_events = true;
  int max_frame_gap = 50;               // a larger forward jump in frame numbers is refused (bad input)
  /// A robot whose first frame is not frame 0 (started late, or restarted without
  /// a state file) takes the odometer's dead reckoning over that many frames of
  /// this motion as its prior (dead_reckoning_cov, docs/adr/0023-late-start-prior.md).
  double late_start_step_m = 0.15;      // [m]   the most a robot moves per frame
  double late_start_turn = deg2rad(1.5);  // [rad] its turn per frame
  /// The robot_node process saves its state file (--state) at most this often (0:
  /// after every frame), and at exit.
  double state_save_interval_s = 0.5;   // [s]

  // What a message may say (docs/security.md).
  MessageLimits limits;
  /// The most the robot can move in one frame, with margin: an odometer increment
  /// over k frames beyond k times these is refused as a glitch or forgery (not the
  /// late start's bounds above, which describe the paths: these bound the vehicle).
  double max_step_m = 1.0;              // [m] per frame
  double max_turn = deg2rad(90.0);      // [rad] per frame
  /// A refused odometer jump that the next readings continue (each within the
  /// bounds above of the one before) is a real change of the odometer's origin
  /// (a reset): after this many such frames in a row the robot re-anchors on it,
  /// the motion since its last frame unknown within the bounds above.
  int odometry_reanchor_frames = 3;
  /// A forward jump of more than this many frames is taken only when the next frame
  /// confirms it (continues it within this many frames): one forged frame number
  /// never makes the robot refuse the real ones. Up to node.max_frame_gap.
  int confirm_jump_frames = 5;
  /// main_robot not heard (none of its channels) for this long while frames are
  /// processed: FAULT_MAIN_SILENT in STATUS and a FAULT line (0: not watched).
  double main_silent_s = 5.0;  // [s]
};

/// Read the `robot:` section (see config/paper.yaml for every key and its unit).
void parse(config::Reader& r, RobotOptions* o);

/// Settings that are valid together but known to work badly, as one line of advice
/// for stderr ("" when none): `ela.lone_needs_check` on while `team_map.fuse` is off
/// (a robot alone needs every lone correction; on MRCLAM dataset1 one robot
/// diverged to 1.8 m that way: docs/mrclam.md), in a mode that uses it.
std::string config_advice(const RobotOptions& o);

/// Load the `robot:` section of a config file; other sections are allowed.
/// Throws config::ConfigError listing every problem.
RobotOptions load_robot_options(const std::string& path, std::string* effective_yaml = nullptr);

}  // namespace elaslam

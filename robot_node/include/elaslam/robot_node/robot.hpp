// SPDX-License-Identifier: Apache-2.0
// One frame of Algorithm 1 (paper section 3.3) end to end, for every mode: predict
// from the odometer increment, judge the mapped landmarks in view (ElaGate), correct
// the filter with the accepted ones, move each landmark along its lifecycle (LMap):
// candidates confirmed or re-anchored, moving ones removed, expected-but-missing
// ones found moving; apply dynamic notices; produce the outgoing map events. Robot
// only orders the steps and pairs each L-map transition with its filter operation
// (EkfSlam). No I/O; fixed memory after construction
// (tests/robot_node/test_frame_no_alloc.cpp).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "elaslam/common/contract.hpp"
#include "elaslam/robot_node/consistency.hpp"
#include "elaslam/robot_node/ekf_slam.hpp"
#include "elaslam/robot_node/filter_pair.hpp"
#include "elaslam/robot_node/ela_gate.hpp"
#include "elaslam/robot_node/filter_history.hpp"
#include "elaslam/robot_node/lmap.hpp"
#include "elaslam/robot_node/mover_tracks.hpp"
#include "elaslam/robot_node/rigid_fit.hpp"
#include "elaslam/robot_node/robot_options.hpp"
#include "elaslam/robot_node/team_aid.hpp"

namespace elaslam {

struct Observation {
  int landmark_id = -1;
  RangeBearing z;
};

/// One sensor frame, already validated (see RobotNode for the checks).
struct FrameInput {
  /// Room for `capacity` observations (RobotOptions::max_observations), allocated here.
  explicit FrameInput(int capacity = contract::kMaxObsPerFrame) : obs(static_cast<std::size_t>(capacity)) {}
  int frame = 0;
  /// [us] when the frame was taken (sensor_frame_t::utime): the time an odometer
  /// increment spans, for the calibration's turn bias and random walk (Robot::predict).
  std::int64_t utime = 0;
  Pose2 odometer;        // cumulative odometer reading, odometry frame O (= W at start)
  OdometryNoise noise;   // odometry noise model of this robot
  /// The odometer's origin changed (RobotNode: a jump the following readings
  /// confirmed): no increment from the last reading; the motion since the last frame
  /// is unknown within options.max_step_m / max_turn per frame.
  bool reanchor = false;
  int num_obs = 0;
  std::vector<Observation> obs;  // first num_obs valid; never resized after construction
};

/// Values match landmark_event_t's constants.
enum class EventKind : std::int8_t { kAdd = 1, kUpdate = 2, kMoving = 3, kReturn = 4 };
const char* to_string(EventKind k);

struct MapEvent {
  EventKind kind = EventKind::kUpdate;
  int landmark_id = -1;
  int frame = 0;
  Eigen::Vector2d position = Eigen::Vector2d::Zero();  // [m] W
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();        // [m^2]
};

/// What happened in one frame.
struct FrameSummary {
  int num_obs = 0;
  int num_accepted = 0;   // corrected the filter
  int num_rejected = 0;   // refused by a gate (outside ELA, innovation gate)
  int num_unchecked = 0;  // inside, but alone and never judged with another (lone_needs_check)
  int num_added = 0;      // landmarks added to the filter (ADD or RETURN)
  int num_moving = 0;     // landmarks removed as moving (ELA, missing)
  int num_candidates = 0; // observations of landmarks not (yet) in the filter
  int filter_faults = 0;  // filter operations refused by its health checks (filter_full included)
  int filter_full = 0;    // landmarks not added: every slot of the filter taken (a capacity limit)
  int evicted = 0;        // landmarks that left the full filter to make room (make_room)
  int restored = 0;       // evicted landmarks seen again and back in the filter
  int events_dropped = 0; // events beyond the fixed event buffer (should stay 0)
  double nis = 0.0;           // the frame's corrections' NIS (sum of d2; own filter) ...
  int nis_dof = 0;            // ... and its degrees of freedom (2 per correction)
  bool inconsistent = false;  // the consistency monitor's verdict after this frame
  bool recovered = false;     // ... and the pose covariance was widened (consistency_recover)
  int movers_followed = 0;    // candidates followed this frame (tracking.correct_pose: validated, static or bounded)
  int mover_corrections = 0;  // ... whose sightings corrected the filter
  int drifted = 0;            // 1: the own filter had drifted from the aided one: no MOVING finding (own_filter_drifted)
};

/// One landmark of a team map (TEAM_MAP_<r>).
struct TeamEstimate {
  int landmark_id = -1;
  Eigen::Vector2d position = Eigen::Vector2d::Zero();  // [m] W
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();        // [m^2]
};

/// The team map's effect on this robot (RobotNode reports them).
struct TeamCounters {
  std::int64_t offered = 0;  // team estimates received for landmarks the aided filter holds as STATIC
  std::int64_t fused = 0;    // increments fused (a held one when its candidate is confirmed)
  std::int64_t held = 0;     // increments held for a candidate (team_map_hold_candidates)
  std::int64_t gated = 0;    // team estimates that failed the consistency test (team_map_gate_probability)
  std::int64_t refused = 0;  // increments the aided filter refused (its health checks)
  double nis_sum = 0.0;      // sum of the fused increments' d2 (2 dof each: about 2 per increment when consistent)
  std::int64_t lost = 0;     // team maps most of whose estimates disagreed with the robot's: the robot was lost
  std::int64_t relocalised = 0;  // team maps that moved the robot's whole state by a rigid motion (apply_team_map)
};

/// What one team map did (Robot::apply_team_map).
enum class TeamVerdict : std::uint8_t {
  kNone,         // no aided filter, or nothing the robot holds as STATIC in it
  kHeld,         // the estimates that agree were fused; the robot kept its map
  kLost,         // most disagreed and the robot saw trouble itself: every one fused, untested
  kRelocalised,  // most disagreed, one rigid motion made most agree: the robot moved by it
};
const char* to_string(TeamVerdict v);

/// The rigid motion of the last relocalisation and what it was found on.
struct Relocalisation {
  int frame = -1;            // the robot's last frame when it happened (-1: never)
  double rotation = 0.0;     // [rad] the motion applied to the robot's state: p -> R p + t
  Eigen::Vector2d translation = Eigen::Vector2d::Zero();  // [m]
  double rotation_sigma = 0.0;     // [rad] its standard deviations (the fit's)
  double translation_sigma = 0.0;  // [m] sqrt of the larger eigenvalue of t's covariance
  int shared = 0;            // landmarks tested (held STATIC by the robot, in the team map)
  int disagreed = 0;         // ... that failed the team-map test before the motion
  int agreed_after = 0;      // ... that passed it after the motion
};

class Robot {
 public:
  Robot(const RobotOptions& options, int robot_id);
  /// The most events one frame can emit: the event buffers are reserved for it.
  static std::size_t event_capacity(const RobotOptions& o);

  /// Forget everything; the next frame initialises the filter at its odometer reading.
  void reset();

  /// Process one frame. Events and gate records of this frame replace the previous ones.
  FrameSummary process(const FrameInput& in);

  /// A dynamic notice from main_robot: drop the landmark as moving (step 5).
  /// Returns true when the robot held it in its filter. Emits no event. Mode ekf (the
  /// baseline that takes every landmark as static) ignores every notice: false.
  bool apply_notice(int landmark_id, int frame);

  /// The estimates of one team map that are due (TEAM_MAP_<r>, the map without this
  /// robot; team_aid.hpp), with options.team_map_fuse: for each STATIC landmark the
  /// robot holds, what it adds to what was fused before goes into the aided filter.
  /// Each is tested against the aided filter's estimate (team_map_gate_probability).
  /// - The gauge test first (options.team_map_gauge_test): when, for each of the
  ///   two filters, at least kTeamMinTested were tested, more than half disagree,
  ///   and one weighted rigid motion that carries the filter's estimates onto the
  ///   team's (rigid_fit.hpp) makes more than half agree (and passes the joint
  ///   tests of gauge_test), and the two filters' motions agree, the robot's map is
  ///   right in itself and wrong as a whole (a heading lost where it saw nothing,
  ///   then everything mapped from there): each filter moves by its motion, the
  ///   L-map with the own one (relocalise), and the estimates that agree then are
  ///   fused: kRelocalised. Maps corrupted in different ways are not one rigid
  ///   motion: no fit makes most of them agree.
  /// - Otherwise, when more than half of at least kTeamMinTested disagree with the
  ///   aided filter and the robot saw trouble itself in the last
  ///   kTroubleMemoryFrames frames (a frame in which every mapped landmark it
  ///   judged, at least kTeamMinTested, failed, or the consistency monitor's
  ///   verdict), the robot, not the team, is wrong (lost): every one is fused,
  ///   untested (the aided filter relocalises against the team's map): kLost.
  /// - Otherwise those that disagree are not fused (one robot's divergence must not
  ///   pull the others): kHeld.
  /// Only a relocalisation changes the own filter (it otherwise holds the robot's own
  /// data only). No allocation.
  TeamVerdict apply_team_map(const TeamEstimate* estimates, int n);
  static constexpr int kTeamMinTested = 3;
  /// "Lately" for the robot's own trouble: the frames a FAULT stays flagged in STATUS.
  static constexpr int kTroubleMemoryFrames = 100;

  // ---- outputs of the last frame ----------------------------------------------
  const std::vector<MapEvent>& events() const { return events_; }
  const std::vector<GateRecord>& gate_records() const { return gate_.records(); }
  const ElaGate& gate() const { return gate_; }
  const ConsistencyMonitor& consistency() const { return monitor_; }

  // ---- state ------------------------------------------------------------------
  /// The own filter: the robot's own observations only; its map is what the robot
  /// reports (events, snapshots).
  const EkfSlam& filter() const { return filters_.own(); }
  /// The robot's best estimate: the aided filter with options.team_map_fuse, else
  /// the own one. Its pose is the robot's pose (POSE).
  const EkfSlam& estimate() const { return filters_.estimate(); }
  const TeamCounters& team_counters() const { return team_counters_; }
  /// The moving landmarks' tracks (robot.tracking, docs/tracking.md): consider
  /// estimates that never correct the robot.
  const MoverTracks& tracks() const { return tracks_; }
  /// The last frame's operations on the tracks, in the order applied: an evaluator
  /// replays them on tracks of its own fed the true pose, which separates tracking
  /// error from localisation error (team_run).
  const std::vector<TrackOp>& track_ops() const { return track_ops_; }
  /// [s] the robot's clock: the frames' stamps since its first frame (step_seconds).
  double clock_s() const { return clock_s_; }
  const Relocalisation& last_relocalisation() const { return relocalisation_; }
  const TeamChannel& team_channel() const { return team_; }
  const LMap& lmap() const { return lmap_; }
  /// The own filter's history (options.candidate_history_frames).
  const FilterHistory& history() const { return filters_.own_history(); }
  const RobotOptions& options() const { return options_; }
  int robot_id() const { return robot_id_; }
  bool initialised() const { return initialised_; }
  /// mean(diag(P)) over the robot pose and the STATIC landmarks: the uncertainty of
  /// the map (paper eq 19); candidates, inert states in the filter, are not the map.
  double map_mean_diag() const;
  int last_frame() const { return last_frame_; }
  const Pose2& last_odometer() const { return last_odometer_; }
  /// The time a prediction from the last frame to `in` spans [s]: the frames'
  /// utime difference, within [0, kMaxFramePeriodS per frame elapsed] (a stamp that
  /// does not advance gives 0; one far ahead is bounded: stamps are the sender's).
  double step_seconds(const FrameInput& in) const;
  static constexpr double kMaxFramePeriodS = 10.0;

 private:
  friend struct RobotStateAccess;  // the state file (robot_state.cpp): saves and restores the members below

  void predict(const FrameInput& in, FrameSummary* s);
  void process_classic(const FrameInput& in, FrameSummary* s);
  void process_ela(const FrameInput& in, FrameSummary* s);
  void correct(int id, const RangeBearing& z, FrameSummary* s);
  void check_consistency(FrameSummary* s);
  void handle_candidates(const FrameInput& in, FrameSummary* s);
  void confirm(int id, const RangeBearing& z, FrameSummary* s);
  void drop_unseen_candidates();
  void check_missing(FrameSummary* s);
  bool expected_in_view(int id, const Pose2& pose) const;
  void mark_moving(int id, const RangeBearing* seen, FrameSummary* s);
  /// The frame's operations on the tracks, in order, applied at the end of the
  /// frame (apply_track_ops) with the robot's pose and covariance then: reading the
  /// covariance mid-frame would settle the filter's pending covariance steps early
  /// and change its rounding, and tracks must change nothing the robot estimates.
  void queue_track(TrackOp::Kind kind, int id, const RangeBearing& z, const Eigen::Vector2d& anchor, bool may_begin);
  void apply_track_ops();
  /// tracking.correct_pose: candidates whose tracks are validated and likeliest
  /// static or bounded move in the filter as their tracks predict (followed).
  void follow_movers(FrameSummary* s);
  /// A free slot in the filter: true when there is one or one was made by evicting
  /// the held landmark farthest from the robot beyond sensor_range that was not
  /// seen this frame (a STATIC one is archived, a candidate dropped); false when
  /// every held landmark is in range (the add then fails with kFull, counted).
  bool make_room(FrameSummary* s);
  /// Archived landmarks seen in this frame back into the filter (modes ela and
  /// consensus): each re-enters at its observation and is tested against its
  /// archived estimate; one that disagrees has moved while out of the filter.
  void restore_archived(const FrameInput& in, FrameSummary* s);
  void record_sighting(int id, const RangeBearing& z);
  void emit(EventKind kind, int id);
  /// A team estimate of a landmark the aided filter holds as STATIC (else false).
  bool team_eligible(int id) const;
  /// Fuse what the team estimate adds (TeamChannel); `test`: only when it agrees.
  bool fuse_team_estimate(const TeamEstimate& e, bool test);
  bool hold_team_estimate(const TeamEstimate& e);
  /// The gauge test of one filter against a team map (apply_team_map).
  struct GaugeTest {
    int tested = 0, disagreed = 0, agreed_after = 0;
    RigidMotion motion;
    bool fires = false;
  };
  GaugeTest gauge_test(const EkfSlam& f, const TeamEstimate* estimates, int n);
  /// Move the own filter and the L-map by `own`'s motion, the aided filter by
  /// `aided`'s (apply_team_map); the histories, the consistency window and the
  /// trouble memory start over.
  void relocalise(const GaugeTest& own, const GaugeTest& aided);
  /// An add_landmark's status: false (counted) unless kOk.
  bool added(EkfStatus st, FrameSummary* s);
  void emit_at(EventKind kind, int id, const Eigen::Vector2d& p, const Eigen::Matrix2d& C);

  RobotOptions options_;
  int robot_id_;
  // The own filter (sole owner of the mean and covariance the robot reports) and,
  // with team_map_fuse, the aided one, with their histories, kept in step.
  FilterPair filters_;
  TeamChannel team_;
  TeamCounters team_counters_;
  Relocalisation relocalisation_;
  std::vector<PointPair> pairs_;  // the team map's landmarks the robot holds (reserved: filter capacity)
  double team_gate_threshold_ = 0.0;  // chi2 quantile, 2 dof, of team_map_gate_probability
  double restore_threshold_ = 0.0;    // chi2 quantile, 2 dof, of drift_gate_probability (restore_archived)
  double drift3_threshold_ = 0.0;     // chi2 quantile, 3 dof, of team_map_gate_probability (own_filter_drifted)
  bool own_drifted_ = false;          // this frame's own_filter_drifted()
  bool own_filter_drifted() const;
  int trouble_frame_ = -1;  // last frame all of whose judged landmarks failed, or found inconsistent
  LMap lmap_;     // sole owner of the per-landmark state and its lifecycle
  MoverTracks tracks_;  // the moving landmarks' tracks (not in the state file: a restart starts none)
  std::vector<TrackOp> track_ops_;  // the last frame's (reserved: two per observation)
  std::vector<int> followed_frame_;  // per landmark id: the last frame follow_movers moved it in (-1: never)
  double clock_s_ = 0.0;  // [s] clock_s()
  ElaGate gate_;  // this frame's verdicts and gate records
  ConsistencyMonitor monitor_;  // NIS of the corrections over a window of frames
  bool initialised_ = false;
  int last_frame_ = -1;
  Pose2 last_odometer_;
  std::int64_t last_utime_ = 0;  // [us] the last frame's FrameInput::utime
  std::vector<int> updated_;      // ids corrected this frame (reserved: one per observation)
  std::vector<MapEvent> events_;  // this frame's events (reserved at construction)
  int events_dropped_ = 0;
};

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// main_robot's message layer, without I/O: a robot's LMAP_EVENT(S) / LMAP_SNAPSHOT /
// POSE pass the checks (main_checks.hpp and the robot's incarnation, frame and seq
// windows), go to the GlobalMap, and tell FrameCompletion what is in; MapPublisher
// fills GLOBAL_MAP, GLOBAL_MOVING and TEAM_MAP_<r>; MainNode ties them together, fills
// DYNAMIC_NOTICE, LMAP_RESYNC and STATUS_MAIN; TrackFusion fuses the robots' TRACKS
// into GLOBAL_TRACKS; MainNode keeps the counters and faults. The
// main_robot process and the in-process team run share it, and both wire it to the
// message layer with MainPorts (main_ports.hpp).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "elaslam/dynamic_notice_t.hpp"
#include "elaslam/global_map_t.hpp"
#include "elaslam/global_tracks_t.hpp"
#include "elaslam/landmark_event_t.hpp"
#include "elaslam/lmap_events_t.hpp"
#include "elaslam/lmap_snapshot_t.hpp"
#include "elaslam/main_robot/frame_completion.hpp"
#include "elaslam/main_robot/global_map.hpp"
#include "elaslam/main_robot/map_publisher.hpp"
#include "elaslam/main_robot/track_fusion.hpp"
#include "elaslam/node_status_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/resync_request_t.hpp"
#include "elaslam/track_list_t.hpp"

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
  std::int64_t map_chunks = 0;           // GLOBAL_MAP chunks of those publications
  std::int64_t moving_sets = 0;          // GLOBAL_MOVING publications (main.moving_repeat_s)
  std::int64_t team_maps_published = 0;  // TEAM_MAP_<r> publications (all chunks of one count once)
  std::int64_t resyncs_requested = 0;    // LMAP_RESYNC requests sent
  std::int64_t restarts = 0;             // robots seen with a new incarnation
  std::int64_t runs_started = 0;         // ... far behind the team's frame: a new run (the team's frame starts over)
  std::int64_t stale_incarnation = 0;    // messages of an older incarnation refused (replay, second sender)
  std::int64_t stale_snapshots = 0;      // snapshot chunks older than one applied, refused
  std::int64_t stale_poses = 0;          // POSEs of a frame already held or finished (late, repeated): ignored
  std::int64_t occupied = 0;             // STATIC landmarks found where a robot was (main.body_radius_m): now moving
  RefusalCounts refused;                 // every refusal, per reason (rejected_inputs is their sum)
  std::int64_t capacity_faults = 0;      // GLOBAL_MAP publications that could not carry the whole map
  std::int64_t state_damaged = 0;        // a damaged state file was moved aside at start (map_state.hpp)
  std::int64_t tracks = 0;               // TRACKS_<r> chunks taken
  std::int64_t tracks_refused = 0;       // ... refused (invalid, an older incarnation, a frame too far ahead, at odds with its publication's other chunks; in rejected_inputs too)
  std::int64_t stale_tracks = 0;         // ... ignored: of an older publication than the robot's newest, or a chunk taken already (late, repeated)
  std::int64_t global_tracks_published = 0;  // GLOBAL_TRACKS publications (each one or more chunks)
  std::int64_t global_tracks_omitted = 0;    // fused tracks left out of them (more than contract::kMaxTrackChunks chunks hold), summed
};

class MainNode {
 public:
  explicit MainNode(const GlobalMapOptions& options);

  /// Returns false (and counts it) when the message is invalid; `why` says why.
  bool on_event(const landmark_event_t& msg, std::string* why = nullptr);
  bool on_snapshot(const lmap_snapshot_t& msg, std::string* why = nullptr);
  /// LMAP_EVENTS: a robot's events of one frame. A message whose header and events
  /// disagree (robot, incarnation, frame), with seqs not ascending or a count outside
  /// [1, contract::kMaxBatchEvents] is refused whole (counted once); else every event
  /// goes through on_event in order, exactly as if it had come alone (each refusal
  /// counted). False when anything was refused; `why` says the first problem.
  bool on_events(const lmap_events_t& msg, std::string* why = nullptr);
  /// TRACKS_<r>: a chunk of robot r's tracks of its moving landmarks. Refused
  /// (counted per reason, in tracks_refused and rejected_inputs; nothing changes)
  /// when invalid (check_track_list, a robot outside limits.team), of an incarnation
  /// other than the one main follows, more than max_frame_gap frames ahead of the
  /// robot's newest, or at odds with its publication's other chunks (TrackFusion::
  /// take); ignored (stale_tracks) when of an older publication or taken already.
  /// Else taken: once its publication is complete (or superseded) its tracks replace
  /// the robot's previous ones in the fusion (TrackFusion).
  bool on_tracks(const track_list_t& msg, std::string* why = nullptr);
  /// GLOBAL_TRACKS, stamped like make_global_map: the fused tracks (TrackFusion::fuse
  /// at that frame) in ascending id, in chunks of contract::kMaxGlobalTracks, at most
  /// contract::kMaxTrackChunks (the rest counted in num_omitted and
  /// global_tracks_omitted). Returns the chunks to go out: while there are fused
  /// tracks, and once more (one empty chunk) when the last has gone; else 0.
  int make_global_tracks(std::int64_t now_utime, int frame = -1);
  int num_global_tracks_chunks() const { return num_global_tracks_chunks_; }
  const global_tracks_t& global_tracks(int chunk) const { return global_tracks_[static_cast<std::size_t>(chunk)]; }
  const TrackFusion& track_fusion() const { return fusion_; }
  void count_decode_error() { ++counters_.decode_errors; }
  /// The state file was damaged and moved aside at start (map_state.hpp).
  void count_state_damaged() { ++counters_.state_damaged; }
  /// The outcome of the last state save: FAULT_SAVE_FAILED while the last one failed,
  /// an alert at the first failure of a series.
  void note_save(bool ok, const std::string& why);
  /// Faults stay flagged this many frames of the team after their last sign.
  static constexpr int kAlertFrames = 100;
  /// More of a robot's frames than this missing between two of its POSEs: a partition
  /// (or a lossy stretch) healed when it is heard again (FAULT_PARTITION_HEALED).
  static constexpr int kPartitionFrames = 10;

  /// Notices produced since the last call, as messages (seq assigned); clears them.
  const std::vector<dynamic_notice_t>& take_notices(std::int64_t now_utime);
  /// Repair requests (LMAP_RESYNC) produced since the last call; clears them. A robot
  /// is asked when its events show a gap, when it restarted without its state, when
  /// it is first heard of past frame 0, and again every resync_interval_frames of its
  /// frames while the gap stays unrepaired.
  const std::vector<resync_request_t>& take_resyncs(std::int64_t now_utime);

  /// A robot's POSE: robot `robot_id` has finished frame `frame` (it publishes its
  /// events before its POSE). Returns the newest frame that every robot seen so far
  /// has finished when that advanced with this call, else -1: the moment to publish
  /// GLOBAL_MAP for that frame. A POSE of a stale incarnation returns -1; so does an
  /// invalid one (counted; `why` says why): from outside limits.team, a position or
  /// covariance outside limits, a frame jump not confirmed yet. A POSE of a new frame
  /// also takes every STATIC landmark where the robot's body is as moving
  /// (GlobalMap::occupy, main.body_radius_m; counted in MainCounters::occupied).
  int on_pose(const pose_estimate_t& msg, std::string* why = nullptr);
  /// A robot sends its POSE before the frame's events and snapshot; the POSE says up
  /// to which event seq the frame goes (event_seq) and whether a snapshot follows
  /// (snapshot_chunks). A POSE whose events or snapshot are not all applied yet is
  /// held: the frame counts as finished when they are (on_event, on_events,
  /// on_snapshot: its last chunk), or, should some be lost, at the robot's next POSE. The newest
  /// frame the team finished that way since the last call, else -1: the moment to
  /// publish GLOBAL_MAP for it (as on_pose's return value).
  int take_finished() { return completion_.take_finished(); }

  /// The global map in chunks that each fit one datagram (global_map_t), stamped
  /// with `frame` (default: the newest frame every robot has finished, or before any
  /// POSE was seen, the newest frame of any event). Returns the chunk count.
  int make_global_map(std::int64_t now_utime, int frame = -1);
  /// GLOBAL_MOVING: the global map's moving lists alone (chunks of global_map_t
  /// without landmarks, cut by id as GLOBAL_MAP's), stamped as make_global_map
  /// stamps, in the same chunk pool. What a robot reads of the global map: a few
  /// hundred bytes where GLOBAL_MAP is tens of kB. Returns the chunk count.
  int make_moving_set(std::int64_t now_utime, int frame = -1);
  /// Is the moving set just made (make_moving_set) due to go out at `now_utime`
  /// (main.moving_repeat_s)? True when its lists (ids, frames, finders) differ from
  /// the last set that was due, when that one is moving_repeat_s old or older, or
  /// when the option is 0; counted (MainCounters::moving_sets). Every change goes out
  /// at the moment it did when every map carried it; the repeats only repair.
  bool moving_set_due(int num_chunks, std::int64_t now_utime);
  /// Robot r's team map (TEAM_MAP_<r>, main.team_map_period_frames): the global map
  /// without r's own information (GlobalMap::fused_without), in the same chunk pool
  /// (map_chunk; the last make_* call fills it). Returns the chunk count.
  int make_team_map(int robot_id, std::int64_t now_utime, int frame = -1);
  /// True (once) when the team maps of `frame` are due: once per period of
  /// main.team_map_period_frames, at the first frame finished in a period after the
  /// last team map's (its multiple when no POSE is lost), never for an older frame.
  /// A due round first checks the robots' maps against each other (check_team).
  bool team_map_due(int frame);
  /// Whether robot r has been heard from (a POSE): who gets a team map.
  bool robot_seen(int robot_id) const {
    return robot_id >= 1 && robot_id <= kMaxTeamRobots && completion_.robot_frame(robot_id) >= 0;
  }
  const global_map_t& map_chunk(int i) const { return publisher_.map_chunk(i); }
  node_status_t status_msg(std::int64_t now_utime) const;

  /// The incarnation GLOBAL_MAP, DYNAMIC_NOTICE and LMAP_RESYNC carry (set at start-up).
  std::int64_t incarnation() const { return incarnation_; }
  void set_incarnation(std::int64_t v) { incarnation_ = v; }
  /// A line for stderr when something happened an operator must see (a second
  /// sender with a robot's id, a robot restarted), once per occurrence; else "".
  std::string take_alert();

  GlobalMap& map() { return map_; }
  const GlobalMap& map() const { return map_; }
  const MainCounters& counters() const { return counters_; }

  /// The checks of a message on its own (contract, limits, team); "" when valid,
  /// else the problem, and `reason` (when given) its kind.
  std::string validate(const landmark_event_t& msg, Refusal* reason = nullptr) const;
  std::string validate(const lmap_snapshot_t& msg, Refusal* reason = nullptr) const;
  std::string validate(const lmap_events_t& msg, Refusal* reason = nullptr) const;  // the message, not its events
  std::string validate(const pose_estimate_t& msg, Refusal* reason = nullptr) const;
  std::string validate(const track_list_t& msg, Refusal* reason = nullptr) const;

 private:
  /// The frame and seq windows of robot `robot_id` (valid, in the team): "" when the
  /// message may be applied, else why not (counted as kFrameWindow / kSeqWindow).
  std::string check_frame(int robot_id, int frame, Refusal* reason);
  std::string check_seq(int robot_id, std::int64_t seq, bool snapshot, Refusal* reason);
  /// The checks an LMAP_EVENT (snapshot false) or an LMAP_SNAPSHOT chunk (true) passes
  /// before it is applied: valid, of the robot's current incarnation, inside its seq
  /// and frame windows. False when refused (counted; `why`, when given, says why).
  template <class Msg>
  bool admit(const Msg& m, bool snapshot, std::string* why);
  /// The incarnation check of every robot message: false when it must be refused.
  bool accept_incarnation(int robot_id, std::int64_t incarnation, int frame);
  /// A robot restarted without its state: its stream starts over, a snapshot is asked.
  void restarted(int robot_id, std::int64_t incarnation, int frame);
  /// A message of an older incarnation refused: counted, FAULT_INCARNATION, an alert.
  void refused_incarnation(int robot_id, std::int64_t incarnation, int frame);
  void request_resync(int robot_id, std::int8_t reason);
  void check_team();
  /// The frame GLOBAL_MAP and its kin are stamped with when none is given.
  int stamp(int frame) const;
  /// A refused message: counted per reason, `why` (when given) says why; returns false.
  bool refused(Refusal reason, const std::string& problem, std::string* why);
  GlobalMap map_;
  FrameCompletion completion_;
  MapPublisher publisher_;
  TrackFusion fusion_;
  // contract::kMaxTrackChunks chunks, each reserved for contract::kMaxGlobalTracks at
  // construction; the first num_global_tracks_chunks_ are the last publication.
  std::vector<global_tracks_t> global_tracks_;
  int num_global_tracks_chunks_ = 0;
  int global_tracks_published_ = 0;  // fused tracks (sent and omitted) of the last GLOBAL_TRACKS
  int team_map_frame_ = -1;  // frame of the last team maps
  MainCounters counters_;
  std::vector<Notice> pending_;
  std::vector<dynamic_notice_t> notices_;
  std::int64_t notice_seq_ = 0;
  std::int64_t incarnation_ = 0;
  std::vector<resync_request_t> resyncs_, taken_;
  std::array<int, kMaxTeamRobots> resync_frame_;  // robot frame of the last request, per robot
  std::array<JumpGuard, kMaxTeamRobots> frame_guard_{}, event_guard_{}, snapshot_guard_{};  // per robot
  std::array<int, kMaxTeamRobots> pose_frame_;                 // newest POSE frame per robot, -1: none
  std::array<int, kMaxTeamRobots> incarnation_refused_frame_;  // team frame of the last refusal as another incarnation
  int healed_frame_ = -1;        // a robot heard again after a partition (FAULT_PARTITION_HEALED)
  bool save_failed_ = false;     // FAULT_SAVE_FAILED
  std::array<bool, kMaxTeamRobots> alerted_duplicate_{};
  static constexpr std::size_t kAlertCapacity = 4096;
  std::string alert_;
  std::vector<std::pair<int, RobotEstimate>> snap_lms_;
  std::vector<int> snap_moving_, snap_moving_frames_;
};

/// main_robot's summary line at exit (ending in a newline): every counter, the map's
/// static and moving landmarks, its version and the team-map rounds left out.
std::string final_summary(const MainNode& node);

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// The robot node's message layer, without I/O: a SENSOR frame passes FrameAdmission,
// runs through the Robot, and leaves as the messages RobotMessages fills (POSE,
// LMAP_EVENT with a per-robot seq, LMAP_SNAPSHOT, CANDIDATES, TRACKS); main_robot's inputs
// wait in DeferredInputs for their frame; RobotNode counts, reports faults (STATUS,
// alerts) and ties these together. The robot_node process and the in-process team
// run both drive this class, so both behave the same; both wire it to the message
// layer with RobotPorts (robot_ports.hpp).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "elaslam/common/histogram.hpp"
#include "elaslam/candidate_list_t.hpp"
#include "elaslam/track_list_t.hpp"
#include "elaslam/dynamic_notice_t.hpp"
#include "elaslam/global_map_t.hpp"
#include "elaslam/landmark_event_t.hpp"
#include "elaslam/lmap_events_t.hpp"
#include "elaslam/lmap_snapshot_t.hpp"
#include "elaslam/node_status_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/resync_request_t.hpp"
#include "elaslam/robot_node/deferred_inputs.hpp"
#include "elaslam/robot_node/frame_admission.hpp"
#include "elaslam/robot_node/robot.hpp"
#include "elaslam/robot_node/robot_messages.hpp"
#include "elaslam/sensor_frame_t.hpp"

namespace elaslam {

struct RobotNodeCounters {
  std::int64_t frames = 0;            // frames processed
  std::int64_t frames_gap = 0;        // frames never received (gaps bridged by the odometer)
  std::int64_t frames_duplicate = 0;  // refused: same frame again
  std::int64_t frames_out_of_order = 0;  // refused: older than the last processed
  std::int64_t rejected_inputs = 0;   // messages that failed validation
  std::int64_t decode_errors = 0;     // messages that could not be decoded (counted by the I/O shell)
  std::int64_t queue_drops = 0;       // messages lost before the handler (counted by the I/O shell)
  std::int64_t filter_faults = 0;     // filter operations refused by its health checks
  std::int64_t events_sent = 0;
  std::int64_t notices_applied = 0;   // dynamic notices that removed a landmark here
  std::int64_t notices_ignored = 0;   // notices about landmarks this robot did not hold / its own
  std::int64_t notices_deferred = 0;  // notices for a frame this robot had not processed yet: held until it has
  std::int64_t notices_repaired = 0;  // moving landmarks learnt from GLOBAL_MAP whose notice never came
  std::int64_t notices_stale = 0;     // notices not after one had for the landmark, or older than this robot's own view of it
  std::int64_t resyncs_answered = 0;  // snapshots sent on main_robot's request
  std::int64_t foreign_poses = 0;     // own POSE_<r> (or STATUS_ROBOT_<r>) messages of another incarnation: a second sender with this id
  RefusalCounts refused;              // refused messages per reason (their sum is rejected_inputs)
  std::int64_t odometry_reanchors = 0;  // odometer origin changes taken (a confirmed jump)
  std::int64_t filter_full = 0;       // landmarks not added because every filter slot was taken
  std::int64_t evictions = 0;         // landmarks that left the full filter to make room (Robot::make_room)
  std::int64_t restored = 0;          // evicted landmarks seen again and back in the filter
  std::int64_t movers_followed = 0;   // candidate-frames followed as their tracks predict (tracking.correct_pose)
  std::int64_t mover_corrections = 0; // ... sightings of them that corrected the filter
  std::int64_t inconsistent_frames = 0;  // frames the consistency monitor found the filter inconsistent
  std::int64_t recoveries = 0;           // of those, pose covariance widened (consistency_recover)
  std::int64_t own_drifted_frames = 0;   // frames whose own filter had drifted from the aided one: no MOVING finding
  std::int64_t team_map_chunks = 0;      // TEAM_MAP_<r> chunks applied (robot.team_map.fuse)
  std::int64_t team_map_stale = 0;       // ... ignored: older than one applied
  std::int64_t tracks_omitted = 0;       // tracks left out of TRACKS_<r> (more than contract::kMaxTracks), summed over frames
};

class RobotNode {
 public:
  enum class Verdict { kProcessed, kDuplicate, kOutOfOrder, kInvalid };

  RobotNode(const RobotOptions& options, int robot_id);

  /// One sensor frame. On kProcessed the outputs below hold this frame's messages.
  /// `now_utime` stamps the outgoing messages; `why` gets the reason of a refusal.
  Verdict on_sensor(const sensor_frame_t& msg, std::int64_t now_utime, std::string* why = nullptr);

  /// A dynamic notice from main_robot. Returns false when it was invalid.
  /// A notice about frame f takes effect after this robot has processed its own
  /// frame f, whatever the order of arrival (another robot's detection in frame f
  /// may reach this robot before its own SENSOR frame f does): it is held until
  /// then, so the live team does what the in-process run does (notices of frame k
  /// between frames k and k + 1). Held at most node.max_frame_gap frames ahead.
  /// DYNAMIC_NOTICE goes to the whole team: the finder drops its own finding's
  /// notice unread (counted in notices_ignored).
  bool on_notice(const dynamic_notice_t& msg, std::string* why = nullptr);

  /// One chunk of the global map's moving lists (GLOBAL_MOVING): each landmark in it
  /// that another robot found moving is a MovingReport, taken like a notice's (held
  /// the same way) when it is news: its notice was lost, or sent before this robot
  /// started, and this robot has not changed its own view of the landmark since.
  /// Returns false when the chunk was invalid.
  bool on_global_map(const global_map_t& msg, std::string* why = nullptr);

  /// One chunk of the team's map without this robot (TEAM_MAP_<r>, robot.team_map):
  /// its landmarks go to Robot::apply_team_map. Refused (false, counted) when
  /// invalid or when a landmark in it lists this robot as a contributor (this
  /// robot's own information would come back: a GLOBAL_MAP on the wrong channel).
  /// A chunk older than one applied (a lower version of the same main incarnation)
  /// is ignored. A chunk of frame k takes effect after this robot's frame k + 1 (held
  /// until then, like a notice): the live team and the in-process run agree. Without
  /// robot.team_map.fuse the robot does not subscribe (and refuses it here).
  bool on_team_map(const global_map_t& msg, std::string* why = nullptr);

  /// main_robot asks for a snapshot. True when this robot answers: a snapshot is
  /// ready (snapshot_chunk()), at most one per processed frame.
  bool on_resync(const resync_request_t& msg, std::int64_t now_utime);

  /// A message of `incarnation` and `frame` seen on one of this robot's own output
  /// channels (its POSE_<r>, or its STATUS_ROBOT_<r> in channel groups). Another
  /// incarnation is another sender: two processes run as this robot, flagged (returns
  /// true; the STATUS fault flag stays set for 50 frames after the last one) when it
  /// is newer (it started after this one), or older and heard with three frames, each
  /// newer than the one before (it keeps working; a dead predecessor's late datagrams
  /// are not a second sender).
  bool on_own_channel(std::int64_t incarnation, int frame);

  void count_decode_error() { ++counters_.decode_errors; }
  void count_queue_drops(std::int64_t n) { counters_.queue_drops += n; }

  // ---- outputs of the last processed frame -----------------------------------------
  const pose_estimate_t& pose_msg() const { return messages_.pose(); }
  const std::vector<landmark_event_t>& event_msgs() const { return messages_.events(); }
  /// The same events in messages of at most contract::kMaxBatchEvents each
  /// (LMAP_EVENTS, robot.node.batch_events), filled from event_msgs(); none when the
  /// frame had no event. A pool sized at construction: no allocation.
  int num_event_batches() const { return messages_.num_event_batches(); }
  const lmap_events_t& event_batch(int i) const { return messages_.event_batch(i); }
  /// Stamp this frame's outgoing events (singly and in batches) with `utime`: the
  /// moment they go out.
  void stamp_events(std::int64_t utime) { messages_.stamp_events(utime); }
  /// True when this frame also produced a snapshot (every snapshot_period_frames).
  bool snapshot_ready() const { return messages_.snapshot_ready(); }
  /// The last snapshot, in chunks that each fit one datagram (lmap_snapshot_t).
  int num_snapshot_chunks() const { return messages_.num_snapshot_chunks(); }
  const lmap_snapshot_t& snapshot_chunk(int i) const { return messages_.snapshot_chunk(i); }
  /// Fill a snapshot now (e.g. on start-up or on request); returns its chunk count.
  int make_snapshot(std::int64_t now_utime) { return messages_.make_snapshot(robot_, admission_.last_frame(), now_utime); }
  /// True when this frame also produced a CANDIDATES_<r> message (robot.node.
  /// candidates_period_frames): the robot's candidates, at most contract::kMaxCandidates.
  bool candidates_ready() const { return messages_.candidates_ready(); }
  const candidate_list_t& candidates_msg() const { return messages_.candidates(); }
  /// This frame's TRACKS_<r> publication: the robot's tracks of its moving landmarks
  /// in chunks of contract::kMaxTracks, at most contract::kMaxTrackChunks (the rest
  /// in num_omitted and counted in RobotNodeCounters::tracks_omitted); 0 chunks when
  /// this frame sends none.
  int num_track_chunks() const { return messages_.num_track_chunks(); }
  const track_list_t& track_chunk(int i) const { return messages_.track_chunk(i); }

  /// The incarnation every outgoing message carries (landmark_event_t): the start-up
  /// wall clock [us] of a fresh start, kept from the state file on a resume
  /// (robot_node/main.cpp).
  std::int64_t incarnation() const { return messages_.incarnation(); }
  void set_incarnation(std::int64_t v) { messages_.set_incarnation(v); }
  /// Leave `n` event seq numbers unused (a resume from a state file saved up to one
  /// save interval ago: the numbers sent since were seen by main_robot already).
  void skip_seq(std::int64_t n) { messages_.skip_seq(n); }

  node_status_t status_msg(std::int64_t now_utime) const;
  /// counters().frames is the robot's (saved in its state, resumed with it);
  /// frames_this_run() counts only what this process did, as POSE.frames_processed
  /// and STATUS.frames say (a count that goes back shows a restart: tools/evaluate).
  const RobotNodeCounters& counters() const { return counters_; }
  /// SENSOR frames refused as older than the last processed one since it was
  /// processed. A late datagram now and then comes between processed frames; a run
  /// of them with none processed is a sensor source that started over (a new run from
  /// frame 0) while this node ran on, which it would refuse until the frames pass
  /// its old ones: the process shell starts fresh after 10 (main.cpp).
  int frames_behind() const { return admission_.frames_behind(); }
  std::int64_t frames_this_run() const { return frames_this_run_; }
  std::int64_t event_seq() const { return messages_.seq(); }  // seq of the last LMAP_EVENT sent
  const Robot& robot() const { return robot_; }
  const DurationHistogram& processing() const { return processing_; }
  int robot_id() const { return robot_id_; }

  /// Check a sensor frame against the contract (robot id, counts, finite values,
  /// ranges, ids within capacity) and limits (odometer within world_bound_m).
  /// Empty string when valid, else the problem and `reason` (when given) its kind.
  std::string validate(const sensor_frame_t& msg, Refusal* reason = nullptr) const {
    return admission_.validate(msg, reason);
  }

  /// main_robot heard (a message on one of its channels): what FAULT_MAIN_SILENT watches.
  void main_heard(std::int64_t now_utime);
  /// FAULT_MAIN_SILENT when main_robot has not been heard for node.main_silent_s while
  /// frames are processed (a FAULT line when it starts); when main is heard again
  /// after that, FAULT_PARTITION_HEALED for kAlertFrames frames and a line saying how
  /// long it was silent. Called at every processed frame and STATUS.
  void check_main(std::int64_t now_utime);
  /// The outcome of the last state save (the process's --state): FAULT_SAVE_FAILED
  /// while the last one failed, a FAULT line at the first failure of a series.
  void note_save(bool ok, const std::string& why);

  /// A line for stderr when an operator must see something (a capacity exceeded:
  /// the filter full), at most once per kAlertFrames frames; else "".
  std::string take_alert();
  static constexpr int kAlertFrames = 100;
  static constexpr std::size_t kAlertBytes = 384;  // an alert line's buffer, reserved at construction

 private:
  friend struct RobotStateAccess;  // the state file (robot_state.cpp): saves and restores the members below

  /// A SENSOR frame's admission (FrameAdmission's checks, a stray first frame
  /// dropped, gaps noted). kProcessed: the frame is to be processed; else the verdict
  /// (counted, `why` says why).
  Verdict admit(const sensor_frame_t& msg, std::string* why);
  /// An admitted frame through the Robot, and its outputs (events, snapshot,
  /// candidates, POSE).
  void run_frame(const sensor_frame_t& msg, std::int64_t now_utime);
  /// A valid report of another robot's finding: taken now, held or stale (counted).
  void take_moving(const MovingReport& m);
  void apply_moving(const MovingReport& m);
  /// The held team estimates whose map's frame this robot has passed go to the Robot.
  void apply_team_estimates();
  void note_inconsistent(bool recovered);  // FAULT_INCONSISTENT and a rate-limited alert
  void note_relocalised();                 // FAULT_RELOCALISED, an alert with the motion, a snapshot due
  void note_filter_full(int n);  // landmarks left out this frame: FAULT_CAPACITY and a rate-limited alert
  void note_frames_lost(int from, int to);  // frames never received: FAULT_FRAMES_LOST and a rate-limited alert
  /// The one frame processed so far was not the stream's (a forged or stray first
  /// frame): the node starts over, fresh, with the next incarnation.
  void start_over();
  /// A refused message: counted per reason, `why` (when given) says why; returns false.
  bool refused(Refusal reason, const std::string& problem, std::string* why);
  int last_frame() const { return admission_.last_frame(); }

  RobotOptions options_;
  int robot_id_;
  Robot robot_;
  FrameAdmission admission_;
  RobotMessages messages_;
  DeferredInputs deferred_;
  FrameInput input_;
  RobotNodeCounters counters_;
  std::int64_t frames_this_run_ = 0;  // not in the state: a resumed node counts from 0
  DurationHistogram processing_;
  int inconsistent_frame_ = -1;  // last frame found inconsistent (FAULT_INCONSISTENT for kAlertFrames)
  int inconsistent_alerted_ = -1000000;
  int relocalised_frame_ = -1;   // last relocalisation by the team map (FAULT_RELOCALISED for kAlertFrames)
  bool snapshot_due_ = false;    // the map moved as a whole: the next frame sends a snapshot whatever its number
  int full_frame_ = -1;          // last frame the filter was found full (FAULT_CAPACITY for kAlertFrames)
  int alerted_frame_ = -1000000; // last frame a capacity alert went out
  int lost_frame_ = -1;          // last frame that followed a gap (FAULT_FRAMES_LOST for kAlertFrames)
  int lost_alerted_ = -1000000;  // last frame a frames-lost alert went out
  std::int64_t main_heard_utime_ = 0;    // when main_robot was last heard, 0: not since the first frame
  std::int64_t first_frame_utime_ = 0;   // when this run's first frame was processed
  bool main_silent_ = false;             // FAULT_MAIN_SILENT
  int healed_frame_ = -1;                // main heard again after a silence (FAULT_PARTITION_HEALED)
  bool save_failed_ = false;             // FAULT_SAVE_FAILED
  std::string alert_;
  int last_resync_frame_ = -1;
  int duplicate_until_frame_ = -1;            // STATUS shows FAULT_DUPLICATE_SENDER until then
  std::int64_t older_sender_ = 0;             // an older incarnation heard on the own channels
  int older_sender_frame_ = -1;               // its newest frame heard
  int older_sender_frames_ = 0;               // how many newer frames it was heard with
};

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// The robot node's message layer, without I/O: validates incoming messages, keeps
// frame order, runs the Robot, and fills the outgoing messages (POSE, LMAP_EVENT
// with a per-robot seq, LMAP_SNAPSHOT, STATUS_ROBOT). The robot_node process and
// the in-process team run both drive this class, so both behave the same; both wire
// it to the message layer with RobotPorts (below).
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/chunks.hpp"
#include "elaslam/common/histogram.hpp"
#include "elaslam/common/log.hpp"
#include "elaslam/candidate_list_t.hpp"
#include "elaslam/dynamic_notice_t.hpp"
#include "elaslam/global_map_t.hpp"
#include "elaslam/landmark_event_t.hpp"
#include "elaslam/lmap_events_t.hpp"
#include "elaslam/lmap_snapshot_t.hpp"
#include "elaslam/node_status_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/resync_request_t.hpp"
#include "elaslam/robot_node/robot.hpp"
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
  std::int64_t inconsistent_frames = 0;  // frames the consistency monitor found the filter inconsistent
  std::int64_t recoveries = 0;           // of those, pose covariance widened (consistency_recover)
  std::int64_t own_drifted_frames = 0;   // frames whose own filter had drifted from the aided one: no MOVING finding
  std::int64_t team_map_chunks = 0;      // TEAM_MAP_<r> chunks applied (robot.team_map.fuse)
  std::int64_t team_map_stale = 0;       // ... ignored: older than one applied
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
  bool on_notice(const dynamic_notice_t& msg, std::string* why = nullptr);

  /// One chunk of the global map: every landmark in it that the team knows is moving
  /// and whose notice this robot has not had (lost, or sent before it started) is
  /// taken as that notice (held like one), unless this robot has changed its own
  /// view of the landmark since. Returns false when the chunk was invalid.
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
  const pose_estimate_t& pose_msg() const { return pose_; }
  const std::vector<landmark_event_t>& event_msgs() const { return events_; }
  /// The same events in messages of at most contract::kMaxBatchEvents each
  /// (LMAP_EVENTS, robot.node.batch_events), filled from event_msgs(); none when the
  /// frame had no event. A pool sized at construction: no allocation.
  int num_event_batches() const { return num_batches_; }
  const lmap_events_t& event_batch(int i) const { return batches_[static_cast<std::size_t>(i)]; }
  /// Stamp this frame's outgoing events (singly and in batches) with `utime`: the
  /// moment they go out.
  void stamp_events(std::int64_t utime);
  /// True when this frame also produced a snapshot (every snapshot_period_frames).
  bool snapshot_ready() const { return snapshot_ready_; }
  /// The last snapshot, in chunks that each fit one datagram (lmap_snapshot_t).
  int num_snapshot_chunks() const { return num_chunks_; }
  const lmap_snapshot_t& snapshot_chunk(int i) const { return chunks_[static_cast<std::size_t>(i)]; }
  /// Fill a snapshot now (e.g. on start-up or on request); returns its chunk count.
  int make_snapshot(std::int64_t now_utime);
  /// True when this frame also produced a CANDIDATES_<r> message (robot.node.
  /// candidates_period_frames): the robot's candidates, at most contract::kMaxCandidates.
  bool candidates_ready() const { return candidates_ready_; }
  const candidate_list_t& candidates_msg() const { return candidates_; }

  /// The incarnation every outgoing message carries (landmark_event_t): the start-up
  /// wall clock [us] of a fresh start, kept from the state file on a resume
  /// (robot_node/main.cpp).
  std::int64_t incarnation() const { return incarnation_; }
  void set_incarnation(std::int64_t v) { incarnation_ = v; }
  /// Leave `n` event seq numbers unused (a resume from a state file saved up to one
  /// save interval ago: the numbers sent since were seen by main_robot already).
  void skip_seq(std::int64_t n) { seq_ += n; }

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
  int frames_behind() const { return behind_; }
  std::int64_t frames_this_run() const { return frames_this_run_; }
  std::int64_t event_seq() const { return seq_; }  // seq of the last LMAP_EVENT sent
  const Robot& robot() const { return robot_; }
  const DurationHistogram& processing() const { return processing_; }
  int robot_id() const { return robot_id_; }

  /// Check a sensor frame against the contract (robot id, counts, finite values,
  /// ranges, ids within capacity) and limits (odometer within world_bound_m).
  /// Empty string when valid, else the problem and `reason` (when given) its kind.
  std::string validate(const sensor_frame_t& msg, Refusal* reason = nullptr) const;

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

  /// A SENSOR frame's admission: the contract, one sighting per landmark, the order
  /// (duplicates, older frames, a stray first frame), the frame window and the
  /// odometry bound, gaps noted. kProcessed: the frame is to be processed; else the
  /// verdict (counted, `why` says why).
  Verdict admit(const sensor_frame_t& msg, std::string* why);
  /// "" unless a landmark is sighted twice in the frame (the contract allows one).
  std::string check_duplicate_ids(const sensor_frame_t& msg, Refusal* reason);
  /// An admitted frame through the Robot, and its outputs (events, snapshot,
  /// candidates, POSE).
  void run_frame(const sensor_frame_t& msg, std::int64_t now_utime);
  /// Notices held for this frame or an earlier one take effect, in arrival order.
  void release_held_notices();
  void fill_pose(const sensor_frame_t& msg, std::int64_t now_utime, const FrameSummary& s, std::int64_t us);
  void fill_events(std::int64_t now_utime);
  void apply_notice(const dynamic_notice_t& msg);
  /// The held team estimates whose map's frame this robot has passed go to the Robot.
  void apply_team_estimates();
  void note_inconsistent(bool recovered);  // FAULT_INCONSISTENT and a rate-limited alert
  void note_relocalised();                 // FAULT_RELOCALISED, an alert with the motion, a snapshot due
  void note_filter_full(int n);  // landmarks left out this frame: FAULT_CAPACITY and a rate-limited alert
  void note_frames_lost(int from, int to);  // frames never received: FAULT_FRAMES_LOST and a rate-limited alert
  /// The one frame processed so far was not the stream's (a forged or stray first
  /// frame): the node starts over, fresh, with the next incarnation.
  void start_over();
  void prepare_snapshot_chunks();
  std::string validate(const global_map_t& msg, Refusal* reason) const;
  /// A refused message: counted per reason, `why` (when given) says why; returns false.
  bool refused(Refusal reason, const std::string& problem, std::string* why);
  /// The frame window and the odometry bound of a valid, newer frame: "" when it may
  /// be processed (input_.reanchor set when it re-anchors the odometer), else why not.
  std::string check_progress(const sensor_frame_t& msg, Refusal* reason);

  RobotOptions options_;
  int robot_id_;
  Robot robot_;
  FrameInput input_;
  RobotNodeCounters counters_;
  std::int64_t frames_this_run_ = 0;  // not in the state: a resumed node counts from 0
  DurationHistogram processing_;
  int last_frame_ = -1;
  JumpGuard frame_guard_;        // frame jumps beyond confirm_jump_frames wait for the next frame
  Pose2 odo_candidate_;          // a refused odometer jump, possibly a new origin
  int odo_candidate_frame_ = -1; // its frame, -1: none
  int odo_streak_ = 0;           // consecutive refused readings continuing it
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
  std::int64_t seq_ = 0;
  pose_estimate_t pose_{};
  std::vector<landmark_event_t> events_;
  std::vector<lmap_events_t> batches_;  // events_ in LMAP_EVENTS messages; the first num_batches_ in use
  int num_batches_ = 0;
  std::int64_t incarnation_ = 0;
  // Snapshot chunks: a pool sized at construction for the largest map (no allocation).
  ChunkSizes chunk_sizes_;
  std::vector<int> static_ids_, moving_ids_;  // scratch: the map's ids, ascending
  std::vector<ChunkSpan> spans_;
  std::vector<lmap_snapshot_t> chunks_;
  void fill_candidates(std::int64_t now_utime);
  int num_chunks_ = 0;
  bool snapshot_ready_ = false;
  bool candidates_ready_ = false;
  candidate_list_t candidates_{};  // reserved for contract::kMaxCandidates at construction
  int last_resync_frame_ = -1;
  int duplicate_until_frame_ = -1;            // STATUS shows FAULT_DUPLICATE_SENDER until then
  std::int64_t older_sender_ = 0;             // an older incarnation heard on the own channels
  int older_sender_frame_ = -1;               // its newest frame heard
  int older_sender_frames_ = 0;               // how many newer frames it was heard with
  std::int64_t team_map_incarnation_ = 0, team_map_version_ = -1;  // newest TEAM_MAP_<r> applied
  int behind_ = 0;  // SENSOR frames refused as older since the last processed one
  struct TeamPending {  // a team estimate waiting for this robot's frame after its map's frame
    bool valid = false;
    int frame = 0;
    Eigen::Vector2d position = Eigen::Vector2d::Zero();
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  };
  std::vector<TeamPending> team_pending_;  // per landmark id (robot.team_map.fuse only)
  std::vector<TeamEstimate> team_due_;     // scratch: those due now
  int team_pending_count_ = 0;
  /// A notice (or GLOBAL_MAP moving entry) for landmark `id` found in `frame` says
  /// something new: the rule of on_notice and of the GLOBAL_MAP repair.
  bool notice_is_news(int id, int frame) const;
  std::vector<int> notice_frame_;             // per landmark id: frame of the newest notice had, -1: none
  std::vector<std::uint8_t> id_seen_;  // duplicate-id check within a frame
  std::vector<dynamic_notice_t> held_;  // notices for frames not processed yet (fixed capacity)
};

/// Receive queue bounds of the robot's inputs. LCM's default of 30 drops silently
/// (LCM.md): both sized on purpose. Lost sensor frames show up as frame gaps, lost
/// notices as seq gaps (RobotNodeCounters::queue_drops).
struct RobotQueues {
  int sensor = 200;
  int notice = 1000;
  int global_map = 1000;  // GLOBAL_MOVING chunks (one per publication unless the moving set is large)
  int resync = 100;
  int own_pose = 100;     // this robot's own POSE (or STATUS) channel: a second sender with this id
  int team_map = 1000;    // TEAM_MAP_<r> chunks (robot.team_map.fuse)
};

/// A RobotNode on the message layer (transport/node_shell.hpp): receives SENSOR_<r>,
/// DYNAMIC_NOTICE, GLOBAL_MAP (the moving set: lost notices repaired), TEAM_MAP_<r>
/// (with robot.team_map.fuse: the other robots' map), LMAP_RESYNC
/// (main_robot asks for a snapshot) and its own POSE_<r> (a second sender with this
/// id); for every processed frame publishes POSE_<r> (the end of the robot's
/// frame; it carries the seq of the frame's last event, event_seq), then its events
/// (LMAP_EVENTS, or one LMAP_EVENT each without robot.node.batch_events) and its
/// LMAP_SNAPSHOT chunks when one is due; STATUS_ROBOT_<r> on request. The robot_node process and the
/// in-process team run both run this, so the live and in-process paths share it.
/// A template on the shell only so that this library builds without the transport
/// (the no-allocation test compiles its sources alone); Shell is NodeShell.
///
/// Where a frame's time goes, per processed frame, wall-clock [us]:
///   receive: the SENSOR's publish stamp (its utime) to this handler: the sender's
///            encode and send, the network, the wake-up and scheduling of this
///            process, LCM's receive thread and queue, decode and the MAC check.
///            Meaningful only when the sender's clock is this one's (one machine,
///            or synchronised clocks); across unsynchronised clocks it is clamped
///            at 0 or absurd.
///   frame:   RobotNode::on_sensor: the filter, the gate, the outgoing messages filled.
///   pose:    the POSE encoded and sent (its utime is stamped just before); first.
///   outputs: then this frame's LMAP_EVENTS (or LMAP_EVENTs), snapshot chunks and
///            CANDIDATES encoded and sent.
struct FrameStages {
  DurationHistogram receive, frame, outputs, pose;
};

template <class Shell>
class RobotPorts {
 public:
  RobotPorts(Shell& shell, RobotNode& node)
      : shell_(shell),
        node_(node),
        event_(channels::lmap_event(shell.suffix())),
        events_(channels::lmap_events(shell.suffix())),
        snapshot_(channels::lmap_snapshot(shell.suffix())),
        pose_(channels::pose(node.robot_id(), shell.suffix())),
        status_(channels::status_robot(node.robot_id(), shell.suffix())),
        candidates_(channels::candidates(node.robot_id(), shell.suffix())) {}

  /// Subscribe the inputs; false when the transport refused.
  bool open(const RobotQueues& queues = {}) {
    shell_.on_decode_error([this] { node_.count_decode_error(); });
    const int sensor = shell_.template subscribe<sensor_frame_t>(
        channels::sensor(node_.robot_id(), shell_.suffix()),
        [this](const sensor_frame_t& m, const std::string&) { on_sensor(m); }, queues.sensor);
    const int notice = shell_.template subscribe<dynamic_notice_t>(
        channels::dynamic_notice(shell_.suffix()), [this](const dynamic_notice_t& m, const std::string&) { on_notice(m); },
        queues.notice);
    // The global map's moving lists (they repair lost notices), in GLOBAL_MOVING: the
    // whole GLOBAL_MAP is tens of kB a frame a robot would decode for them.
    const int map = shell_.template subscribe<global_map_t>(
        channels::global_moving(shell_.suffix()), [this](const global_map_t& m, const std::string&) { on_map(m); },
        queues.global_map);
    const int resync = shell_.template subscribe<resync_request_t>(
        channels::lmap_resync(shell_.suffix()), [this](const resync_request_t& m, const std::string&) { on_resync(m); },
        queues.resync);
    // A second sender with this id shows on this robot's own POSE, every frame; in
    // channel groups on its STATUS, about once a second, as reading POSE_<r> would
    // wake this robot for every robot's POSE (channels.hpp).
    const int own = shell_.transport().channel_groups()
                        ? shell_.template subscribe<node_status_t>(
                              status_, [this](const node_status_t& m, const std::string&) { on_own(status_, m.incarnation, m.frame); },
                              queues.own_pose)
                        : shell_.template subscribe<pose_estimate_t>(
                              pose_, [this](const pose_estimate_t& m, const std::string&) { on_own(pose_, m.incarnation, m.frame); },
                              queues.own_pose);
    int team = 1;
    if (node_.robot().options().team_map_fuse)
      team = shell_.template subscribe<global_map_t>(
          channels::team_map(node_.robot_id(), shell_.suffix()),
          [this](const global_map_t& m, const std::string&) { on_team_map(m); }, queues.team_map);
    return sensor > 0 && notice > 0 && map > 0 && resync > 0 && own > 0 && team > 0;
  }

  void publish_status() {
    node_.check_main(shell_.now_utime());
    say_alert();
    node_status_t m = node_.status_msg(shell_.now_utime());
    shell_.stamp_auth(&m);
    shell_.publish(status_, m);
  }

  /// Called after every processed frame, before its messages go out (the in-process
  /// run reads the frame's gate records there).
  void after_frame(std::function<void(const RobotNode&)> fn) { after_frame_ = std::move(fn); }

  /// Where the processed frames' time went (FrameStages).
  const FrameStages& stages() const { return stages_; }

 private:
  void on_sensor(const sensor_frame_t& msg) {
    std::string why;
    const std::int64_t received = shell_.now_utime();
    const auto v = node_.on_sensor(msg, received, &why);
    if (v == RobotNode::Verdict::kInvalid) shell_.refuse("sensor frame refused: " + why);
    if (v != RobotNode::Verdict::kProcessed) return;
    node_.check_main(received);
    say_alert();
    if (after_frame_) after_frame_(node_);
    // The POSE first: it ends the robot's frame for whoever waits on it (a lockstep
    // simulator, the latency); it carries the seq of the frame's last event, which
    // main_robot waits for before it counts the frame finished.
    pose_estimate_t pose = node_.pose_msg();
    const std::int64_t now = shell_.now_utime();
    pose.utime = now;
    shell_.publish(pose_, pose);
    const std::int64_t posed = shell_.now_utime();
    node_.stamp_events(posed);
    if (node_.robot().options().batch_events)
      for (int i = 0; i < node_.num_event_batches(); ++i) shell_.publish(events_, node_.event_batch(i));
    else
      for (const auto& ev : node_.event_msgs()) shell_.publish(event_, ev);
    if (node_.snapshot_ready()) publish_snapshot();
    if (node_.candidates_ready()) shell_.publish(candidates_, node_.candidates_msg());
    const std::int64_t sent = shell_.now_utime();
    stages_.receive.add(span_us(msg.utime, received));
    stages_.frame.add(now - received);
    stages_.pose.add(posed - now);
    stages_.outputs.add(sent - posed);
  }

  /// `to - from` [us], saturated: `from` is a message's stamp, any int64 (one near
  /// INT64_MIN overflowed the subtraction: found by fuzz_datagrams).
  static std::int64_t span_us(std::int64_t from, std::int64_t to) {
    std::int64_t d = 0;
    if (!__builtin_sub_overflow(to, from, &d)) return d;
    return to > from ? std::numeric_limits<std::int64_t>::max() : std::numeric_limits<std::int64_t>::min();
  }

  void publish_snapshot() {
    for (int i = 0; i < node_.num_snapshot_chunks(); ++i) shell_.publish(snapshot_, node_.snapshot_chunk(i));
  }

  // Main's messages (its moving set, notices, team map, resync requests) each tell
  // that main is heard (FAULT_MAIN_SILENT); refused ones too: they came (and, with
  // the team's keys, verified as main's), their content is what was wrong.
  void heard_main() {
    node_.main_heard(shell_.now_utime());
    say_alert();
  }

  void say_alert() {
    if (const std::string alert = node_.take_alert(); !alert.empty()) shell_.say(alert, log::Priority::kWarning);
  }

  void on_map(const global_map_t& msg) {
    heard_main();
    std::string why;
    if (!node_.on_global_map(msg, &why)) shell_.refuse("global map refused: " + why);
  }

  void on_team_map(const global_map_t& msg) {
    heard_main();
    std::string why;
    if (!node_.on_team_map(msg, &why)) shell_.refuse("team map refused: " + why);
  }

  void on_resync(const resync_request_t& msg) {
    heard_main();
    if (node_.on_resync(msg, shell_.now_utime())) publish_snapshot();
  }

  void on_own(const std::string& channel, std::int64_t incarnation, int frame) {
    if (node_.on_own_channel(incarnation, frame))  // loudly, not rate-limited: an operator must see it
      shell_.say("FAULT: another process publishes " + channel + " (incarnation " + std::to_string(incarnation) +
                 ", this one " + std::to_string(node_.incarnation()) + "): two robots with one id",
                 log::Priority::kWarning);
  }

  void on_notice(const dynamic_notice_t& msg) {
    heard_main();
    std::string why;
    if (!node_.on_notice(msg, &why)) return shell_.refuse("dynamic notice refused: " + why);
    // Only an accepted notice moves the tracker: a forged seq must not hide real losses.
    const std::int64_t lost = notice_seq_.observe(msg.seq, msg.incarnation);
    if (lost > 0) node_.count_queue_drops(lost);
  }

  Shell& shell_;
  RobotNode& node_;
  const std::string event_, events_, snapshot_, pose_, status_, candidates_;  // channel names, built once
  typename Shell::SequenceGaps notice_seq_;            // DYNAMIC_NOTICE's seq: lost notices
  std::function<void(const RobotNode&)> after_frame_;
  FrameStages stages_;
};

}  // namespace elaslam

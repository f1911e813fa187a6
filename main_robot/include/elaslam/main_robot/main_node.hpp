// SPDX-License-Identifier: Apache-2.0
// main_robot's message layer, without I/O: validates LMAP_EVENT / LMAP_SNAPSHOT,
// applies them to the GlobalMap, and fills GLOBAL_MAP, DYNAMIC_NOTICE and
// STATUS_MAIN. The main_robot process and the in-process team run share it, and
// both wire it to the message layer with MainPorts (below).
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/chunks.hpp"
#include "elaslam/common/log.hpp"
#include "elaslam/dynamic_notice_t.hpp"
#include "elaslam/global_map_t.hpp"
#include "elaslam/landmark_event_t.hpp"
#include "elaslam/lmap_events_t.hpp"
#include "elaslam/lmap_snapshot_t.hpp"
#include "elaslam/main_robot/global_map.hpp"
#include "elaslam/node_status_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/resync_request_t.hpp"

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
  int take_finished() {
    const int f = finished_;
    finished_ = -1;
    return f;
  }

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
    return robot_id >= 1 && robot_id <= kMaxTeamRobots && robot_frame_[static_cast<std::size_t>(robot_id - 1)] >= 0;
  }
  const global_map_t& map_chunk(int i) const { return chunks_[static_cast<std::size_t>(i)]; }
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

 private:
  /// The frame and seq windows of robot `robot_id` (valid, in the team): "" when the
  /// message may be applied, else why not (counted as kFrameWindow / kSeqWindow).
  std::string check_frame(int robot_id, int frame, Refusal* reason);
  std::string check_seq(int robot_id, std::int64_t seq, bool snapshot, Refusal* reason);
  /// The incarnation check of every robot message: false when it must be refused.
  bool accept_incarnation(int robot_id, std::int64_t incarnation, int frame);
  void request_resync(int robot_id, std::int8_t reason);
  void check_team();
  /// Robot `robot_id` (valid) finished `frame`: the newest frame the whole team has
  /// finished when that advanced, else -1.
  int finished_frame(int robot_id, int frame);
  /// Robot `robot_id`'s held POSE, when its events up to its event_seq are applied
  /// now: the frame counts as finished (finished_ when the team's frame advanced).
  void settle_pose(int robot_id);
  /// A refused message: counted per reason, `why` (when given) says why; returns false.
  bool refused(Refusal reason, const std::string& problem, std::string* why);
  int make_map_chunks(std::int64_t now_utime, int frame, int exclude_robot, bool moving_only = false);
  GlobalMap map_;
  int team_map_frame_ = -1;  // frame of the last team maps
  MainCounters counters_;
  std::vector<Notice> pending_;
  std::vector<dynamic_notice_t> notices_;
  std::int64_t notice_seq_ = 0;
  std::array<int, kMaxTeamRobots> robot_frame_;  // last finished frame per robot, -1: never seen
  // A robot's POSE waiting for what it announced (take_finished).
  struct HeldPose {
    int frame = -1;             // -1: none held
    std::int64_t event_seq = 0;  // the event seq it waits for
    bool snapshot = false;       // and whether it waits for its frame's snapshot
  };
  std::array<HeldPose, kMaxTeamRobots> held_{};
  // The frame of the last snapshot whose last chunk was applied, per robot: on
  // separate ports a snapshot may come in before the POSE that announces it.
  std::array<int, kMaxTeamRobots> snapshot_done_frame_;
  int finished_ = -1;
  int completed_frame_ = -1;
  std::int64_t incarnation_ = 0;
  std::vector<resync_request_t> resyncs_, taken_;
  std::array<int, kMaxTeamRobots> resync_frame_;  // robot frame of the last request, per robot
  std::array<JumpGuard, kMaxTeamRobots> frame_guard_{}, event_guard_{}, snapshot_guard_{};  // per robot
  bool capacity_fault_ = false;  // the last GLOBAL_MAP could not carry the whole map
  std::array<int, kMaxTeamRobots> pose_frame_;                 // newest POSE frame per robot, -1: none
  std::array<int, kMaxTeamRobots> incarnation_refused_frame_;  // team frame of the last refusal as another incarnation
  int healed_frame_ = -1;        // a robot heard again after a partition (FAULT_PARTITION_HEALED)
  bool save_failed_ = false;     // FAULT_SAVE_FAILED
  std::array<bool, kMaxTeamRobots> alerted_duplicate_{};
  static constexpr std::size_t kAlertCapacity = 4096;
  std::string alert_;
  // GLOBAL_MAP chunks: a pool sized at construction for the largest map (no allocation).
  ChunkSizes chunk_sizes_;
  std::vector<int> static_ids_, moving_ids_;
  std::vector<int> moving_sent_, moving_now_;  // (id, frame, by) of the last due moving set and of the one just made
  std::int64_t moving_sent_utime_ = 0;
  bool any_moving_sent_ = false;
  std::vector<ChunkSpan> spans_;
  std::vector<global_map_t> chunks_;
  std::vector<std::pair<int, RobotEstimate>> snap_lms_;
  std::vector<int> snap_moving_, snap_moving_frames_;
};

/// Receive queue bounds of main_robot's inputs (LCM's default of 30 drops silently:
/// LCM.md). Events come in bursts (one per observed landmark per robot per frame): a
/// deep queue, on purpose; losses show up as seq gaps and snapshots repair them.
struct MainQueues {
  int event = 10000;
  int events = 1000;  // LMAP_EVENTS: one message per robot per frame
  int snapshot = 100;
  int pose = 1000;
};

/// A MainNode on the message layer (transport/node_shell.hpp): receives LMAP_EVENT,
/// LMAP_EVENTS, LMAP_SNAPSHOT and every robot's POSE_<r>; publishes DYNAMIC_NOTICE as soon as an
/// event or snapshot produces one, GLOBAL_MAP for frame k as soon as every robot seen
/// so far has finished k (its POSE marks the end of its frame and says up to which
/// event seq the frame goes: the frame is finished when those events are applied),
/// and GLOBAL_MAP / STATUS_MAIN on request. The main_robot process and
/// the in-process team run both run this. A template on the shell only so that this
/// library builds without the transport; Shell is NodeShell.
template <class Shell>
class MainPorts {
 public:
  MainPorts(Shell& shell, MainNode& node)
      : shell_(shell),
        node_(node),
        map_(channels::global_map(shell.suffix())),
        moving_(channels::global_moving(shell.suffix())),
        notice_(channels::dynamic_notice(shell.suffix())),
        status_(channels::status_main(shell.suffix())),
        resync_(channels::lmap_resync(shell.suffix())) {
    for (int r = 1; r <= kMaxTeamRobots; ++r) team_map_[static_cast<std::size_t>(r - 1)] = channels::team_map(r, shell.suffix());
  }

  /// Subscribe the inputs; false when the transport refused.
  bool open(const MainQueues& queues = {}) {
    shell_.on_decode_error([this] { node_.count_decode_error(); });
    const std::string& sfx = shell_.suffix();
    const int e = shell_.template subscribe<landmark_event_t>(
        channels::lmap_event(sfx), [this](const landmark_event_t& m, const std::string&) { on_event(m); }, queues.event);
    const int b = shell_.template subscribe<lmap_events_t>(
        channels::lmap_events(sfx), [this](const lmap_events_t& m, const std::string&) { on_events(m); }, queues.events);
    const int s = shell_.template subscribe<lmap_snapshot_t>(
        channels::lmap_snapshot(sfx), [this](const lmap_snapshot_t& m, const std::string&) { on_snapshot(m); },
        queues.snapshot);
    const int p = shell_.template subscribe<pose_estimate_t>(
        channels::any_pose(sfx), [this](const pose_estimate_t& m, const std::string&) { on_pose(m); }, queues.pose);
    return e > 0 && b > 0 && s > 0 && p > 0;
  }

  /// GLOBAL_MAP now, stamped `frame` (default: the newest frame every robot has finished).
  /// With main.team_map_period_frames, every robot heard from also gets its team
  /// map (TEAM_MAP_<r>) when one is due for `frame`.
  void publish_map(int frame = -1) {
    last_map_utime_ = shell_.now_utime();
    const int n = node_.make_global_map(last_map_utime_, frame);
    for (int i = 0; i < n; ++i) shell_.publish(map_, node_.map_chunk(i));
    const int k = node_.make_moving_set(last_map_utime_, frame);
    if (node_.moving_set_due(k, last_map_utime_))
      for (int i = 0; i < k; ++i) shell_.publish(moving_, node_.map_chunk(i));
    if (!node_.team_map_due(frame)) return;
    for (int r = 1; r <= kMaxTeamRobots; ++r) {
      if (!node_.robot_seen(r)) continue;
      const int m = node_.make_team_map(r, shell_.now_utime(), frame);
      for (int i = 0; i < m; ++i) shell_.publish(team_map_[static_cast<std::size_t>(r - 1)], node_.map_chunk(i));
    }
  }
  /// The timer's GLOBAL_MAP (main.publish_rate_hz): only when no map went out in the
  /// last `period_us`. While the team's frames finish, each finished frame publishes
  /// its map and the timer adds none (a second one every period would double the map
  /// traffic at 10 Hz, docs/benchmarks.md "Scale"); when they stall (a robot
  /// down, POSEs lost) the timer keeps the map going out.
  void publish_map_if_quiet(std::int64_t period_us) {
    if (last_map_utime_ != kNever && shell_.now_utime() - last_map_utime_ < period_us) return;
    publish_map();
  }
  void publish_status() {
    node_status_t m = node_.status_msg(shell_.now_utime());
    shell_.stamp_auth(&m);
    shell_.publish(status_, m);
  }

 private:
  void on_event(const landmark_event_t& m) {
    std::string why;
    if (!node_.on_event(m, &why)) shell_.refuse("event refused: " + why);
    send_notices();
    publish_finished();
  }
  void on_events(const lmap_events_t& m) {
    std::string why;
    if (!node_.on_events(m, &why)) shell_.refuse("events refused: " + why);
    send_notices();
    publish_finished();
  }
  void on_snapshot(const lmap_snapshot_t& m) {
    std::string why;
    if (!node_.on_snapshot(m, &why)) shell_.refuse("snapshot refused: " + why);
    send_notices();
    publish_finished();
  }
  /// A held POSE's events are in: that frame's map (MainNode::take_finished).
  void publish_finished() {
    if (const int done = node_.take_finished(); done >= 0) publish_map(done);
  }
  void on_pose(const pose_estimate_t& m) {
    std::string why;
    const int done = node_.on_pose(m, &why);
    if (!why.empty()) shell_.refuse("pose refused: " + why);
    send_notices();
    if (done >= 0) publish_map(done);
  }
  void send_notices() {
    for (const auto& n : node_.take_notices(shell_.now_utime())) shell_.publish(notice_, n);
    for (const auto& r : node_.take_resyncs(shell_.now_utime())) shell_.publish(resync_, r);
    const std::string alert = node_.take_alert();
    if (!alert.empty()) shell_.say(alert, log::Priority::kWarning);
  }

  static constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::min();
  Shell& shell_;
  MainNode& node_;
  std::int64_t last_map_utime_ = kNever;  // when the last GLOBAL_MAP went out
  const std::string map_, moving_, notice_, status_, resync_;  // channel names, built once
  std::array<std::string, kMaxTeamRobots> team_map_;  // TEAM_MAP_<r>
};

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
#include "elaslam/main_robot/main_node.hpp"

#include <algorithm>
#include <cstdio>

#include "elaslam/common/contract.hpp"
#include "elaslam/common/cov.hpp"
#include "elaslam/main_robot/main_checks.hpp"

namespace elaslam {

MainNode::MainNode(const GlobalMapOptions& options) : map_(options), publisher_(options.max_landmark_id) {
  pose_frame_.fill(-1);
  incarnation_refused_frame_.fill(-1);
  resync_frame_.fill(-1000000);
  const auto max_id = static_cast<std::size_t>(options.max_landmark_id);
  pending_.reserve(max_id);
  notices_.reserve(max_id);
  snap_lms_.reserve(max_id);  // a valid chunk lists each id at most once (main_checks::snapshot)
  snap_moving_.reserve(max_id);
  snap_moving_frames_.reserve(max_id);
  resyncs_.reserve(kMaxTeamRobots * 4);
  taken_.reserve(kMaxTeamRobots * 4);
  alert_.reserve(kAlertCapacity);  // check_team's lines go in without allocating
  // Every chunk a GLOBAL_TRACKS publication can have, each with room for a full
  // chunk: making them allocates nothing (num_tracks says how many count).
  global_tracks_.resize(contract::kMaxTrackChunks);
  for (auto& c : global_tracks_) c.tracks.resize(contract::kMaxGlobalTracks);
}

namespace {

/// A check that says why into *reason when the caller asks, else into a local.
template <typename Check>
std::string checked(Refusal* reason, Check check) {
  Refusal ignored = Refusal::kMalformed;
  return check(reason ? reason : &ignored);
}

}  // namespace

std::string MainNode::validate(const landmark_event_t& m, Refusal* reason) const {
  return checked(reason, [&](Refusal* r) { return main_checks::event(m, map_.options().limits, map_.max_landmark_id(), r); });
}

std::string MainNode::validate(const lmap_snapshot_t& m, Refusal* reason) const {
  return checked(reason, [&](Refusal* r) { return main_checks::snapshot(m, map_.options().limits, map_.max_landmark_id(), r); });
}

std::string MainNode::validate(const lmap_events_t& m, Refusal* reason) const {
  return checked(reason, [&](Refusal* r) { return main_checks::events(m, map_.options().limits, r); });
}

std::string MainNode::validate(const pose_estimate_t& m, Refusal* reason) const {
  return checked(reason, [&](Refusal* r) { return main_checks::pose(m, map_.options().limits, r); });
}

std::string MainNode::validate(const track_list_t& m, Refusal* reason) const {
  return checked(reason, [&](Refusal* r) { return main_checks::tracks(m, map_.options().limits, map_.max_landmark_id(), r); });
}

// The newest frame known of the robot (else of the team, when the robot is new): a
// message further ahead than max_frame_gap is held until a next one confirms it.
std::string MainNode::check_frame(int robot_id, int frame, Refusal* reason) {
  const auto r = static_cast<std::size_t>(robot_id - 1);
  int last = std::max(map_.stream(robot_id).last_frame, completion_.robot_frame(robot_id));
  if (last < 0) last = std::max(map_.newest_frame(), completion_.completed());
  if (last < 0) return "";  // nothing known yet: the first frame sets the reference
  const auto v = frame_guard_[r].check(last, frame, map_.options().max_frame_gap, /*strictly_after=*/false);
  if (v != JumpGuard::Verdict::kHeld) return "";
  *reason = Refusal::kFrameWindow;
  return contract::got("frame more than max_frame_gap " + std::to_string(map_.options().max_frame_gap) +
                           " ahead of robot " + std::to_string(robot_id) + "'s last " + std::to_string(last) +
                           ", held until a next message confirms it",
                       frame);
}

std::string MainNode::check_seq(int robot_id, std::int64_t seq, bool snapshot, Refusal* reason) {
  const auto r = static_cast<std::size_t>(robot_id - 1);
  const std::int64_t last = map_.stream(robot_id).last_seq;
  if (seq <= last) return "";  // a duplicate or stale one: the map ignores it
  JumpGuard& g = snapshot ? snapshot_guard_[r] : event_guard_[r];
  if (g.check(last, seq, map_.options().max_seq_jump, /*strictly_after=*/!snapshot) != JumpGuard::Verdict::kHeld) return "";
  *reason = Refusal::kSeqWindow;
  return contract::got("seq more than max_seq_jump " + std::to_string(map_.options().max_seq_jump) + " ahead of robot " +
                           std::to_string(robot_id) + "'s last " + std::to_string(last) +
                           ", held until a next message confirms it",
                       seq);
}

bool MainNode::accept_incarnation(int robot_id, std::int64_t incarnation, int frame) {
  switch (map_.observe_incarnation(robot_id, incarnation, frame)) {
    case IncarnationVerdict::kCurrent: return true;
    case IncarnationVerdict::kRestarted: restarted(robot_id, incarnation, frame); return true;
    case IncarnationVerdict::kStale: refused_incarnation(robot_id, incarnation, frame); return false;
  }
  return false;
}

void MainNode::restarted(int robot_id, std::int64_t incarnation, int frame) {
  ++counters_.restarts;
  const auto r = static_cast<std::size_t>(robot_id - 1);
  completion_.restart(robot_id);
  fusion_.forget(robot_id);  // the tracks of its earlier incarnation
  frame_guard_[r].clear();
  event_guard_[r].clear();
  snapshot_guard_[r].clear();
  alert_ = "robot " + std::to_string(robot_id) + " restarted without its state (incarnation " +
           std::to_string(incarnation) +
           (map_.stream(robot_id).restarted_back
                ? ", older than the one followed, which is no longer heard: its start count or clock was reset"
                : "") +
           "): its stream starts over, snapshot requested";
  // Far behind the frame the team finished: the sensor source started over (a new
  // run; frames are the team's one index, a robot restarted within a run comes back
  // at the team's frame). The team's frame starts over with it, else no map would go
  // out until the new run passed the old one's last frame.
  const int completed = completion_.completed();
  if (completed >= 0 && frame < completed - map_.options().max_frame_gap) {
    alert_ += "; frame " + std::to_string(frame) + " is far behind the team's " + std::to_string(completed) +
              ": a new run, the team's frame starts over";
    completion_.new_run();
    team_map_frame_ = -1;
    ++counters_.runs_started;
  }
  request_resync(robot_id, resync_request_t::NEW_INCARNATION);
}

void MainNode::refused_incarnation(int robot_id, std::int64_t incarnation, int frame) {
  ++counters_.stale_incarnation;
  counters_.refused.add(Refusal::kStale);
  ++counters_.rejected_inputs;
  // FAULT_INCARNATION for kAlertFrames of the team after the last such refusal; a line
  // at the first of a series (a duplicate sender has its own, below).
  const auto ri = static_cast<std::size_t>(robot_id - 1);
  const int team_frame = std::max(completion_.completed(), frame);
  if (incarnation_refused_frame_[ri] < 0 || team_frame - incarnation_refused_frame_[ri] >= kAlertFrames)
    if (alert_.empty() && !map_.duplicate_sender(robot_id))
      alert_ = "FAULT: robot " + std::to_string(robot_id) + "'s messages of incarnation " + std::to_string(incarnation) +
               " refused: main follows its incarnation " + std::to_string(map_.stream(robot_id).incarnation) +
               " (a replay, or a second sender with its id)";
  incarnation_refused_frame_[ri] = team_frame;
  auto& alerted = alerted_duplicate_[ri];
  if (map_.duplicate_sender(robot_id) && !alerted) {
    alert_ = "FAULT: two live senders use robot id " + std::to_string(robot_id) + " (incarnations " +
             std::to_string(map_.stream(robot_id).incarnation) + " and " + std::to_string(incarnation) +
             "); following the newer one";
  }
  alerted = map_.duplicate_sender(robot_id);
}

void MainNode::note_save(bool ok, const std::string& why) {
  if (!ok && !save_failed_ && alert_.empty()) alert_ = "FAULT: main_robot cannot save its state: " + why;
  save_failed_ = !ok;
}

void MainNode::request_resync(int robot_id, std::int8_t reason) {
  const auto r = static_cast<std::size_t>(robot_id - 1);
  const int frame = std::max(map_.stream(robot_id).last_frame, completion_.robot_frame(robot_id));
  if (reason == resync_request_t::GAP && frame - resync_frame_[r] < map_.options().resync_interval_frames) return;
  resync_frame_[r] = frame;
  if (resyncs_.size() >= resyncs_.capacity()) return;
  resync_request_t q{};
  q.robot_id = static_cast<std::int16_t>(robot_id);
  q.robot_incarnation = map_.stream(robot_id).incarnation;
  q.after_seq = map_.stream(robot_id).last_seq;
  q.reason = reason;
  resyncs_.push_back(q);
}

const std::vector<resync_request_t>& MainNode::take_resyncs(std::int64_t now_utime) {
  taken_.swap(resyncs_);  // both reserved at construction: no allocation
  resyncs_.clear();
  for (auto& q : taken_) {
    q.utime = now_utime;
    q.incarnation = incarnation_;
  }
  counters_.resyncs_requested += static_cast<std::int64_t>(taken_.size());
  return taken_;
}

std::string MainNode::take_alert() {
  std::string a(alert_);  // a copy: alert_ keeps its reserved capacity
  alert_.clear();
  return a;
}

template <class Msg>
bool MainNode::admit(const Msg& m, bool snapshot, std::string* why) {
  Refusal reason = Refusal::kMalformed;
  if (const std::string problem = validate(m, &reason); !problem.empty()) return refused(reason, problem, why);
  if (!accept_incarnation(m.robot_id, m.incarnation, m.frame)) {
    if (why)
      *why = std::string(snapshot ? "snapshot" : "event") + " of an older incarnation of robot " +
             std::to_string(m.robot_id) + " (replay or second sender)";
    return false;
  }
  if (std::string p = check_seq(m.robot_id, m.seq, snapshot, &reason); !p.empty()) return refused(reason, p, why);
  if (std::string p = check_frame(m.robot_id, m.frame, &reason); !p.empty()) return refused(reason, p, why);
  return true;
}

bool MainNode::on_event(const landmark_event_t& m, std::string* why) {
  if (!admit(m, false, why)) return false;
  GlobalEvent e;
  e.robot_id = m.robot_id;
  e.seq = m.seq;
  e.frame = m.frame;
  e.kind = m.kind;
  e.landmark_id = m.landmark_id;
  e.position = {m.x, m.y};
  e.cov = read_cov(m.cov);
  switch (map_.apply(e, &pending_)) {
    case EventResult::kApplied: ++counters_.events; break;
    case EventResult::kAppliedAfterGap:
      ++counters_.events, ++counters_.gaps;
      request_resync(m.robot_id, resync_request_t::GAP);
      break;
    case EventResult::kDuplicate:
    case EventResult::kStale: ++counters_.duplicates; break;
  }
  completion_.events_applied(m.robot_id, map_.stream(m.robot_id).last_seq);
  return true;
}

bool MainNode::on_events(const lmap_events_t& m, std::string* why) {
  Refusal reason = Refusal::kMalformed;
  if (const std::string problem = validate(m, &reason); !problem.empty()) return refused(reason, problem, why);
  bool all = true;
  std::string first;
  for (int k = 0; k < m.num_events; ++k) {
    std::string w;
    if (!on_event(m.events[static_cast<std::size_t>(k)], why ? &w : nullptr) && all) {
      all = false;
      first = std::move(w);
    }
  }
  if (!all && why) *why = first;
  return all;
}

bool MainNode::on_snapshot(const lmap_snapshot_t& m, std::string* why) {
  if (!admit(m, true, why)) return false;
  snap_lms_.clear();
  snap_moving_.clear();
  snap_moving_frames_.clear();
  for (int k = 0; k < m.num_landmarks; ++k) {
    const landmark_estimate_t& l = m.landmarks[static_cast<std::size_t>(k)];
    snap_lms_.push_back({l.id, RobotEstimate{true, {l.x, l.y}, read_cov(l.cov), m.frame}});
  }
  for (int k = 0; k < m.num_moving; ++k) {
    snap_moving_.push_back(m.moving_ids[static_cast<std::size_t>(k)]);
    snap_moving_frames_.push_back(m.moving_frames[static_cast<std::size_t>(k)]);
  }
  if (!map_.apply_snapshot(m.robot_id, m.seq, m.frame, m.id_begin, m.id_end, snap_lms_, snap_moving_,
                           snap_moving_frames_, &pending_)) {
    ++counters_.stale_snapshots;
    const RobotStream& st = map_.stream(m.robot_id);
    const std::string what = m.seq < st.last_seq ? "the robot's events applied (seq " + std::to_string(st.last_seq) + ")"
                                                 : "the one applied (seq " + std::to_string(st.snapshot_seq) +
                                                       ", frame " + std::to_string(st.snapshot_frame) + ")";
    return refused(Refusal::kStale,
                   "snapshot (seq " + std::to_string(m.seq) + ", frame " + std::to_string(m.frame) + ") older than " +
                       what + ": it would roll the map back",
                   why);
  }
  ++counters_.snapshots;
  if (m.chunk == m.num_chunks - 1)  // its last chunk
    completion_.snapshot_applied(m.robot_id, m.frame, map_.stream(m.robot_id).last_seq);
  else
    completion_.events_applied(m.robot_id, map_.stream(m.robot_id).last_seq);
  return true;
}

const std::vector<dynamic_notice_t>& MainNode::take_notices(std::int64_t now_utime) {
  notices_.clear();
  for (const Notice& n : pending_) {
    dynamic_notice_t d{};
    d.utime = now_utime;
    d.frame = n.frame;
    d.incarnation = incarnation_;
    d.seq = ++notice_seq_;
    d.landmark_id = n.landmark_id;
    d.detected_by = static_cast<int16_t>(n.detected_by);
    notices_.push_back(d);
  }
  pending_.clear();
  counters_.notices_sent += static_cast<std::int64_t>(notices_.size());
  return notices_;
}

bool MainNode::refused(Refusal reason, const std::string& problem, std::string* why) {
  return counters_.refused.count(reason, problem, &counters_.rejected_inputs, why);
}

int MainNode::on_pose(const pose_estimate_t& m, std::string* why) {
  Refusal reason = Refusal::kMalformed;
  // A POSE from outside the team never counts towards the frame the team has finished.
  if (const std::string problem = validate(m, &reason); !problem.empty()) return refused(reason, problem, why), -1;
  const auto r = static_cast<std::size_t>(m.robot_id - 1);
  const bool first = map_.stream(m.robot_id).incarnation == 0 && completion_.robot_frame(m.robot_id) < 0;
  if (!accept_incarnation(m.robot_id, m.incarnation, m.frame)) return -1;
  if (std::string p = check_frame(m.robot_id, m.frame, &reason); !p.empty()) return refused(reason, p, why), -1;
  // A robot heard again after more than kPartitionFrames of its frames were missing:
  // a partition (or a burst of loss) healed; said, and flagged for kAlertFrames.
  if (pose_frame_[r] >= 0 && m.frame - pose_frame_[r] > kPartitionFrames) {
    healed_frame_ = m.frame;
    if (alert_.empty())
      alert_ = "robot " + std::to_string(m.robot_id) + " heard again at frame " + std::to_string(m.frame) +
             " after frame " + std::to_string(pose_frame_[r]) + " (" + std::to_string(m.frame - pose_frame_[r] - 1) +
             " of its frames missing): a partition or a lossy stretch healed";
  }
  pose_frame_[r] = std::max(pose_frame_[r], m.frame);
  // Heard of first past its first frames (main started late or without its state):
  // the robot's earlier events never reached this map.
  if (first && m.frame > 0 && map_.stream(m.robot_id).last_seq == 0)
    request_resync(m.robot_id, resync_request_t::MAIN_STARTED);
  // A POSE older than one held or finished (a late or repeated datagram): the robot
  // is past that frame; it changes nothing (holding it would let the held one go).
  if (completion_.stale(m.robot_id, m.frame)) {
    ++counters_.stale_poses;
    return -1;
  }
  // Where the robot is, no static landmark can be (off while main.body_radius_m is 0).
  const Eigen::Vector2d position(m.x, m.y);
  const Eigen::Matrix2d position_cov = read_cov(m.cov).topLeftCorner<2, 2>();
  counters_.occupied += map_.occupy(m.robot_id, m.frame, position, position_cov, &pending_);
  const FrameCompletion::PoseOutcome out =
      completion_.take_pose(m.robot_id, m.frame, m.event_seq, m.snapshot_chunks, map_.stream(m.robot_id).last_seq);
  // An older POSE let go with its events still not in: lost (or late). The robot's
  // last events of a burst would otherwise be missed until its next event shows the
  // gap, which may be never: a gap now, repaired by a snapshot taken after them (a
  // late one that still comes is applied as usual).
  if (out.let_go_frame >= 0 && map_.missed_events(m.robot_id, out.let_go_event_seq)) ++counters_.gaps;
  if (map_.stream(m.robot_id).gap_pending) request_resync(m.robot_id, resync_request_t::GAP);  // (rate-limited)
  return out.finished;
}

int MainNode::stamp(int frame) const {
  if (frame >= 0) return frame;
  return completion_.completed() >= 0 ? completion_.completed() : map_.newest_frame();
}

int MainNode::make_global_map(std::int64_t now_utime, int frame) {
  const int n = publisher_.make(map_, MapPublisher::Kind::kGlobalMap, now_utime, stamp(frame), incarnation_);
  if (publisher_.capacity_fault()) ++counters_.capacity_faults;
  ++counters_.maps_published;
  counters_.map_chunks += n;
  return n;
}

int MainNode::make_moving_set(std::int64_t now_utime, int frame) {
  return publisher_.make(map_, MapPublisher::Kind::kMovingSet, now_utime, stamp(frame), incarnation_);
}

bool MainNode::moving_set_due(int num_chunks, std::int64_t now_utime) {
  if (!publisher_.moving_set_due(num_chunks, now_utime, map_.options().moving_repeat_s)) return false;
  ++counters_.moving_sets;
  return true;
}

int MainNode::make_team_map(int robot_id, std::int64_t now_utime, int frame) {
  if (robot_id < 1 || robot_id > kMaxTeamRobots) return 0;
  const int n = publisher_.make(map_, MapPublisher::Kind::kTeamMap, now_utime, stamp(frame), incarnation_, robot_id);
  if (publisher_.capacity_fault()) ++counters_.capacity_faults;
  ++counters_.team_maps_published;
  return n;
}

// Once per period: at the first finished frame of a period after the last team
// map's (frame k * period in a lossless run; the next one finished when the team's
// finished frame jumps over it, lost POSEs).
bool MainNode::team_map_due(int frame) {
  const int period = map_.options().team_map_period_frames;
  if (period <= 0 || frame < 0 || frame <= team_map_frame_) return false;
  if (team_map_frame_ >= 0 && frame / period <= team_map_frame_ / period) return false;
  team_map_frame_ = frame;
  check_team();
  return true;
}

// A round of team maps begins: who is left out of it (GlobalMap::check_team). Said
// when it changes: an alert line, and FAULT_INCONSISTENT in STATUS_MAIN while anyone
// is left out. The line is formatted into the alert's reserved capacity: no
// allocation on main's frame path (FrameNoAlloc).
void MainNode::check_team() {
  const unsigned before = map_.left_out();
  const unsigned now = map_.check_team();
  for (int r = 1; r <= kMaxTeamRobots; ++r) {
    const unsigned bit = 1u << (r - 1);
    if ((now & bit) == (before & bit)) continue;
    const TeamCheck& t = map_.team_check(r);
    char line[192];
    const char* sep = alert_.empty() ? "" : "; ";
    int n = 0;
    if (now & bit) {
      n = std::snprintf(line, sizeof line,
                        "%srobot %d's map disagrees with the other robots' on %d of %d shared landmarks: left out of "
                        "their team maps",
                        sep, r, t.disagree, t.shared);
    } else if (t.shared < kTeamCheckMinShared) {
      n = std::snprintf(line, sizeof line,
                        "%srobot %d's map shares too few landmarks with the other robots' to be judged (%d, fewer "
                        "than %d): back in their team maps",
                        sep, r, t.shared, kTeamCheckMinShared);
    } else {
      n = std::snprintf(line, sizeof line,
                        "%srobot %d's map agrees with the other robots' again (%d of %d shared landmarks disagree): "
                        "back in their team maps",
                        sep, r, t.disagree, t.shared);
    }
    if (n > 0 && alert_.size() + static_cast<std::size_t>(n) <= alert_.capacity()) alert_.append(line);
  }
}

node_status_t MainNode::status_msg(std::int64_t now_utime) const {
  node_status_t s{};
  s.utime = now_utime;
  s.frame = map_.newest_frame();
  s.node_kind = node_status_t::MAIN;
  s.node_id = 0;
  s.odom_turn_scale = s.odom_speed_scale = 1.0f;  // no odometer of its own: the identity
  s.incarnation = incarnation_;
  for (int r = 1; r <= kMaxTeamRobots; ++r) {
    if (map_.duplicate_sender(r)) {
      s.duplicate_robots = static_cast<std::int16_t>(s.duplicate_robots | (1 << (r - 1)));
      s.fault_flags |= node_status_t::FAULT_DUPLICATE_SENDER;
    }
    if (map_.stream(r).gap_pending) s.fault_flags |= node_status_t::FAULT_UNREPAIRED_GAP;
  }
  if (publisher_.capacity_fault()) s.fault_flags |= node_status_t::FAULT_CAPACITY;
  if (map_.left_out() != 0) s.fault_flags |= node_status_t::FAULT_INCONSISTENT;
  const int team_frame = std::max(completion_.completed(), map_.newest_frame());
  for (std::size_t r = 0; r < kMaxTeamRobots; ++r)
    if (incarnation_refused_frame_[r] >= 0 && team_frame - incarnation_refused_frame_[r] < kAlertFrames)
      s.fault_flags |= node_status_t::FAULT_INCARNATION;
  if (healed_frame_ >= 0 && team_frame - healed_frame_ < kAlertFrames) s.fault_flags |= node_status_t::FAULT_PARTITION_HEALED;
  if (save_failed_) s.fault_flags |= node_status_t::FAULT_SAVE_FAILED;
  for (int k = 0; k < kNumRefusals; ++k) s.refused[k] = counters_.refused.n[static_cast<std::size_t>(k)];
  s.frames = counters_.events;
  s.frames_dropped = counters_.gaps;
  s.rejected_inputs = counters_.rejected_inputs;
  s.decode_errors = counters_.decode_errors;
  s.events_sent = counters_.notices_sent;
  return s;
}

}  // namespace elaslam

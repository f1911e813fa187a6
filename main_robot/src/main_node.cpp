// SPDX-License-Identifier: Apache-2.0
#include "elaslam/main_robot/main_node.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "elaslam/common/contract.hpp"
#include "elaslam/common/cov.hpp"

namespace elaslam {
namespace {


// A global map chunk's two kinds of entry (chunks.hpp, prepare_chunks).
void grow_static(global_map_t* m, int n) { contract::set_count(&m->landmarks, &m->num_landmarks, n); }
void grow_moving(global_map_t* m, int n) {
  contract::set_count(&m->moving_ids, &m->num_moving, n);
  m->moving_frames.resize(static_cast<std::size_t>(n));
  m->moving_by.resize(static_cast<std::size_t>(n));
}

}  // namespace

MainNode::MainNode(const GlobalMapOptions& options) : map_(options) {
  robot_frame_.fill(-1);
  pose_frame_.fill(-1);
  incarnation_refused_frame_.fill(-1);
  snapshot_done_frame_.fill(-1);
  resync_frame_.fill(-1000000);
  const auto max_id = static_cast<std::size_t>(options.max_landmark_id);
  pending_.reserve(max_id);
  notices_.reserve(max_id);
  snap_lms_.reserve(max_id);  // a valid chunk lists each id at most once (validate)
  snap_moving_.reserve(max_id);
  snap_moving_frames_.reserve(max_id);
  resyncs_.reserve(kMaxTeamRobots * 4);
  taken_.reserve(kMaxTeamRobots * 4);
  static_ids_.reserve(max_id);
  moving_ids_.reserve(max_id);
  moving_sent_.reserve(3 * max_id);
  moving_now_.reserve(3 * max_id);
  // All ids counted as the larger kind of entry: a bound for any mix of the two.
  prepare_chunks(grow_static, grow_moving, contract::kMaxChunkBytes, options.max_landmark_id, 0, &chunk_sizes_, &chunks_);
  spans_.reserve(chunks_.size());
  alert_.reserve(kAlertCapacity);  // check_team's lines go in without allocating
}

namespace {

/// The robot id of a message: within the contract, then in the team.
std::string check_robot(int robot_id, const MessageLimits& l, Refusal* reason) {
  if (robot_id < 1 || robot_id > kMaxTeamRobots) {
    *reason = Refusal::kMalformed;
    return contract::got(contract::outside("robot_id", 1, kMaxTeamRobots), robot_id);
  }
  if (!l.in_team(robot_id)) {
    *reason = Refusal::kOutsideTeam;
    return contract::got("robot_id not in limits.team " + team_text(l.team_mask), robot_id);
  }
  return "";
}

}  // namespace

std::string MainNode::validate(const landmark_event_t& m, Refusal* reason) const {
  Refusal dummy = Refusal::kMalformed;
  Refusal& r = reason ? *reason : dummy;
  const MessageLimits& lim = map_.options().limits;
  if (std::string p = check_robot(m.robot_id, lim, &r); !p.empty()) return p;
  r = Refusal::kMalformed;
  if (m.seq < 1 || m.seq > kMaxSeq) return contract::got("seq not in [1, 2^62]", m.seq);
  if (m.incarnation < 0) return contract::got("incarnation is negative", m.incarnation);
  if (m.frame < 0) return contract::got("frame is negative", m.frame);
  if (m.kind < landmark_event_t::ADD || m.kind > landmark_event_t::RETURN) return contract::got("unknown kind", int(m.kind));
  if (m.landmark_id < 0 || m.landmark_id >= map_.max_landmark_id())
    return contract::got("landmark_id outside [0, max_landmark_id)", m.landmark_id);
  if (m.kind != landmark_event_t::MOVING) {
    r = Refusal::kImplausible;
    if (std::string p = check_position(m.x, m.y, lim, "position"); !p.empty()) return p;
    if (std::string p = check_cov2(m.cov, lim, "cov"); !p.empty()) return p;
  }
  return "";
}

std::string MainNode::validate(const lmap_snapshot_t& m, Refusal* reason) const {
  Refusal dummy = Refusal::kMalformed;
  Refusal& r = reason ? *reason : dummy;
  const MessageLimits& lim = map_.options().limits;
  if (std::string p = check_robot(m.robot_id, lim, &r); !p.empty()) return p;
  r = Refusal::kMalformed;
  if (m.seq < 0 || m.seq > kMaxSeq) return contract::got("seq not in [0, 2^62]", m.seq);
  if (m.incarnation < 0) return contract::got("incarnation is negative", m.incarnation);
  if (m.frame < 0) return contract::got("frame is negative", m.frame);
  if (m.num_chunks < 1 || m.chunk < 0 || m.chunk >= m.num_chunks) return contract::got("chunk outside [0, num_chunks)", m.chunk);
  if (m.id_begin < 0 || m.id_end <= m.id_begin || m.id_end > map_.max_landmark_id())
    return contract::got("id range not within [0, max_landmark_id), id_begin", m.id_begin);
  if (!contract::count_fits(m.landmarks, m.num_landmarks)) return contract::got("num_landmarks does not match the array", m.num_landmarks);
  if (!contract::count_fits(m.moving_ids, m.num_moving) || !contract::count_fits(m.moving_frames, m.num_moving))
    return contract::got("num_moving does not match the arrays", m.num_moving);
  int previous = -1;
  for (int k = 0; k < m.num_landmarks; ++k) {
    const landmark_estimate_t& l = m.landmarks[static_cast<std::size_t>(k)];
    r = Refusal::kMalformed;
    if (l.id < m.id_begin || l.id >= m.id_end) return contract::got("landmark id outside the chunk's range", l.id);
    if (l.id == previous) return r = Refusal::kDuplicateId, contract::got("landmark id listed twice", l.id);
    if (l.id < previous) return contract::got("landmark ids not ascending, id", l.id);
    previous = l.id;
    r = Refusal::kImplausible;  // (no string built unless refused: the frame path allocates nothing)
    if (std::string p = check_position(l.x, l.y, lim, "position"); !p.empty()) return "landmark " + std::to_string(l.id) + " " + p;
    if (std::string p = check_cov2(l.cov, lim, "cov"); !p.empty()) return "landmark " + std::to_string(l.id) + " " + p;
  }
  previous = -1;
  for (int k = 0; k < m.num_moving; ++k) {
    const int id = m.moving_ids[static_cast<std::size_t>(k)];
    r = Refusal::kMalformed;
    if (id < m.id_begin || id >= m.id_end) return contract::got("moving id outside the chunk's range", id);
    // Ascending like the landmarks (snapshot chunks list both in id order): a repeat is one id twice.
    if (id == previous) return r = Refusal::kDuplicateId, contract::got("moving id listed twice", id);
    if (id < previous) return contract::got("moving ids not ascending, id", id);
    previous = id;
    const int found = m.moving_frames[static_cast<std::size_t>(k)];
    if (found < -1 || found > m.frame) return contract::got("moving frame not in [-1, the snapshot's frame]", found);
  }
  // One id both static and moving: two contradicting entries for it.
  for (int a = 0, b = 0; a < m.num_landmarks && b < m.num_moving;) {
    const int ia = m.landmarks[static_cast<std::size_t>(a)].id, ib = m.moving_ids[static_cast<std::size_t>(b)];
    if (ia == ib) return r = Refusal::kDuplicateId, contract::got("id listed as static and as moving", ia);
    (ia < ib ? a : b)++;
  }
  return "";
}

std::string MainNode::validate(const pose_estimate_t& m, Refusal* reason) const {
  Refusal dummy = Refusal::kMalformed;
  Refusal& r = reason ? *reason : dummy;
  const MessageLimits& lim = map_.options().limits;
  if (std::string p = check_robot(m.robot_id, lim, &r); !p.empty()) return p;
  r = Refusal::kMalformed;
  if (m.event_seq < 0 || m.event_seq > kMaxSeq) return contract::got("event_seq not in [0, 2^62]", m.event_seq);
  if (m.snapshot_chunks < 0) return contract::got("snapshot_chunks is negative", m.snapshot_chunks);
  return check_pose(m, lim, &r);
}

// The newest frame known of the robot (else of the team, when the robot is new): a
// message further ahead than max_frame_gap is held until a next one confirms it.
std::string MainNode::check_frame(int robot_id, int frame, Refusal* reason) {
  const auto r = static_cast<std::size_t>(robot_id - 1);
  int last = std::max(map_.stream(robot_id).last_frame, robot_frame_[r]);
  if (last < 0) last = std::max(map_.newest_frame(), completed_frame_);
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
    case IncarnationVerdict::kRestarted:
      ++counters_.restarts;
      robot_frame_[static_cast<std::size_t>(robot_id - 1)] = -1;
      held_[static_cast<std::size_t>(robot_id - 1)] = HeldPose{};  // it waited for the old stream's seq
      snapshot_done_frame_[static_cast<std::size_t>(robot_id - 1)] = -1;
      frame_guard_[static_cast<std::size_t>(robot_id - 1)].clear();
      event_guard_[static_cast<std::size_t>(robot_id - 1)].clear();
      snapshot_guard_[static_cast<std::size_t>(robot_id - 1)].clear();
      alert_ = "robot " + std::to_string(robot_id) + " restarted without its state (incarnation " +
               std::to_string(incarnation) +
               (map_.stream(robot_id).restarted_back
                    ? ", older than the one followed, which is no longer heard: its start count or clock was reset"
                    : "") +
               "): its stream starts over, snapshot requested";
      // Far behind the frame the team finished: the sensor source started over (a
      // new run; frames are the team's one index, a robot restarted within a run
      // comes back at the team's frame). The team's frame starts over with it, else
      // no map would go out until the new run passed the old one's last frame.
      if (completed_frame_ >= 0 && frame < completed_frame_ - map_.options().max_frame_gap) {
        alert_ += "; frame " + std::to_string(frame) + " is far behind the team's " + std::to_string(completed_frame_) +
                  ": a new run, the team's frame starts over";
        completed_frame_ = -1;
        team_map_frame_ = -1;
        ++counters_.runs_started;
      }
      request_resync(robot_id, resync_request_t::NEW_INCARNATION);
      return true;
    case IncarnationVerdict::kStale: break;
  }
  ++counters_.stale_incarnation;
  counters_.refused.add(Refusal::kStale);
  ++counters_.rejected_inputs;
  // FAULT_INCARNATION for kAlertFrames of the team after the last such refusal; a line
  // at the first of a series (a duplicate sender has its own, below).
  const auto ri = static_cast<std::size_t>(robot_id - 1);
  const int team_frame = std::max(completed_frame_, frame);
  if (incarnation_refused_frame_[ri] < 0 || team_frame - incarnation_refused_frame_[ri] >= kAlertFrames)
    if (alert_.empty() && !map_.duplicate_sender(robot_id))
      alert_ = "FAULT: robot " + std::to_string(robot_id) + "'s messages of incarnation " + std::to_string(incarnation) +
               " refused: main follows its incarnation " + std::to_string(map_.stream(robot_id).incarnation) +
               " (a replay, or a second sender with its id)";
  incarnation_refused_frame_[ri] = team_frame;
  auto& alerted = alerted_duplicate_[static_cast<std::size_t>(robot_id - 1)];
  if (map_.duplicate_sender(robot_id) && !alerted) {
    alert_ = "FAULT: two live senders use robot id " + std::to_string(robot_id) + " (incarnations " +
             std::to_string(map_.stream(robot_id).incarnation) + " and " + std::to_string(incarnation) +
             "); following the newer one";
  }
  alerted = map_.duplicate_sender(robot_id);
  return false;
}

void MainNode::note_save(bool ok, const std::string& why) {
  if (!ok && !save_failed_ && alert_.empty()) alert_ = "FAULT: main_robot cannot save its state: " + why;
  save_failed_ = !ok;
}

void MainNode::request_resync(int robot_id, std::int8_t reason) {
  const auto r = static_cast<std::size_t>(robot_id - 1);
  const int frame = std::max(map_.stream(robot_id).last_frame, robot_frame_[r]);
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

bool MainNode::on_event(const landmark_event_t& m, std::string* why) {
  Refusal reason = Refusal::kMalformed;
  if (const std::string problem = validate(m, &reason); !problem.empty()) return refused(reason, problem, why);
  if (!accept_incarnation(m.robot_id, m.incarnation, m.frame)) {
    if (why) *why = "event of an older incarnation of robot " + std::to_string(m.robot_id) + " (replay or second sender)";
    return false;
  }
  if (std::string p = check_seq(m.robot_id, m.seq, false, &reason); !p.empty()) return refused(reason, p, why);
  if (std::string p = check_frame(m.robot_id, m.frame, &reason); !p.empty()) return refused(reason, p, why);
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
  settle_pose(m.robot_id);
  return true;
}

std::string MainNode::validate(const lmap_events_t& m, Refusal* reason) const {
  Refusal dummy = Refusal::kMalformed;
  Refusal& r = reason ? *reason : dummy;
  if (std::string p = check_robot(m.robot_id, map_.options().limits, &r); !p.empty()) return p;
  r = Refusal::kMalformed;
  if (m.incarnation < 0) return contract::got("incarnation is negative", m.incarnation);
  if (m.frame < 0) return contract::got("frame is negative", m.frame);
  if (m.num_events < 1 || m.num_events > contract::kMaxBatchEvents)
    return contract::got("num_events outside [1, " + std::to_string(contract::kMaxBatchEvents) + "]", m.num_events);
  if (!contract::count_fits(m.events, m.num_events)) return contract::got("num_events does not match the array", m.num_events);
  std::int64_t previous = 0;
  for (int k = 0; k < m.num_events; ++k) {
    const landmark_event_t& e = m.events[static_cast<std::size_t>(k)];
    // The header speaks for every event: one robot, one incarnation, one frame.
    if (e.robot_id != m.robot_id) return contract::got("an event's robot_id differs from the message's", e.robot_id);
    if (e.incarnation != m.incarnation) return contract::got("an event's incarnation differs from the message's", e.incarnation);
    if (e.frame != m.frame) return contract::got("an event's frame differs from the message's", e.frame);
    if (e.seq <= previous) return contract::got("event seqs not ascending, seq", e.seq);
    previous = e.seq;
  }
  return "";
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
  Refusal reason = Refusal::kMalformed;
  if (const std::string problem = validate(m, &reason); !problem.empty()) return refused(reason, problem, why);
  if (!accept_incarnation(m.robot_id, m.incarnation, m.frame)) {
    if (why) *why = "snapshot of an older incarnation of robot " + std::to_string(m.robot_id) + " (replay or second sender)";
    return false;
  }
  if (std::string p = check_seq(m.robot_id, m.seq, true, &reason); !p.empty()) return refused(reason, p, why);
  if (std::string p = check_frame(m.robot_id, m.frame, &reason); !p.empty()) return refused(reason, p, why);
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
  const auto r = static_cast<std::size_t>(m.robot_id - 1);
  if (m.chunk == m.num_chunks - 1) {  // its last chunk
    snapshot_done_frame_[r] = m.frame;
    if (held_[r].frame == m.frame) held_[r].snapshot = false;
  }
  settle_pose(m.robot_id);
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
  ++counters_.rejected_inputs;
  counters_.refused.add(reason);
  if (why) *why = problem;
  return false;
}

int MainNode::on_pose(const pose_estimate_t& m, std::string* why) {
  Refusal reason = Refusal::kMalformed;
  // A POSE from outside the team never counts towards the frame the team has finished.
  if (const std::string problem = validate(m, &reason); !problem.empty()) return refused(reason, problem, why), -1;
  const auto r = static_cast<std::size_t>(m.robot_id - 1);
  const bool first = map_.stream(m.robot_id).incarnation == 0 && robot_frame_[r] < 0;
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
  HeldPose& held = held_[r];
  if (m.frame <= std::max(held.frame, robot_frame_[r])) {
    ++counters_.stale_poses;
    return -1;
  }
  // Where the robot is, no static landmark can be (off while main.body_radius_m is 0).
  const Eigen::Vector2d position(m.x, m.y);
  const Eigen::Matrix2d position_cov = read_cov(m.cov).topLeftCorner<2, 2>();
  counters_.occupied += map_.occupy(m.robot_id, m.frame, position, position_cov, &pending_);
  // The POSE goes out before its frame's events: the frame is finished when events
  // up to its event_seq are applied. Held until then; an older held POSE is let go
  // now (its events are late or lost: the map is not held back more than a frame).
  int done = -1;
  const HeldPose older = held;
  const bool snapshot_in = m.snapshot_chunks == 0 || snapshot_done_frame_[r] == m.frame;  // (or came first)
  if (m.event_seq <= map_.stream(m.robot_id).last_seq && snapshot_in) {
    held = HeldPose{};
    done = finished_frame(m.robot_id, m.frame);
  } else {
    held = HeldPose{m.frame, m.event_seq, !snapshot_in};
    if (older.frame >= 0) done = finished_frame(m.robot_id, older.frame);
  }
  // The older POSE's events are still not in when the robot's next POSE comes: lost
  // (or late). The robot's last events of a burst would otherwise be missed until its
  // next event shows the gap, which may be never: a gap now, repaired by a snapshot
  // taken after them (a late one that still comes is applied as usual).
  if (older.frame >= 0 && map_.missed_events(m.robot_id, older.event_seq)) ++counters_.gaps;
  if (map_.stream(m.robot_id).gap_pending) request_resync(m.robot_id, resync_request_t::GAP);  // (rate-limited)
  return done;
}

void MainNode::settle_pose(int robot_id) {
  const auto r = static_cast<std::size_t>(robot_id - 1);
  HeldPose& held = held_[r];
  if (held.frame < 0 || held.snapshot || map_.stream(robot_id).last_seq < held.event_seq) return;
  const int frame = held.frame;
  held = HeldPose{};
  const int done = finished_frame(robot_id, frame);
  if (done >= 0) finished_ = std::max(finished_, done);
}

int MainNode::finished_frame(int robot_id, int frame) {
  int& f = robot_frame_[static_cast<std::size_t>(robot_id - 1)];
  f = std::max(f, frame);
  // The oldest frame of the robots seen; a robot whose POSE is held (its events not
  // in yet) has finished only the frame before that POSE's, also when that POSE is
  // the first heard of it (then nothing: -1 holds every map back).
  int all = std::numeric_limits<int>::max();
  bool any = false;
  for (std::size_t r = 0; r < robot_frame_.size(); ++r) {
    int done = robot_frame_[r];
    if (const int held = held_[r].frame; held >= 0) done = done < 0 ? held - 1 : std::min(done, held - 1);
    else if (done < 0)
      continue;
    all = any ? std::min(all, done) : done;
    any = true;
  }
  if (!any || all <= completed_frame_) return -1;
  completed_frame_ = all;
  return all;
}

int MainNode::make_global_map(std::int64_t now_utime, int frame) {
  const int n = make_map_chunks(now_utime, frame, 0);
  ++counters_.maps_published;
  counters_.map_chunks += n;
  return n;
}

int MainNode::make_moving_set(std::int64_t now_utime, int frame) {
  return make_map_chunks(now_utime, frame, 0, /*moving_only=*/true);
}

bool MainNode::moving_set_due(int num_chunks, std::int64_t now_utime) {
  moving_now_.clear();
  for (int k = 0; k < num_chunks; ++k) {
    const global_map_t& c = chunks_[static_cast<std::size_t>(k)];
    for (int i = 0; i < c.num_moving; ++i) {
      const auto j = static_cast<std::size_t>(i);
      moving_now_.insert(moving_now_.end(), {c.moving_ids[j], c.moving_frames[j], c.moving_by[j]});
    }
  }
  const std::int64_t repeat_us = static_cast<std::int64_t>(map_.options().moving_repeat_s * 1e6);
  const bool due = !any_moving_sent_ || repeat_us <= 0 || moving_now_ != moving_sent_ ||
                   now_utime - moving_sent_utime_ >= repeat_us || now_utime < moving_sent_utime_;
  if (!due) return false;
  moving_sent_.swap(moving_now_);
  moving_sent_utime_ = now_utime;
  any_moving_sent_ = true;
  ++counters_.moving_sets;
  return true;
}

int MainNode::make_team_map(int robot_id, std::int64_t now_utime, int frame) {
  if (robot_id < 1 || robot_id > kMaxTeamRobots) return 0;
  const int n = make_map_chunks(now_utime, frame, robot_id);
  ++counters_.team_maps_published;
  return n;
}

// GLOBAL_MAP (exclude_robot 0): the fused map and the moving set. TEAM_MAP_<r>
// (exclude_robot r): per STATIC landmark, the fusion of the other robots' estimates
// (those r alone holds are left out), and no moving set (GLOBAL_MAP carries it).
// GLOBAL_MOVING (moving_only): the moving set alone.
int MainNode::make_map_chunks(std::int64_t now_utime, int frame, int exclude_robot, bool moving_only) {
  static_ids_.clear();
  moving_ids_.clear();
  // A team map's estimates leave out r's and those of the robots check_team left out.
  const int excluded = exclude_robot > 0 ? (1 << (exclude_robot - 1)) | static_cast<int>(map_.left_out()) : 0;
  Eigen::Vector2d p;
  Eigen::Matrix2d C;
  for (int id = 0; id < map_.max_landmark_id(); ++id) {
    const GlobalEntry& g = map_.entry(id);
    // A team map holds only what another robot's usable estimate gives.
    if (g.status == GlobalStatus::kStatic && !moving_only &&
        (exclude_robot == 0 || map_.fused_without(id, exclude_robot, &p, &C)))
      static_ids_.push_back(id);
    else if (g.status == GlobalStatus::kMoving && exclude_robot == 0) moving_ids_.push_back(id);
  }
  cut_chunks(static_ids_.data(), static_cast<int>(static_ids_.size()), moving_ids_.data(),
             static_cast<int>(moving_ids_.size()), chunk_sizes_, map_.max_landmark_id(), &spans_);
  // Equal: the pool fits the largest map. Were it ever short, the map would go out
  // cut: a capacity fault, flagged in STATUS_MAIN, never silent.
  const int n = static_cast<int>(std::min(spans_.size(), chunks_.size()));
  if (!moving_only) {  // the moving set alone always fits: the pool holds the whole map
    capacity_fault_ = spans_.size() > chunks_.size();
    if (capacity_fault_) ++counters_.capacity_faults;
  }
  const int stamp = frame >= 0 ? frame : (completed_frame_ >= 0 ? completed_frame_ : map_.newest_frame());
  for (int k = 0; k < n; ++k) {
    const ChunkSpan& sp = spans_[static_cast<std::size_t>(k)];
    global_map_t& c = chunks_[static_cast<std::size_t>(k)];
    c.utime = now_utime;
    c.frame = stamp;
    c.incarnation = incarnation_;
    c.version = map_.version();
    c.chunk = static_cast<std::int16_t>(k);
    c.num_chunks = static_cast<std::int16_t>(n);
    c.id_begin = sp.id_begin;
    c.id_end = sp.id_end;
    grow_static(&c, sp.count_a);
    for (int i = 0; i < sp.count_a; ++i) {
      const int id = static_ids_[static_cast<std::size_t>(sp.first_a + i)];
      const GlobalEntry& g = map_.entry(id);
      p = g.fused;
      C = g.fused_cov;
      if (exclude_robot > 0) map_.fused_without(id, exclude_robot, &p, &C);  // true: it was selected so
      global_landmark_t& l = c.landmarks[static_cast<std::size_t>(i)];
      l.id = id;
      l.x = p.x();
      l.y = p.y();
      write_cov(l.cov, C);
      l.contributors = static_cast<std::int16_t>(g.contributors() & ~excluded);
      l.status = global_landmark_t::STATIC;
      l.status_frame = g.status_frame;
    }
    grow_moving(&c, sp.count_b);
    for (int i = 0; i < sp.count_b; ++i) {
      const auto j = static_cast<std::size_t>(i);
      const int id = moving_ids_[static_cast<std::size_t>(sp.first_b + i)];
      const GlobalEntry& g = map_.entry(id);
      c.moving_ids[j] = id;
      c.moving_frames[j] = std::max(g.status_frame, 0);
      c.moving_by[j] = static_cast<std::int16_t>(g.moving_unconfirmed ? 0 : g.moving_by);
    }
  }
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
  if (capacity_fault_) s.fault_flags |= node_status_t::FAULT_CAPACITY;
  if (map_.left_out() != 0) s.fault_flags |= node_status_t::FAULT_INCONSISTENT;
  const int team_frame = std::max(completed_frame_, map_.newest_frame());
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

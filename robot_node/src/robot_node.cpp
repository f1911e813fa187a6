// SPDX-License-Identifier: Apache-2.0
#include "elaslam/robot_node/robot_node.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "elaslam/common/contract.hpp"
#include "elaslam/common/cov.hpp"

namespace elaslam {
namespace {

/// The filter's mode as STATUS_ROBOT reports it (node_status_t::MODE_*).
std::int8_t status_mode(Mode m) {
  switch (m) {
    case Mode::kEkf: return node_status_t::MODE_EKF;
    case Mode::kGated: return node_status_t::MODE_GATED;
    case Mode::kEla: return node_status_t::MODE_ELA;
    case Mode::kConsensus: return node_status_t::MODE_CONSENSUS;
  }
  return node_status_t::MODE_NONE;
}

constexpr double kMaxRange = 1e4;       // [m] anything beyond is a corrupt message
constexpr double kMaxOdomVar = 1e3;     // [m^2/m], [rad^2/rad]: sanity bound on the noise model
constexpr double kBearingSlack = 1e-9;  // [rad] tolerance on [-pi, pi]
constexpr std::size_t kMaxHeldNotices = 256;  // notices held for frames not processed yet

bool finite(double v) { return std::isfinite(v); }


// A snapshot chunk's two kinds of entry (chunks.hpp, prepare_chunks).
void grow_static(lmap_snapshot_t* m, int n) { contract::set_count(&m->landmarks, &m->num_landmarks, n); }
void grow_moving(lmap_snapshot_t* m, int n) {
  contract::set_count(&m->moving_ids, &m->num_moving, n);
  m->moving_frames.resize(static_cast<std::size_t>(n));
}

}  // namespace

RobotNode::RobotNode(const RobotOptions& options, int robot_id)
    : options_(options), robot_id_(robot_id), robot_(options, robot_id), input_(options.max_observations) {
  events_.reserve(Robot::event_capacity(options));
  constexpr std::size_t kBatch = contract::kMaxBatchEvents;
  batches_.resize((Robot::event_capacity(options) + kBatch - 1) / kBatch);
  for (auto& b : batches_) b.events.reserve(kBatch);
  id_seen_.assign(static_cast<std::size_t>(options.ekf.max_landmark_id), 0);
  notice_frame_.assign(static_cast<std::size_t>(options.ekf.max_landmark_id), -1);
  held_.reserve(kMaxHeldNotices);
  if (options.team_map_fuse) {
    team_pending_.resize(static_cast<std::size_t>(options.ekf.max_landmark_id));
    team_due_.reserve(static_cast<std::size_t>(options.ekf.max_landmark_id));
  }
  alert_.reserve(kAlertBytes);
  prepare_snapshot_chunks();
  candidates_.candidates.resize(contract::kMaxCandidates);  // num_candidates says how many count
}

// Snapshot chunks, sized from the generated code, a pool for the largest map: every
// id static (held in the filter or archived, Robot::make_room).
void RobotNode::prepare_snapshot_chunks() {
  const int max_id = options_.ekf.max_landmark_id;
  static_ids_.reserve(static_cast<std::size_t>(max_id));
  moving_ids_.reserve(static_cast<std::size_t>(max_id));
  prepare_chunks(grow_static, grow_moving, contract::kMaxChunkBytes, max_id, max_id,
                 &chunk_sizes_, &chunks_);
  spans_.reserve(chunks_.size());
}

std::string RobotNode::validate(const sensor_frame_t& m, Refusal* reason) const {
  Refusal dummy = Refusal::kMalformed;
  Refusal& r = reason ? *reason : dummy;
  r = Refusal::kMalformed;
  if (m.robot_id != robot_id_) return contract::got("robot_id is not this robot's", m.robot_id);
  if (m.frame < 0) return contract::got("frame is negative", m.frame);
  if (m.num_obs < 0 || m.num_obs > options_.max_observations)
    return contract::got(contract::count_outside("num_obs (robot.filter.max_observations)", options_.max_observations),
                         m.num_obs);
  if (!contract::count_fits(m.obs, m.num_obs)) return contract::got("num_obs larger than the obs array", m.num_obs);
  if (!finite(m.odom_x) || !finite(m.odom_y) || !finite(m.odom_theta)) return "odometer reading is not finite";
  for (double v : {m.odom_var_trans_per_m, m.odom_var_rot_per_rad, m.odom_var_rot_per_m})
    if (!finite(v) || v < 0.0 || v > kMaxOdomVar) return contract::got("odometry noise variance not in [0, 1e3]", v);
  for (int k = 0; k < m.num_obs; ++k) {
    const range_bearing_t& o = m.obs[k];
    if (o.landmark_id < 0 || o.landmark_id >= options_.ekf.max_landmark_id)
      return contract::got("observation landmark_id outside [0, max_landmark_id)", o.landmark_id);
    if (!finite(o.range) || o.range <= 0.0 || o.range > kMaxRange)
      return contract::got("observation range not in (0, 1e4] m", o.range);
    if (!finite(o.bearing) || std::fabs(o.bearing) > kPi + kBearingSlack)
      return contract::got("observation bearing not in [-pi, pi]", o.bearing);
  }
  r = Refusal::kImplausible;
  if (std::string p = check_position(m.odom_x, m.odom_y, options_.limits, "odometer position"); !p.empty()) return p;
  return "";
}

// Frames further ahead than confirm_jump_frames wait for the next frame to confirm
// them (JumpGuard); odometer increments beyond what the robot can drive in the
// frames elapsed are refused, and re-anchored on once odometry_reanchor_frames
// readings in a row continue the jump (a real change of the odometer's origin).
std::string RobotNode::check_progress(const sensor_frame_t& msg, Refusal* reason) {
  input_.reanchor = false;
  if (last_frame_ < 0 || !robot_.initialised()) return "";
  const std::int64_t ahead = std::int64_t{msg.frame} - last_frame_;  // > 0 here
  if (ahead > options_.max_frame_gap) {
    *reason = Refusal::kFrameWindow;
    return contract::got("frame jumps further ahead than node.max_frame_gap " + std::to_string(options_.max_frame_gap) +
                             " of the last " + std::to_string(last_frame_),
                         msg.frame);
  }
  if (frame_guard_.check(last_frame_, msg.frame, options_.confirm_jump_frames) == JumpGuard::Verdict::kHeld) {
    *reason = Refusal::kFrameWindow;
    return contract::got("frame more than node.confirm_jump_frames " + std::to_string(options_.confirm_jump_frames) +
                             " ahead of the last " + std::to_string(last_frame_) + ", held until the next frame confirms it",
                         msg.frame);
  }
  const Pose2 reading{msg.odom_x, msg.odom_y, wrap_angle(msg.odom_theta)};
  const auto within = [&](const Pose2& from, std::int64_t frames) {
    const Pose2 d = between(from, reading);
    const double k = static_cast<double>(std::max<std::int64_t>(frames, 1));
    return std::hypot(d.x, d.y) <= options_.max_step_m * k &&
           (options_.max_turn * k >= kPi || std::fabs(d.theta) <= options_.max_turn * k);
  };
  if (within(robot_.last_odometer(), ahead)) {
    odo_candidate_frame_ = -1;
    odo_streak_ = 0;
    return "";
  }
  // A jump: does it continue the previous refused one?
  if (odo_candidate_frame_ >= 0 && msg.frame > odo_candidate_frame_ && within(odo_candidate_, msg.frame - odo_candidate_frame_)) {
    ++odo_streak_;
  } else {
    odo_streak_ = 1;
  }
  odo_candidate_ = reading;
  odo_candidate_frame_ = msg.frame;
  if (odo_streak_ >= options_.odometry_reanchor_frames) {
    input_.reanchor = true;
    odo_candidate_frame_ = -1;
    odo_streak_ = 0;
    ++counters_.odometry_reanchors;
    return "";
  }
  const Pose2 d = between(robot_.last_odometer(), reading);
  *reason = Refusal::kOdometry;
  std::ostringstream os;
  os << "odometer moved " << std::hypot(d.x, d.y) << " m and " << rad2deg(std::fabs(d.theta)) << " deg in " << ahead
     << " frame(s), beyond node.max_step_m " << options_.max_step_m << " / max_turn_deg " << rad2deg(options_.max_turn)
     << " per frame (frame " << msg.frame << "; re-anchored after " << options_.odometry_reanchor_frames
     << " consistent readings)";
  return os.str();
}

RobotNode::Verdict RobotNode::on_sensor(const sensor_frame_t& msg, std::int64_t now_utime, std::string* why) {
  snapshot_ready_ = false;
  candidates_ready_ = false;
  events_.clear();
  num_batches_ = 0;
  if (const Verdict v = admit(msg, why); v != Verdict::kProcessed) return v;
  run_frame(msg, now_utime);
  // Held inputs take effect after this frame's outputs (as in the in-process run).
  release_held_notices();
  apply_team_estimates();
  return Verdict::kProcessed;
}

RobotNode::Verdict RobotNode::admit(const sensor_frame_t& msg, std::string* why) {
  Refusal reason = Refusal::kMalformed;
  std::string problem = validate(msg, &reason);
  if (problem.empty()) problem = check_duplicate_ids(msg, &reason);
  if (!problem.empty()) return refused(reason, problem, why), Verdict::kInvalid;
  // One frame processed so far, and this one does not continue it (older, or further
  // ahead than confirm_jump_frames): that first frame was not the stream's (a forged
  // far-ahead frame number, a stray datagram of an old run). Start over from this one
  // instead of refusing the real frames that follow.
  if (counters_.frames == 1 && frames_this_run_ == 1 &&
      (msg.frame < last_frame_ || std::int64_t{msg.frame} - last_frame_ > options_.confirm_jump_frames))
    start_over();
  if (msg.frame == last_frame_) {
    ++counters_.frames_duplicate;
    if (why) *why = "duplicate frame " + std::to_string(msg.frame);
    return Verdict::kDuplicate;
  }
  if (msg.frame < last_frame_) {
    ++counters_.frames_out_of_order;
    ++behind_;  // with none processed since: a source that started over (frames_behind)
    if (why) *why = "frame " + std::to_string(msg.frame) + " older than " + std::to_string(last_frame_);
    return Verdict::kOutOfOrder;
  }
  problem = check_progress(msg, &reason);
  if (!problem.empty()) return refused(reason, problem, why), Verdict::kInvalid;
  if (last_frame_ >= 0 && msg.frame > last_frame_ + 1) {
    counters_.frames_gap += msg.frame - last_frame_ - 1;
    note_frames_lost(last_frame_ + 1, msg.frame - 1);
  }
  return Verdict::kProcessed;
}

// A valid frame's sightings (ids checked against max_landmark_id by validate).
std::string RobotNode::check_duplicate_ids(const sensor_frame_t& msg, Refusal* reason) {
  std::string problem;
  for (int k = 0; problem.empty() && k < msg.num_obs; ++k) {
    auto& seen = id_seen_[static_cast<std::size_t>(msg.obs[k].landmark_id)];
    if (seen) problem = contract::got("landmark observed twice in one frame", msg.obs[k].landmark_id), *reason = Refusal::kDuplicateId;
    seen = 1;
  }
  // Clear the marks for the next frame.
  const int marked = contract::bounded(msg.num_obs, static_cast<int>(std::min<std::size_t>(msg.obs.size(), static_cast<std::size_t>(options_.max_observations))));
  for (int k = 0; k < marked; ++k) {
    const int id = msg.obs[static_cast<std::size_t>(k)].landmark_id;
    if (id >= 0 && id < options_.ekf.max_landmark_id) id_seen_[static_cast<std::size_t>(id)] = 0;
  }
  return problem;
}

void RobotNode::run_frame(const sensor_frame_t& msg, std::int64_t now_utime) {
  const auto t0 = std::chrono::steady_clock::now();
  input_.frame = msg.frame;
  input_.utime = msg.utime;
  input_.odometer = {msg.odom_x, msg.odom_y, wrap_angle(msg.odom_theta)};
  input_.noise = {msg.odom_var_trans_per_m, msg.odom_var_rot_per_rad, msg.odom_var_rot_per_m};
  input_.num_obs = msg.num_obs;
  for (int k = 0; k < msg.num_obs; ++k)
    input_.obs[static_cast<std::size_t>(k)] = {msg.obs[k].landmark_id, {msg.obs[k].range, msg.obs[k].bearing}};
  const FrameSummary s = robot_.process(input_);
  last_frame_ = msg.frame;
  if (first_frame_utime_ == 0) first_frame_utime_ = now_utime;
  behind_ = 0;
  ++counters_.frames;
  ++frames_this_run_;
  counters_.filter_faults += s.filter_faults;
  if (s.filter_full > 0) note_filter_full(s.filter_full);
  counters_.evictions += s.evicted;
  counters_.restored += s.restored;
  counters_.own_drifted_frames += s.drifted;
  if (s.inconsistent) note_inconsistent(s.recovered);
  fill_events(now_utime);
  if (msg.frame % options_.snapshot_period_frames == 0 || snapshot_due_) {
    make_snapshot(now_utime);
    snapshot_ready_ = true;
    snapshot_due_ = false;
  }
  fill_candidates(now_utime);
  const auto us = std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - t0).count();
  processing_.add(us);
  fill_pose(msg, now_utime, s, us);
}

void RobotNode::release_held_notices() {
  std::size_t kept = 0;
  for (std::size_t i = 0; i < held_.size(); ++i) {
    if (held_[i].frame <= last_frame_) {
      apply_notice(held_[i]);
    } else {
      held_[kept++] = held_[i];
    }
  }
  held_.resize(kept);
}

void RobotNode::fill_pose(const sensor_frame_t& msg, std::int64_t now_utime, const FrameSummary& s,
                          std::int64_t us) {
  const EkfSlam& f = robot_.estimate();  // with the team map: the aided filter
  const Pose2 p = f.pose();
  const Eigen::Matrix3d C = f.pose_cov();
  pose_.utime = now_utime;
  pose_.frame = msg.frame;
  pose_.robot_id = static_cast<int16_t>(robot_id_);
  pose_.incarnation = incarnation_;
  pose_.source_utime = msg.utime;
  pose_.x = p.x;
  pose_.y = p.y;
  pose_.theta = p.theta;
  write_cov(pose_.cov, C);
  pose_.processing_us = static_cast<int32_t>(std::min<std::int64_t>(us, INT32_MAX));
  pose_.mean_diag_p = robot_.map_mean_diag();
  pose_.num_obs = static_cast<int16_t>(s.num_obs);
  pose_.num_accepted = static_cast<int16_t>(s.num_accepted);
  pose_.num_rejected = static_cast<int16_t>(s.num_rejected);
  pose_.num_landmarks = static_cast<int16_t>(f.num_landmarks());
  pose_.nis = s.nis;
  pose_.nis_dof = static_cast<int16_t>(s.nis_dof);
  pose_.frames_processed = frames_this_run_;
  pose_.event_seq = seq_;  // after fill_events: this frame's events included
  pose_.snapshot_chunks = static_cast<int16_t>(snapshot_ready_ ? num_chunks_ : 0);
}

void RobotNode::fill_events(std::int64_t now_utime) {
  for (const MapEvent& e : robot_.events()) {
    landmark_event_t m{};
    m.utime = now_utime;
    m.frame = e.frame;
    m.robot_id = static_cast<int16_t>(robot_id_);
    m.incarnation = incarnation_;
    m.seq = ++seq_;
    m.kind = static_cast<int8_t>(e.kind);
    m.landmark_id = e.landmark_id;
    m.x = e.position.x();
    m.y = e.position.y();
    write_cov(m.cov, e.cov);
    events_.push_back(m);
  }
  counters_.events_sent += static_cast<std::int64_t>(events_.size());
  // The same events in LMAP_EVENTS messages, kMaxBatchEvents at most each.
  const std::size_t n = events_.size(), k = contract::kMaxBatchEvents;
  num_batches_ = static_cast<int>((n + k - 1) / k);
  for (std::size_t b = 0; b < static_cast<std::size_t>(num_batches_); ++b) {
    lmap_events_t& m = batches_[b];
    m.utime = now_utime;
    m.frame = last_frame_;
    m.robot_id = static_cast<int16_t>(robot_id_);
    m.incarnation = incarnation_;
    const std::size_t first = b * k, count = std::min(k, n - first);
    contract::set_count(&m.events, &m.num_events, static_cast<int>(count));
    std::copy_n(events_.begin() + static_cast<std::ptrdiff_t>(first), count, m.events.begin());
  }
}

void RobotNode::stamp_events(std::int64_t utime) {
  for (auto& e : events_) e.utime = utime;
  for (int b = 0; b < num_batches_; ++b) {
    lmap_events_t& m = batches_[static_cast<std::size_t>(b)];
    m.utime = utime;
    for (auto& e : m.events) e.utime = utime;
  }
}

// CANDIDATES_<r>: the candidates in the filter (they are there from their first
// sighting), every candidates_period_frames while there are some and once more when
// the last one has gone, so that a viewer clears them.
void RobotNode::fill_candidates(std::int64_t now_utime) {
  const int period = options_.candidates_period_frames;
  if (period <= 0 || last_frame_ % period != 0) return;
  const EkfSlam& f = robot_.filter();
  const LMap& lm = robot_.lmap();
  int n = 0, omitted = 0;
  for (int slot = 0; slot < f.num_landmarks(); ++slot) {
    const int id = f.id_at(slot);
    if (lm[id].status != LandmarkStatus::kCandidate) continue;
    if (n == contract::kMaxCandidates) {
      ++omitted;
      continue;
    }
    landmark_estimate_t& l = candidates_.candidates[static_cast<std::size_t>(n++)];
    l.id = id;
    const Eigen::Vector2d p = f.landmark(id);
    l.x = p.x();
    l.y = p.y();
    write_cov(l.cov, f.landmark_cov(id));
  }
  if (n + omitted == 0 && candidates_.num_candidates + candidates_.num_omitted == 0) return;
  candidates_.utime = now_utime;
  candidates_.frame = last_frame_;
  candidates_.robot_id = static_cast<std::int16_t>(robot_id_);
  candidates_.incarnation = incarnation_;
  candidates_.num_candidates = static_cast<std::int16_t>(n);
  candidates_.num_omitted = static_cast<std::int16_t>(omitted);
  candidates_ready_ = true;
}

int RobotNode::make_snapshot(std::int64_t now_utime) {
  const EkfSlam& f = robot_.filter();
  const LMap& lm = robot_.lmap();
  static_ids_.clear();
  moving_ids_.clear();
  for (int id = 0; id < lm.size(); ++id) {
    const LMapEntry& e = lm[id];
    if (e.status == LandmarkStatus::kStatic && (f.has_landmark(id) || e.archived))
      static_ids_.push_back(id);  // candidates are not the map; archived landmarks are
    else if (e.status == LandmarkStatus::kMoving || (e.status == LandmarkStatus::kCandidate && e.was_moving))
      moving_ids_.push_back(id);
  }
  cut_chunks(static_ids_.data(), static_cast<int>(static_ids_.size()), moving_ids_.data(),
             static_cast<int>(moving_ids_.size()), chunk_sizes_, lm.size(), &spans_);
  num_chunks_ = static_cast<int>(std::min(spans_.size(), chunks_.size()));  // equal: the pool fits the largest map
  for (int k = 0; k < num_chunks_; ++k) {
    const ChunkSpan& sp = spans_[static_cast<std::size_t>(k)];
    lmap_snapshot_t& c = chunks_[static_cast<std::size_t>(k)];
    c.utime = now_utime;
    c.frame = last_frame_;
    c.robot_id = static_cast<int16_t>(robot_id_);
    c.incarnation = incarnation_;
    c.seq = seq_;
    c.chunk = static_cast<int16_t>(k);
    c.num_chunks = static_cast<int16_t>(num_chunks_);
    c.id_begin = sp.id_begin;
    c.id_end = sp.id_end;
    grow_static(&c, sp.count_a);
    for (int i = 0; i < sp.count_a; ++i) {
      const int id = static_ids_[static_cast<std::size_t>(sp.first_a + i)];
      landmark_estimate_t& l = c.landmarks[static_cast<std::size_t>(i)];
      l.id = id;
      const LMapEntry& e = lm[id];
      const Eigen::Vector2d p = e.archived ? e.position : f.landmark(id);
      l.x = p.x();
      l.y = p.y();
      write_cov(l.cov, e.archived ? e.cov : f.landmark_cov(id));
    }
    grow_moving(&c, sp.count_b);
    for (int i = 0; i < sp.count_b; ++i) {
      const int id = moving_ids_[static_cast<std::size_t>(sp.first_b + i)];
      c.moving_ids[static_cast<std::size_t>(i)] = id;
      c.moving_frames[static_cast<std::size_t>(i)] = lm[id].moving_frame;
    }
  }
  return num_chunks_;
}

void RobotNode::note_inconsistent(bool recovered) {
  ++counters_.inconsistent_frames;
  if (recovered) ++counters_.recoveries;
  inconsistent_frame_ = last_frame_;
  if (last_frame_ - inconsistent_alerted_ < kAlertFrames || !alert_.empty()) return;  // rate-limited
  inconsistent_alerted_ = last_frame_;
  // Into the buffer reserved at construction: the frame path allocates nothing.
  char line[kAlertBytes];
  std::snprintf(line, sizeof line,
                "FAULT: robot %d filter inconsistent at frame %d (its innovations exceed their covariance: lost?)%s; "
                "%lld such frame(s) so far",
                robot_id_, last_frame_, recovered ? "; pose covariance widened to relocalise" : "",
                static_cast<long long>(counters_.inconsistent_frames));
  alert_.assign(line);
}

void RobotNode::note_filter_full(int n) {
  counters_.filter_full += n;
  full_frame_ = last_frame_;
  if (last_frame_ - alerted_frame_ < kAlertFrames) return;  // rate-limited
  alerted_frame_ = last_frame_;
  char line[kAlertBytes];
  std::snprintf(line, sizeof line,
                "FAULT: robot %d filter full (filter.capacity %d landmarks) at frame %d: %lld landmark(s) left out so "
                "far; raise filter.capacity",
                robot_id_, options_.ekf.capacity, last_frame_, static_cast<long long>(counters_.filter_full));
  alert_.assign(line);
}

void RobotNode::note_frames_lost(int from, int to) {
  lost_frame_ = to + 1;
  if (to + 1 - lost_alerted_ < kAlertFrames || !alert_.empty()) return;  // rate-limited
  lost_alerted_ = to + 1;
  char line[kAlertBytes];
  std::snprintf(line, sizeof line,
                "FAULT: robot %d never received frames %d..%d (%lld lost so far): a flood of datagrams, a lossy link "
                "or an overloaded computer",
                robot_id_, from, to, static_cast<long long>(counters_.frames_gap));
  alert_.assign(line);
}

void RobotNode::start_over() {
  const std::int64_t next = incarnation_ + 1;
  const int dropped = last_frame_;
  RobotNode fresh(options_, robot_id_);
  fresh.set_incarnation(next);
  fresh.counters_.frames_out_of_order = counters_.frames_out_of_order + 1;  // the frame taken back
  *this = std::move(fresh);
  char line[kAlertBytes];
  std::snprintf(line, sizeof line,
                "robot %d: its first frame %d was not the stream's (the next one does not continue it): started over, "
                "incarnation %lld",
                robot_id_, dropped, static_cast<long long>(next));
  alert_.assign(line);
}

void RobotNode::main_heard(std::int64_t now_utime) {
  if (main_silent_) {
    main_silent_ = false;
    healed_frame_ = std::max(last_frame_, 0);
    char line[kAlertBytes];
    std::snprintf(line, sizeof line, "robot %d: main_robot heard again after %.1f s of silence (frame %d): the partition healed",
                  robot_id_, static_cast<double>(now_utime - std::max(main_heard_utime_, first_frame_utime_)) * 1e-6,
                  last_frame_);
    alert_.assign(line);
  }
  main_heard_utime_ = now_utime;
}

void RobotNode::check_main(std::int64_t now_utime) {
  if (options_.main_silent_s <= 0.0 || first_frame_utime_ == 0 || main_silent_) return;
  const std::int64_t since = std::max(main_heard_utime_, first_frame_utime_);
  if (static_cast<double>(now_utime - since) * 1e-6 <= options_.main_silent_s) return;
  main_silent_ = true;
  char line[kAlertBytes];
  std::snprintf(line, sizeof line,
                "FAULT: robot %d has not heard main_robot for %.1f s (node.main_silent_s %.1f) at frame %d: main is down "
                "or cut off; the robot goes on alone",
                robot_id_, static_cast<double>(now_utime - since) * 1e-6, options_.main_silent_s, last_frame_);
  alert_.assign(line);
}

void RobotNode::note_save(bool ok, const std::string& why) {
  if (!ok && !save_failed_) {
    char line[kAlertBytes];
    std::snprintf(line, sizeof line, "FAULT: robot %d cannot save its state: %.160s", robot_id_, why.c_str());
    alert_.assign(line);
  }
  save_failed_ = !ok;
}

std::string RobotNode::take_alert() {
  std::string a = alert_;  // a copy: alert_ keeps its reserved buffer
  alert_.clear();
  return a;
}

bool RobotNode::on_notice(const dynamic_notice_t& msg, std::string* why) {
  std::string problem;
  Refusal reason = Refusal::kMalformed;
  if (msg.landmark_id < 0 || msg.landmark_id >= options_.ekf.max_landmark_id)
    problem = contract::got("landmark_id outside [0, max_landmark_id)", msg.landmark_id);
  else if (msg.detected_by < 1 || msg.detected_by > contract::kMaxRobots)
    problem = contract::got(contract::outside("detected_by", 1, contract::kMaxRobots), msg.detected_by);
  else if (msg.frame < 0)
    problem = contract::got("frame is negative", msg.frame);
  else if (msg.seq < 0 || msg.seq > kMaxSeq)
    problem = contract::got("seq not in [0, 2^62]", msg.seq);
  else if (!options_.limits.in_team(msg.detected_by))
    problem = contract::got("detected_by not in limits.team " + team_text(options_.limits.team_mask), msg.detected_by),
    reason = Refusal::kOutsideTeam;
  if (!problem.empty()) return refused(reason, problem, why);
  // This robot's own finding, echoed by main: nothing to do (on_global_map skips it too).
  if (msg.detected_by == robot_id_) {
    ++counters_.notices_ignored;
    return true;
  }
  // A duplicated or late datagram: a notice of this frame or a later one was had
  // already, or this robot's own view of the landmark changed after the notice's
  // frame (it saw it again and took it back). Applying it would undo newer state;
  // the rule is the one of the GLOBAL_MAP repair below.
  if (!notice_is_news(msg.landmark_id, msg.frame)) {
    ++counters_.notices_stale;
    return true;
  }
  notice_frame_[static_cast<std::size_t>(msg.landmark_id)] = msg.frame;
  // Ahead of this robot's frames: hold it (a fresh node, one far behind or a full
  // buffer applies it at once; a notice is never lost).
  if (last_frame_ >= 0 && msg.frame > last_frame_ && std::int64_t{msg.frame} <= std::int64_t{last_frame_} + options_.max_frame_gap &&
      held_.size() < held_.capacity()) {
    held_.push_back(msg);
    ++counters_.notices_deferred;
    return true;
  }
  apply_notice(msg);
  return true;
}

void RobotNode::apply_notice(const dynamic_notice_t& msg) {
  const bool removed = robot_.apply_notice(msg.landmark_id, msg.frame);  // another robot's (on_notice)
  ++(removed ? counters_.notices_applied : counters_.notices_ignored);
}

std::string RobotNode::validate(const global_map_t& m, Refusal* reason) const {
  return check_global_map(m, options_.limits, options_.ekf.max_landmark_id, reason);
}

bool RobotNode::refused(Refusal reason, const std::string& problem, std::string* why) {
  ++counters_.rejected_inputs;
  counters_.refused.add(reason);
  if (why) *why = problem;
  return false;
}

// Not had already (a notice of this frame or a later one for the landmark), and not
// older than this robot's own view of it (it saw it again and took it back after).
bool RobotNode::notice_is_news(int id, int frame) const {
  return notice_frame_[static_cast<std::size_t>(id)] < frame && robot_.lmap()[id].status_frame <= frame;
}

bool RobotNode::on_global_map(const global_map_t& msg, std::string* why) {
  Refusal reason = Refusal::kMalformed;
  if (const std::string problem = validate(msg, &reason); !problem.empty()) return refused(reason, problem, why);
  for (int k = 0; k < msg.num_moving; ++k) {
    const auto i = static_cast<std::size_t>(k);
    const int id = msg.moving_ids[i], by = msg.moving_by[i], frame = msg.moving_frames[i];
    // Unconfirmed (no notice went out), this robot's own finding, a notice had, or
    // this robot's own view of it changed since (it saw it again): nothing to repair.
    if (by == 0 || by == robot_id_ || !notice_is_news(id, frame)) continue;
    dynamic_notice_t n{};
    n.frame = frame;
    n.landmark_id = id;
    n.detected_by = static_cast<int16_t>(by);
    ++counters_.notices_repaired;
    on_notice(n, nullptr);
  }
  return true;
}

bool RobotNode::on_team_map(const global_map_t& msg, std::string* why) {
  if (!options_.team_map_fuse) return refused(Refusal::kMalformed, "a team map, but robot.team_map.fuse is off", why);
  Refusal reason = Refusal::kMalformed;
  if (const std::string problem = validate(msg, &reason); !problem.empty()) return refused(reason, problem, why);
  if (msg.frame > std::max(last_frame_, 0) + options_.max_frame_gap)
    return refused(Refusal::kFrameWindow,
                   "frame " + std::to_string(msg.frame) + " more than node.max_frame_gap ahead of this robot's " +
                       std::to_string(last_frame_),
                   why);
  const int own_bit = 1 << (robot_id_ - 1);
  for (int k = 0; k < msg.num_landmarks; ++k) {
    const global_landmark_t& l = msg.landmarks[static_cast<std::size_t>(k)];
    if (l.id >= options_.ekf.max_landmark_id)
      return refused(Refusal::kMalformed, contract::got("landmark id outside [0, filter.max_landmark_id)", l.id), why);
    if (l.contributors & own_bit)
      return refused(Refusal::kMalformed,
                     "landmark " + std::to_string(l.id) + " lists this robot as a contributor: not a map without it",
                     why);
  }
  // Older: a version below the last applied of main's incarnation, or a chunk of an
  // earlier incarnation (a datagram delayed past main's restart; incarnations grow).
  if (msg.incarnation < team_map_incarnation_ ||
      (msg.incarnation == team_map_incarnation_ && msg.version < team_map_version_)) {
    ++counters_.team_map_stale;
    return true;
  }
  team_map_incarnation_ = msg.incarnation;
  team_map_version_ = msg.version;
  // Held until this robot has processed frame msg.frame + 1 (then applied after that
  // frame's outputs), so the live team does what the in-process run does: main
  // sends the team map of frame k once every robot finished k, which in a lockstep
  // team may reach a robot before or after its SENSOR of frame k + 1.
  for (int k = 0; k < msg.num_landmarks; ++k) {
    const global_landmark_t& l = msg.landmarks[static_cast<std::size_t>(k)];
    TeamPending& p = team_pending_[static_cast<std::size_t>(l.id)];
    if (!p.valid) ++team_pending_count_;
    p = {true, msg.frame, Eigen::Vector2d(l.x, l.y), read_cov(l.cov)};
  }
  ++counters_.team_map_chunks;
  apply_team_estimates();
  return true;
}

void RobotNode::apply_team_estimates() {
  if (team_pending_count_ == 0) return;
  team_due_.clear();  // reserved at construction: one per landmark id
  for (std::size_t id = 0; id < team_pending_.size(); ++id) {
    TeamPending& p = team_pending_[id];
    if (!p.valid || p.frame >= last_frame_) continue;
    team_due_.push_back({static_cast<int>(id), p.position, p.cov});
    p.valid = false;
    --team_pending_count_;
  }
  if (team_due_.empty()) return;
  switch (robot_.apply_team_map(team_due_.data(), static_cast<int>(team_due_.size()))) {
    case TeamVerdict::kLost:  // flagged like the consistency monitor's verdict
      note_inconsistent(/*recovered=*/true);
      break;
    case TeamVerdict::kRelocalised:
      note_relocalised();
      break;
    case TeamVerdict::kNone:
    case TeamVerdict::kHeld:
      break;
  }
}

// Not rate-limited (a relocalisation is rare and each one moves the robot's map):
// an alert that waits for the last one to be said is replaced.
void RobotNode::note_relocalised() {
  const Relocalisation& r = robot_.last_relocalisation();
  relocalised_frame_ = last_frame_;
  snapshot_due_ = true;  // main's copy of this robot's map moves with it
  char line[kAlertBytes];
  std::snprintf(line, sizeof line,
                "FAULT: robot %d relocalised at frame %d: its map was right in itself, wrong as a whole (%d of %d "
                "landmarks shared with the team map disagreed, %d agree after the motion); moved by rotation %.2f deg "
                "(sigma %.2f), translation (%.3f, %.3f) m (sigma %.3f); %lld so far",
                robot_id_, r.frame, r.disagreed, r.shared, r.agreed_after, rad2deg(r.rotation), rad2deg(r.rotation_sigma),
                r.translation.x(), r.translation.y(), r.translation_sigma,
                static_cast<long long>(robot_.team_counters().relocalised));
  alert_.assign(line);
}

bool RobotNode::on_resync(const resync_request_t& msg, std::int64_t now_utime) {
  if (msg.robot_id != robot_id_ || last_frame_ < 0 || last_resync_frame_ == last_frame_) return false;
  last_resync_frame_ = last_frame_;
  make_snapshot(now_utime);
  ++counters_.resyncs_answered;
  return true;
}

bool RobotNode::on_own_channel(std::int64_t incarnation, int frame) {
  if (incarnation == incarnation_) return false;  // this process's own message, looped back
  ++counters_.foreign_poses;
  if (incarnation < incarnation_) {  // a predecessor's late datagram, or a live older process
    if (incarnation != older_sender_) older_sender_ = incarnation, older_sender_frame_ = frame, older_sender_frames_ = 0;
    if (frame <= older_sender_frame_ && older_sender_frames_ > 0) return false;
    older_sender_frame_ = std::max(older_sender_frame_, frame);
    if (++older_sender_frames_ < 3) return false;
  }
  const bool fresh = duplicate_until_frame_ < 0 || last_frame_ > duplicate_until_frame_;
  duplicate_until_frame_ = std::max(last_frame_, 0) + 50;
  return fresh || counters_.foreign_poses % 100 == 1;
}

node_status_t RobotNode::status_msg(std::int64_t now_utime) const {
  node_status_t s{};
  s.utime = now_utime;
  s.frame = last_frame_;
  s.node_kind = node_status_t::ROBOT;
  s.node_id = static_cast<int16_t>(robot_id_);
  s.mode = status_mode(options_.mode);
  s.incarnation = incarnation_;
  s.fault_flags = duplicate_until_frame_ >= 0 && last_frame_ <= duplicate_until_frame_ ? node_status_t::FAULT_DUPLICATE_SENDER : 0;
  if (full_frame_ >= 0 && last_frame_ - full_frame_ < kAlertFrames) s.fault_flags |= node_status_t::FAULT_CAPACITY;
  if (inconsistent_frame_ >= 0 && last_frame_ - inconsistent_frame_ < kAlertFrames)
    s.fault_flags |= node_status_t::FAULT_INCONSISTENT;
  if (lost_frame_ >= 0 && last_frame_ - lost_frame_ < kAlertFrames) s.fault_flags |= node_status_t::FAULT_FRAMES_LOST;
  if (save_failed_) s.fault_flags |= node_status_t::FAULT_SAVE_FAILED;
  if (main_silent_) s.fault_flags |= node_status_t::FAULT_MAIN_SILENT;
  if (healed_frame_ >= 0 && last_frame_ - healed_frame_ < kAlertFrames)
    s.fault_flags |= node_status_t::FAULT_PARTITION_HEALED;
  if (relocalised_frame_ >= 0 && last_frame_ - relocalised_frame_ < kAlertFrames)
    s.fault_flags |= node_status_t::FAULT_RELOCALISED;
  const Relocalisation& r = robot_.last_relocalisation();
  s.relocalisations = static_cast<int32_t>(std::min<std::int64_t>(robot_.team_counters().relocalised, INT32_MAX));
  s.relocalised_frame = r.frame;
  s.relocalised_rotation = static_cast<float>(r.rotation);
  s.relocalised_x = static_cast<float>(r.translation.x());
  s.relocalised_y = static_cast<float>(r.translation.y());
  for (int k = 0; k < kNumRefusals; ++k) s.refused[k] = counters_.refused.n[static_cast<std::size_t>(k)];
  s.frames = frames_this_run_;
  s.frames_dropped = counters_.frames_gap + counters_.frames_duplicate + counters_.frames_out_of_order;
  s.rejected_inputs = counters_.rejected_inputs;
  s.decode_errors = counters_.decode_errors;
  s.queue_drops = counters_.queue_drops;
  s.filter_faults = counters_.filter_faults;
  s.events_sent = counters_.events_sent;
  s.processing_us_p50 = static_cast<int32_t>(processing_.quantile(0.5));
  s.processing_us_p99 = static_cast<int32_t>(processing_.quantile(0.99));
  s.processing_us_max = static_cast<int32_t>(std::min<std::int64_t>(processing_.max(), INT32_MAX));
  // The odometer's calibration as the own filter estimates it (the configured
  // constants, sigma 0, while frozen; before the first frame, the prior's means).
  const EkfSlam& f = robot_.filter();
  const OdometryCalibration c = f.calibration();
  const Eigen::Matrix3d C = f.calibration_cov();
  const auto sigma = [&C](int k) { return static_cast<float>(std::sqrt(std::max(C(k, k), 0.0))); };
  s.odom_turn_scale = static_cast<float>(c.turn_scale);
  s.odom_turn_scale_sigma = sigma(0);
  s.odom_speed_scale = static_cast<float>(c.speed_scale);
  s.odom_speed_scale_sigma = sigma(1);
  s.odom_turn_bias_rad_s = static_cast<float>(c.turn_bias);
  s.odom_turn_bias_sigma_rad_s = sigma(2);
  return s;
}

}  // namespace elaslam

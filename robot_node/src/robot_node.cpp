// SPDX-License-Identifier: Apache-2.0
#include "elaslam/robot_node/robot_node.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>

#include "elaslam/common/contract.hpp"

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

}  // namespace

RobotNode::RobotNode(const RobotOptions& options, int robot_id)
    : options_(options),
      robot_id_(robot_id),
      robot_(options, robot_id),
      admission_(options, robot_id),
      messages_(options, robot_id),
      deferred_(options),
      input_(options.max_observations) {
  alert_.reserve(kAlertBytes);
}

RobotNode::Verdict RobotNode::on_sensor(const sensor_frame_t& msg, std::int64_t now_utime, std::string* why) {
  messages_.begin_frame();
  if (const Verdict v = admit(msg, why); v != Verdict::kProcessed) return v;
  run_frame(msg, now_utime);
  // Held inputs take effect after this frame's outputs (as in the in-process run).
  deferred_.release_moving(last_frame(), [this](const MovingReport& m) { apply_moving(m); });
  apply_team_estimates();
  return Verdict::kProcessed;
}

RobotNode::Verdict RobotNode::admit(const sensor_frame_t& msg, std::string* why) {
  Refusal reason = Refusal::kMalformed;
  std::string problem = admission_.validate(msg, &reason);
  if (problem.empty()) problem = admission_.check_duplicate_ids(msg, &reason);
  if (!problem.empty()) return refused(reason, problem, why), Verdict::kInvalid;
  // One frame processed so far, and this one does not continue it: that first frame
  // was not the stream's (a forged far-ahead frame number, a stray datagram of an old
  // run). Start over from this one instead of refusing the real frames that follow.
  if (counters_.frames == 1 && frames_this_run_ == 1 && admission_.breaks_from_last(msg)) start_over();
  const int last = last_frame();
  switch (admission_.order(msg)) {
    case FrameAdmission::Order::kDuplicate:
      ++counters_.frames_duplicate;
      if (why) *why = "duplicate frame " + std::to_string(msg.frame);
      return Verdict::kDuplicate;
    case FrameAdmission::Order::kOlder:
      ++counters_.frames_out_of_order;
      if (why) *why = "frame " + std::to_string(msg.frame) + " older than " + std::to_string(last);
      return Verdict::kOutOfOrder;
    case FrameAdmission::Order::kNewer:
      break;
  }
  problem = admission_.check_progress(msg, robot_, &input_.reanchor, &reason);
  if (!problem.empty()) return refused(reason, problem, why), Verdict::kInvalid;
  if (input_.reanchor) ++counters_.odometry_reanchors;
  if (last >= 0 && msg.frame > last + 1) {
    counters_.frames_gap += msg.frame - last - 1;
    note_frames_lost(last + 1, msg.frame - 1);
  }
  return Verdict::kProcessed;
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
  admission_.processed(msg.frame);
  if (first_frame_utime_ == 0) first_frame_utime_ = now_utime;
  ++counters_.frames;
  ++frames_this_run_;
  counters_.filter_faults += s.filter_faults;
  if (s.filter_full > 0) note_filter_full(s.filter_full);
  counters_.evictions += s.evicted;
  counters_.restored += s.restored;
  counters_.mover_corrections += s.mover_corrections;
  counters_.movers_followed += s.movers_followed;
  counters_.own_drifted_frames += s.drifted;
  if (s.inconsistent) note_inconsistent(s.recovered);
  messages_.fill_events(robot_, msg.frame, now_utime);
  counters_.events_sent += static_cast<std::int64_t>(messages_.events().size());
  if (msg.frame % options_.snapshot_period_frames == 0 || snapshot_due_) {
    messages_.make_snapshot(robot_, msg.frame, now_utime);
    messages_.send_snapshot();
    snapshot_due_ = false;
  }
  messages_.fill_candidates(robot_, msg.frame, now_utime);
  messages_.fill_tracks(robot_, msg.frame, now_utime);
  if (messages_.num_track_chunks() > 0) counters_.tracks_omitted += messages_.track_chunk(0).num_omitted;
  const auto us = std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - t0).count();
  processing_.add(us);
  messages_.fill_pose(robot_, msg, now_utime, s, us, frames_this_run_);
}

void RobotNode::note_inconsistent(bool recovered) {
  ++counters_.inconsistent_frames;
  if (recovered) ++counters_.recoveries;
  inconsistent_frame_ = last_frame();
  if (last_frame() - inconsistent_alerted_ < kAlertFrames || !alert_.empty()) return;  // rate-limited
  inconsistent_alerted_ = last_frame();
  // Into the buffer reserved at construction: the frame path allocates nothing.
  char line[kAlertBytes];
  std::snprintf(line, sizeof line,
                "FAULT: robot %d filter inconsistent at frame %d (its innovations exceed their covariance: lost?)%s; "
                "%lld such frame(s) so far",
                robot_id_, last_frame(), recovered ? "; pose covariance widened to relocalise" : "",
                static_cast<long long>(counters_.inconsistent_frames));
  alert_.assign(line);
}

void RobotNode::note_filter_full(int n) {
  counters_.filter_full += n;
  full_frame_ = last_frame();
  if (last_frame() - alerted_frame_ < kAlertFrames) return;  // rate-limited
  alerted_frame_ = last_frame();
  char line[kAlertBytes];
  std::snprintf(line, sizeof line,
                "FAULT: robot %d filter full (filter.capacity %d landmarks) at frame %d: %lld landmark(s) left out so "
                "far; raise filter.capacity",
                robot_id_, options_.ekf.capacity, last_frame(), static_cast<long long>(counters_.filter_full));
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
  const std::int64_t next = incarnation() + 1;
  const int dropped = last_frame();
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
    healed_frame_ = std::max(last_frame(), 0);
    char line[kAlertBytes];
    std::snprintf(line, sizeof line, "robot %d: main_robot heard again after %.1f s of silence (frame %d): the partition healed",
                  robot_id_, static_cast<double>(now_utime - std::max(main_heard_utime_, first_frame_utime_)) * 1e-6,
                  last_frame());
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
                robot_id_, static_cast<double>(now_utime - since) * 1e-6, options_.main_silent_s, last_frame());
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
  if (msg.detected_by == robot_id_) {  // this robot's own finding: it knows
    ++counters_.notices_ignored;
    return true;
  }
  take_moving({msg.landmark_id, msg.frame, msg.detected_by});
  return true;
}

void RobotNode::take_moving(const MovingReport& m) {
  switch (deferred_.take_moving(m, robot_.lmap(), last_frame())) {
    case DeferredInputs::Take::kStale:
      ++counters_.notices_stale;
      break;
    case DeferredInputs::Take::kHeld:
      ++counters_.notices_deferred;
      break;
    case DeferredInputs::Take::kNow:
      apply_moving(m);
      break;
  }
}

void RobotNode::apply_moving(const MovingReport& m) {
  const bool removed = robot_.apply_notice(m.landmark_id, m.frame);  // another robot's finding
  ++(removed ? counters_.notices_applied : counters_.notices_ignored);
}

bool RobotNode::refused(Refusal reason, const std::string& problem, std::string* why) {
  return counters_.refused.count(reason, problem, &counters_.rejected_inputs, why);
}

bool RobotNode::on_global_map(const global_map_t& msg, std::string* why) {
  Refusal reason = Refusal::kMalformed;
  const std::string problem = check_global_map(msg, options_.limits, options_.ekf.max_landmark_id, &reason);
  if (!problem.empty()) return refused(reason, problem, why);
  for (int k = 0; k < msg.num_moving; ++k) {
    const auto i = static_cast<std::size_t>(k);
    const MovingReport m{msg.moving_ids[i], msg.moving_frames[i], msg.moving_by[i]};
    // Unconfirmed (no notice went out), this robot's own finding, or not news (the
    // notice was had, or this robot saw the landmark again since): nothing to repair.
    if (m.detected_by == 0 || m.detected_by == robot_id_ || !deferred_.is_news(m, robot_.lmap())) continue;
    ++counters_.notices_repaired;
    take_moving(m);
  }
  return true;
}

bool RobotNode::on_team_map(const global_map_t& msg, std::string* why) {
  if (!options_.team_map_fuse) return refused(Refusal::kMalformed, "a team map, but robot.team_map.fuse is off", why);
  Refusal reason = Refusal::kMalformed;
  const std::string problem = check_global_map(msg, options_.limits, options_.ekf.max_landmark_id, &reason);
  if (!problem.empty()) return refused(reason, problem, why);
  if (msg.frame > std::max(last_frame(), 0) + options_.max_frame_gap)
    return refused(Refusal::kFrameWindow,
                   "frame " + std::to_string(msg.frame) + " more than node.max_frame_gap ahead of this robot's " +
                       std::to_string(last_frame()),
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
  // Held until this robot has processed frame msg.frame + 1 (then applied after that
  // frame's outputs), so the live team does what the in-process run does: main
  // sends the team map of frame k once every robot finished k, which in a lockstep
  // team may reach a robot before or after its SENSOR of frame k + 1.
  if (!deferred_.take_team_map(msg)) {
    ++counters_.team_map_stale;
    return true;
  }
  ++counters_.team_map_chunks;
  apply_team_estimates();
  return true;
}

void RobotNode::apply_team_estimates() {
  const std::vector<TeamEstimate>& due = deferred_.due_team_estimates(last_frame());
  if (due.empty()) return;
  switch (robot_.apply_team_map(due.data(), static_cast<int>(due.size()))) {
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
  relocalised_frame_ = last_frame();
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
  if (msg.robot_id != robot_id_ || last_frame() < 0 || last_resync_frame_ == last_frame()) return false;
  last_resync_frame_ = last_frame();
  make_snapshot(now_utime);
  ++counters_.resyncs_answered;
  return true;
}

bool RobotNode::on_own_channel(std::int64_t incarnation, int frame) {
  if (incarnation == this->incarnation()) return false;  // this process's own message, looped back
  ++counters_.foreign_poses;
  if (incarnation < this->incarnation()) {  // a predecessor's late datagram, or a live older process
    if (incarnation != older_sender_) older_sender_ = incarnation, older_sender_frame_ = frame, older_sender_frames_ = 0;
    if (frame <= older_sender_frame_ && older_sender_frames_ > 0) return false;
    older_sender_frame_ = std::max(older_sender_frame_, frame);
    if (++older_sender_frames_ < 3) return false;
  }
  const bool fresh = duplicate_until_frame_ < 0 || last_frame() > duplicate_until_frame_;
  duplicate_until_frame_ = std::max(last_frame(), 0) + 50;
  return fresh || counters_.foreign_poses % 100 == 1;
}

node_status_t RobotNode::status_msg(std::int64_t now_utime) const {
  node_status_t s{};
  s.utime = now_utime;
  s.frame = last_frame();
  s.node_kind = node_status_t::ROBOT;
  s.node_id = static_cast<int16_t>(robot_id_);
  s.mode = status_mode(options_.mode);
  s.incarnation = incarnation();
  s.fault_flags = duplicate_until_frame_ >= 0 && last_frame() <= duplicate_until_frame_ ? node_status_t::FAULT_DUPLICATE_SENDER : 0;
  if (full_frame_ >= 0 && last_frame() - full_frame_ < kAlertFrames) s.fault_flags |= node_status_t::FAULT_CAPACITY;
  if (inconsistent_frame_ >= 0 && last_frame() - inconsistent_frame_ < kAlertFrames)
    s.fault_flags |= node_status_t::FAULT_INCONSISTENT;
  if (lost_frame_ >= 0 && last_frame() - lost_frame_ < kAlertFrames) s.fault_flags |= node_status_t::FAULT_FRAMES_LOST;
  if (save_failed_) s.fault_flags |= node_status_t::FAULT_SAVE_FAILED;
  if (main_silent_) s.fault_flags |= node_status_t::FAULT_MAIN_SILENT;
  if (healed_frame_ >= 0 && last_frame() - healed_frame_ < kAlertFrames)
    s.fault_flags |= node_status_t::FAULT_PARTITION_HEALED;
  if (relocalised_frame_ >= 0 && last_frame() - relocalised_frame_ < kAlertFrames)
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

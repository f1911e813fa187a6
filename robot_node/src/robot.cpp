// SPDX-License-Identifier: Apache-2.0
#include "elaslam/robot_node/robot.hpp"

#include "elaslam/common/stats.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>

namespace elaslam {

// Room for one frame's events: every observation can yield an UPDATE, an ADD or
// MOVING and the UPDATE of a landmark it evicts (make_room), every mapped landmark
// can go missing.
std::size_t Robot::event_capacity(const RobotOptions& o) {
  return static_cast<std::size_t>(3 * o.max_observations + o.ekf.capacity + 8);
}

namespace {

// Candidates exist in modes ela and consensus only.
int history_window(const RobotOptions& o) {
  return o.mode == Mode::kEla || o.mode == Mode::kConsensus ? o.candidate_history_frames : 0;
}

// Operations a frame can apply to a filter: two predictions, per observation an
// update or a remove and an add, per held landmark a removal (missing, notices) or a
// team increment; the window's frames and the current one.
int history_ops(const RobotOptions& o) {
  return (history_window(o) + 1) * (3 * o.max_observations + 2 * o.ekf.capacity + 8);
}

}  // namespace

const char* to_string(EventKind k) {
  switch (k) {
    case EventKind::kAdd: return "ADD";
    case EventKind::kUpdate: return "UPDATE";
    case EventKind::kMoving: return "MOVING";
    case EventKind::kReturn: return "RETURN";
  }
  return "?";
}

Robot::Robot(const RobotOptions& options, int robot_id)
    : options_(options),
      robot_id_(robot_id),
      filters_(options.ekf, options.team_map_fuse, history_window(options), history_ops(options)),
      team_(options.team_map_fuse ? options.ekf.max_landmark_id : 0, options.team_map_min_gain),
      lmap_(options.ekf.max_landmark_id, lifecycle_rules(options)),
      tracks_(options.tracking, options.ekf.max_landmark_id),
      gate_(options),
      monitor_(options.consistency_window_frames, options.consistency_probability) {
  team_gate_threshold_ = options.team_map_gate_probability < 1.0 ? chi2_quantile(options.team_map_gate_probability, 2)
                                                                  : std::numeric_limits<double>::infinity();
  restore_threshold_ = chi2_quantile(options.drift_gate_probability, 2);
  drift3_threshold_ = chi2_quantile(options.team_map_gate_probability, 3);
  updated_.reserve(static_cast<std::size_t>(options.max_observations));
  pairs_.reserve(static_cast<std::size_t>(options.ekf.capacity));
  events_.reserve(event_capacity(options));
  track_ops_.reserve(2 * static_cast<std::size_t>(options.max_observations));
  followed_frame_.assign(static_cast<std::size_t>(std::max(options.ekf.max_landmark_id, 0)), -1);
}

void Robot::reset() {
  initialised_ = false;
  last_frame_ = -1;
  lmap_.clear();
  events_.clear();
  gate_.clear();
  monitor_.restart();
  team_.clear();
  trouble_frame_ = -1;
  tracks_.clear();
  track_ops_.clear();
  std::fill(followed_frame_.begin(), followed_frame_.end(), -1);
  clock_s_ = 0.0;
}

FrameSummary Robot::process(const FrameInput& in) {
  FrameSummary s;
  events_.clear();
  gate_.clear();
  updated_.clear();
  track_ops_.clear();
  s.num_obs = in.num_obs;
  const double dt = initialised_ ? step_seconds(in) : 0.0;
  predict(in, &s);
  clock_s_ += dt;
  last_frame_ = in.frame;
  follow_movers(&s);
  for (int k = 0; k < in.num_obs; ++k) lmap_.seen(in.obs[static_cast<std::size_t>(k)].landmark_id, in.frame);

  if (options_.mode == Mode::kEkf || options_.mode == Mode::kGated) {
    process_classic(in, &s);
  } else {
    process_ela(in, &s);       // steps 1-3 of docs/design.md section 4: the landmarks seen
    check_missing(&s);         // step 4: those expected in view but not seen
    drop_unseen_candidates();  // candidates not seen lately start over
  }
  // UPDATEs are rate-limited per landmark: they refresh main_robot's copy, which
  // snapshots also repair, and one message per observation per frame would be most
  // of the team's traffic (docs/design.md: messages per frame bound the team's rate).
  for (int id : updated_) {
    const LMapEntry& e = lmap_[id];
    if (e.status == LandmarkStatus::kStatic && in.frame - e.reported_frame >= options_.update_period_frames)
      emit(EventKind::kUpdate, id);
  }
  s.events_dropped = events_dropped_;
  events_dropped_ = 0;
  check_consistency(&s);
  apply_track_ops();
  // Trouble the robot sees itself: every mapped landmark it judged, at least
  // kTeamMinTested, failed (a robot lost in heading finds them all outside their
  // ELA; movers rarely make a whole view), or the consistency monitor's verdict.
  // With a team map that mostly disagrees, it means lost.
  if ((s.num_rejected >= kTeamMinTested && s.num_accepted == 0) || s.inconsistent) trouble_frame_ = in.frame;
  return s;
}

// The consistency monitor's verdict on this frame's window (consistency.hpp); when
// the filter is found inconsistent and recovery is on, the pose covariance widens
// (a zero-motion prediction with the recovery noise: the cross-covariances are
// kept, so the map moves with the pose) and the window starts over.
void Robot::check_consistency(FrameSummary* s) {
  s->inconsistent = monitor_.end_frame();
  s->nis = monitor_.frame_nis();
  s->nis_dof = monitor_.frame_dof();
  if (!s->inconsistent || !options_.consistency_recover) return;
  const double xy = options_.recovery_sigma_xy * options_.recovery_sigma_xy;
  const double th = options_.recovery_sigma_theta * options_.recovery_sigma_theta;
  filters_.predict(last_frame_, Pose2{}, Eigen::Vector3d(xy, xy, th).asDiagonal(), /*dt=*/0.0, &s->filter_faults);
  monitor_.restart();
  s->recovered = true;
}

double Robot::step_seconds(const FrameInput& in) const {
  const double frames = std::max(1, in.frame - last_frame_);
  // In doubles: the stamps are the sender's, and any two int64 may be subtracted.
  const double dt = (static_cast<double>(in.utime) - static_cast<double>(last_utime_)) * 1e-6;
  return std::clamp(dt, 0.0, kMaxFramePeriodS * frames);
}

// Prediction from the odometer increment (eqs 4-5). The first frame sets the prior
// at the odometer reading: robots start at known poses (paper section 4), and the
// odometry frame O of each robot coincides with W at its start; the odometer's
// calibration states start at their prior (EkfSlam::reset). Each increment is the
// odometer's reported one: the filter applies its calibration estimate over the
// time the step spans (step_seconds).
void Robot::predict(const FrameInput& in, FrameSummary* s) {
  if (!initialised_) {
    Eigen::Matrix3d P0 = Eigen::Matrix3d::Zero();
    P0(StateLayout::kX, StateLayout::kX) = P0(StateLayout::kY, StateLayout::kY) =
        options_.initial_sigma_xy * options_.initial_sigma_xy;
    P0(StateLayout::kTheta, StateLayout::kTheta) = options_.initial_sigma_theta * options_.initial_sigma_theta;
    // A late start (first frame > 0: started late, or restarted without a state
    // file): the odometer has dead-reckoned since frame 0; its prior says so.
    if (in.frame > 0)
      P0 = dead_reckoning_cov(P0, in.frame, options_.late_start_step_m, options_.late_start_turn, in.noise);
    filters_.reset(in.odometer, P0);  // the histories start over too
    team_.clear();
    initialised_ = true;
  } else if (in.reanchor) {
    // A new odometer origin: no increment, and the frames since the last one driven
    // anywhere within the vehicle's bounds. (The calibration's random walk still
    // spans the time; its bias turns the robot by b dt, well inside this U.)
    const double k = std::max(1, in.frame - last_frame_);
    const double step = options_.max_step_m * k, turn = std::min(kPi, options_.max_turn * k);
    const Eigen::Matrix3d U = Eigen::Vector3d(step * step, step * step, turn * turn).asDiagonal();
    filters_.predict(in.frame, Pose2{}, U, step_seconds(in), &s->filter_faults);
  } else {
    // Frames missed since the last one (in.frame - last_frame_ > 1): the increment
    // spans them all, and its noise is theirs compounded.
    const Pose2 increment = between(last_odometer_, in.odometer);
    filters_.predict(in.frame, increment, gap_odometry_covariance(increment, in.frame - last_frame_, in.noise),
                   step_seconds(in), &s->filter_faults);
  }
  last_odometer_ = in.odometer;
  last_utime_ = in.utime;
}

// Modes ekf and gated: every observation of a mapped landmark corrects the filter
// (gated: unless its innovation fails the chi-square gate); new ones are added at once.
void Robot::process_classic(const FrameInput& in, FrameSummary* s) {
  const bool gate = options_.mode == Mode::kGated;
  for (int k = 0; k < in.num_obs; ++k) {
    const Observation& o = in.obs[static_cast<std::size_t>(k)];
    if (!filters_.own().has_landmark(o.landmark_id)) continue;
    const UpdateReport r = filters_.update(last_frame_, o.landmark_id, o.z, gate, &s->filter_faults);
    if (r.status == EkfStatus::kOk) monitor_.add(r.d2);
    gate_.record({o.landmark_id, gate ? GateKind::kInnovation : GateKind::kNone, r.d2, r.threshold,
                  r.status != EkfStatus::kGated});
    if (r.status == EkfStatus::kOk) {
      ++s->num_accepted;
      updated_.push_back(o.landmark_id);
    } else if (r.status == EkfStatus::kGated) {
      ++s->num_rejected;
    } else {
      ++s->filter_faults;
    }
  }
  for (int k = 0; k < in.num_obs; ++k) {
    const Observation& o = in.obs[static_cast<std::size_t>(k)];
    if (filters_.own().has_landmark(o.landmark_id)) continue;
    ++s->num_candidates;
    make_room(s);  // an archived landmark comes back as new: its ADD replaces the old estimate at main
    if (!added(filters_.add(last_frame_, o.landmark_id, o.z, &s->filter_faults), s)) continue;
    lmap_.map_at_once(o.landmark_id, in.frame);
    emit(EventKind::kAdd, o.landmark_id);
    ++s->num_added;
  }
}

// Modes ela and consensus: Algorithm 1's loop over the observed landmarks
// (docs/design.md section 4): step 3 for the mapped ones, all judged against the same
// prior before any of them corrects the filter, then steps 1-2 for the others.
void Robot::process_ela(const FrameInput& in, FrameSummary* s) {
  own_drifted_ = own_filter_drifted();
  if (own_drifted_) ++s->drifted;
  // 3. The mapped landmarks in view and their verdicts (ElaGate: eq 16, the
  //    consensus clique or the single-landmark test, then the drift test).
  for (int k = 0; k < in.num_obs; ++k) {
    const Observation& o = in.obs[static_cast<std::size_t>(k)];
    if (lmap_[o.landmark_id].status == LandmarkStatus::kStatic && filters_.own().has_landmark(o.landmark_id))
      gate_.add_to_view(o.landmark_id, o.z);  // not the archived ones (restore_archived, below)
  }
  gate_.judge_view(filters_.own(), &lmap_);
  // 3, inside: correct the filter (eqs 7-13), in view order; with lone_needs_check,
  //    a landmark judged alone only if it has once agreed with another (checked).
  for (int k = 0; k < gate_.view_size(); ++k) {
    const ElaVerdict verdict = gate_.verdict(k);
    if (!verdict.inside) continue;
    const int id = gate_.in_view(k).id;
    if (options_.lone_needs_check && verdict.alone && !lmap_[id].checked) {
      ++s->num_unchecked;
      continue;
    }
    correct(id, gate_.in_view(k).z, s);
  }
  // 3, outside: rejected; the `moving_after`-th out-of-ELA verdict in a row makes
  //    it MOVING: out of the filter, re-anchored as a candidate where it is now.
  for (int k = 0; k < gate_.view_size(); ++k) {
    const InView& v = gate_.in_view(k);
    const ElaVerdict verdict = gate_.verdict(k);
    if (verdict.inside) {
      lmap_.inside_ela(v.id, !verdict.alone);
      continue;
    }
    ++s->num_rejected;
    // A landmark judged alone cannot tell its own motion from the robot's pose
    // error: unless configured otherwise, it is only skipped.
    if (!options_.lone_verdicts && verdict.alone) continue;
    if (lmap_.outside_ela(v.id) && !own_drifted_) mark_moving(v.id, &v.z, s);
  }
  restore_archived(in, s);
  // 1-2. New landmarks and candidates.
  lmap_.set_few_static(s->num_accepted < 3);
  handle_candidates(in, s);
  // Confirmed candidates' earlier sightings, into the filters (FilterHistory).
  s->filter_faults += filters_.end_frame(in.frame);
}

bool Robot::own_filter_drifted() const {
  return filters_.has_aided() && options_.team_map_drift_check &&
         pose_drifted(filters_.own(), filters_.aided(), drift3_threshold_);
}

void Robot::correct(int id, const RangeBearing& z, FrameSummary* s) {
  const UpdateReport r = filters_.update(last_frame_, id, z, false, &s->filter_faults);
  if (r.status == EkfStatus::kOk) {
    monitor_.add(r.d2);
    ++s->num_accepted;
    updated_.push_back(id);
  } else {
    ++s->filter_faults;
  }
}

// Steps 1-2 of section 5, with candidates kept in the filter as inert states: a
// new landmark is added to the filter at its first sighting (so its estimate is
// anchored where the robot's pose was best known, and its correlation with the
// pose is tracked from then on) but corrects nothing until it is confirmed. Each
// re-sighting is its ELA test (ElaGate::judge_candidate). Inconsistent: re-anchored
// here; `moving_after` times in a row: reported MOVING.
void Robot::handle_candidates(const FrameInput& in, FrameSummary* s) {
  for (int k = 0; k < in.num_obs; ++k) {
    const Observation& o = in.obs[static_cast<std::size_t>(k)];
    const int id = o.landmark_id;
    const LMapEntry& e = lmap_[id];
    // STATIC ones, and those found moving in step 3, were judged in view.
    if (e.status == LandmarkStatus::kStatic || e.moved_frame == in.frame) continue;
    ++s->num_candidates;
    // Sightings the map keeps out go to the landmark's track; one found or told
    // moving before without a track (lost, or told while out of view) starts one.
    queue_track(TrackOp::Kind::kSee, id, o.z, e.position, e.times_moving > 0);
    record_sighting(id, o.z);
    if (e.status == LandmarkStatus::kCandidate && filters_.own().has_landmark(id)) {
      if (gate_.judge_candidate(id, filters_.own().check(id, o.z), &lmap_)) {
        const bool followed = followed_frame_[static_cast<std::size_t>(id)] == in.frame;
        const bool moving_track = (options_.tracking.return_when_stopped || followed) && tracks_.has(id) &&
                                  !tracks_.track(id).stopped();
        if (lmap_.candidate_consistent(id) && !moving_track) {
          confirm(id, o.z, s);
        } else if (followed) {
          // A followed mover: its sighting corrects the pose as a static landmark's
          // would, through the state its track moves (follow_movers).
          if (filters_.update(last_frame_, id, o.z, false, &s->filter_faults).status == EkfStatus::kOk) {
            ++s->mover_corrections;
          } else {
            ++s->filter_faults;
          }
        } else if (options_.candidate_updates) {
          filters_.update_landmark_only(last_frame_, id, o.z, &s->filter_faults);
        }
        continue;
      }
      filters_.remove(last_frame_, id);
      if (lmap_.candidate_inconsistent(id)) {
        emit_at(EventKind::kMoving, id, e.position, e.cov);
        ++s->num_moving;
      }
    }
    // New, seen again after moving or after a gap, or inconsistent: (re)anchor here.
    lmap_.anchor_candidate(id, in.frame);
    make_room(s);
    added(filters_.add(last_frame_, id, o.z, &s->filter_faults), s);  // kFull: candidate outside the filter
  }
}

// A candidate consistent for long enough becomes STATIC: it corrects the filter
// from now on, starting with this frame's sighting.
void Robot::confirm(int id, const RangeBearing& z, FrameSummary* s) {
  const bool returned = lmap_.confirm(id, last_frame_);
  queue_track(TrackOp::Kind::kEnd, id, z, Eigen::Vector2d::Zero(), false);  // STATIC again: the map holds it
  FilterHistory::Op held;
  held.kind = FilterHistory::Kind::kHeldPosition;
  filters_.upgrade(id, &held);
  if (held.kind == FilterHistory::Kind::kPosition) {
    // The team estimate held for the candidate (hold_team_estimate) corrects the
    // aided filter as of its team map (the rebuild at the end of this frame): the
    // channel counts it fused.
    TeamIncrement inc;
    inc.epoch = lmap_[id].times_moving;
    inc.z = held.p;
    inc.R = held.R;
    inc.Y = held.R.inverse();
    team_.commit(id, inc);
    ++team_counters_.fused;
  }
  if (filters_.update(last_frame_, id, z, false, &s->filter_faults).status == EkfStatus::kOk) {
    ++s->num_accepted;
  } else {
    ++s->filter_faults;
  }
  emit(returned ? EventKind::kReturn : EventKind::kAdd, id);
  ++s->num_added;
}

// Candidates in the filter that have not been seen for `candidate_gap_frames`
// frames lose their streak: they leave the filter (they never corrected the
// robot) and start over when seen again.
void Robot::drop_unseen_candidates() {
  for (int slot = filters_.own().num_landmarks() - 1; slot >= 0; --slot) {
    const int id = filters_.own().id_at(slot);
    const LMapEntry& e = lmap_[id];
    if (e.status == LandmarkStatus::kStatic || last_frame_ - e.last_seen_frame < options_.candidate_gap_frames) continue;
    filters_.remove(last_frame_, id);
    lmap_.drop_candidate(id);
  }
}

// Step 4: a STATIC landmark expected in view that has not been seen for
// LifecycleRules::missing_needed frames has left: `missing_frames`, or more for a
// sensor that misses landmarks (detection_probability < 1), so that a present
// landmark goes unreported that long only with the ELA gate's false-alarm
// probability.
void Robot::check_missing(FrameSummary* s) {
  if (options_.missing_frames <= 0) return;
  const Pose2 pose = filters_.own().pose();
  for (int slot = filters_.own().num_landmarks() - 1; slot >= 0; --slot) {
    const int id = filters_.own().id_at(slot);
    const LMapEntry& e = lmap_[id];
    if (e.status != LandmarkStatus::kStatic) continue;
    const bool expected = e.last_seen_frame != last_frame_ && expected_in_view(id, pose);
    if (lmap_.missed(id, expected) && !own_drifted_) mark_moving(id, nullptr, s);
  }
}

// Well inside the field of view: the disc of sensor_range_m, or the cone of
// +-fov_half_angle_deg in it, shrunk by fov_margin_m at its edges.
bool Robot::expected_in_view(int id, const Pose2& pose) const {
  const Eigen::Vector2d d = filters_.own().landmark(id) - pose.translation();
  const double range = d.norm();
  if (!(range < options_.sensor_range - options_.fov_margin)) return false;
  if (!(options_.fov_half_angle < kPi)) return true;
  const double bearing = wrap_angle(std::atan2(d.y(), d.x()) - pose.theta);
  return std::fabs(bearing) < options_.fov_half_angle - options_.fov_margin / std::max(range, 1e-3);
}

// Remove a STATIC landmark found moving; seen now, it is re-anchored as a candidate
// where it is (it may come back when it stops).
void Robot::mark_moving(int id, const RangeBearing* seen, FrameSummary* s) {
  const Eigen::Vector2d last = filters_.own().landmark(id);
  const Eigen::Matrix2d last_cov = filters_.own().landmark_cov(id);
  if (filters_.remove(last_frame_, id) != EkfStatus::kOk) {
    ++s->filter_faults;
    return;
  }
  lmap_.found_moving(id, last_frame_, seen != nullptr);
  if (seen) {
    // The verdict "not static" starts the mover's track at the sighting, anchored
    // where the landmark stood.
    queue_track(TrackOp::Kind::kBegin, id, *seen, last, true);
    record_sighting(id, *seen);
    added(filters_.add(last_frame_, id, *seen, &s->filter_faults), s);
  }
  emit_at(EventKind::kMoving, id, last, last_cov);
  ++s->num_moving;
}

// The bounded filter (docs/adr/0036-bounded-filter.md): a robot in a world
// larger than its filter keeps the landmarks near it. When an add finds every slot
// taken, the held landmark farthest from the robot goes, if it is beyond
// sensor_range and was not seen this frame (it cannot be in view: nothing the
// robot sees now is given up). A STATIC one sends its last estimate to main_robot
// (an UPDATE; the global map keeps it) and stays in the L-map as archived, listed
// in the snapshots; a candidate is dropped, as one unseen too long is. O(n).
bool Robot::make_room(FrameSummary* s) {
  if (filters_.own().num_landmarks() < filters_.own().capacity()) return true;
  const Eigen::Vector2d here = filters_.own().pose().translation();
  int victim = -1;
  double farthest = options_.sensor_range;
  for (int slot = 0; slot < filters_.own().num_landmarks(); ++slot) {
    const int id = filters_.own().id_at(slot);
    if (lmap_[id].last_seen_frame == last_frame_) continue;
    const double d = (filters_.own().landmark(id) - here).norm();
    if (d > farthest) {
      farthest = d;
      victim = id;
    }
  }
  if (victim < 0) return false;
  if (lmap_[victim].status == LandmarkStatus::kStatic) {
    emit(EventKind::kUpdate, victim);
    lmap_.archive(victim, filters_.own().landmark(victim), filters_.own().landmark_cov(victim));
    filters_.remove(last_frame_, victim);
  } else {
    filters_.remove(last_frame_, victim);
    lmap_.drop_candidate(victim);
  }
  ++s->evicted;
  return true;
}

// An archived landmark seen again re-enters the filter from this observation (its
// old estimate cannot be fused back: it is correlated with the robot's pose and
// map in ways the filter no longer tracks) and is STATIC at once. The two
// estimates are tested against each other, at drift_gate_probability (one strict
// test standing for moving_after ELA tests): one that moved while out of the
// filter is found moving here, as the ELA gate would have found it in view.
void Robot::restore_archived(const FrameInput& in, FrameSummary* s) {
  for (int k = 0; k < in.num_obs; ++k) {
    const Observation& o = in.obs[static_cast<std::size_t>(k)];
    const LMapEntry& e = lmap_[o.landmark_id];
    if (e.status != LandmarkStatus::kStatic || !e.archived) continue;
    make_room(s);
    if (!added(filters_.add(last_frame_, o.landmark_id, o.z, &s->filter_faults), s)) continue;  // stays archived
    const Eigen::Vector2d kept = e.position;
    const Eigen::Matrix2d kept_cov = e.cov;
    lmap_.unarchive(o.landmark_id);
    ++s->restored;
    const double d2 = mahalanobis2(filters_.own().landmark(o.landmark_id) - kept, filters_.own().landmark_cov(o.landmark_id) + kept_cov);
    if (d2 > restore_threshold_) mark_moving(o.landmark_id, &o.z, s);
  }
}

// The L-map's record of a sighting: world position g(R, y) (eq 15) and its covariance.
void Robot::record_sighting(int id, const RangeBearing& z) {
  Eigen::Matrix<double, 2, 3> Gx;
  Eigen::Matrix2d Gz;
  const Eigen::Vector2d p_LinW = inverse_observe(filters_.own().pose(), z, &Gx, &Gz);
  const Eigen::Matrix2d C = Gx * filters_.own().pose_cov() * Gx.transpose() + Gz * filters_.own().measurement_cov() * Gz.transpose();
  lmap_.record_sighting(id, p_LinW, C);
}

double Robot::map_mean_diag() const {
  // Block accessors only: covariance() would complete the whole matrix.
  const EkfSlam& f = estimate();
  double sum = f.pose_cov().trace();
  int n = StateLayout::kPoseDim;
  for (int slot = 0; slot < f.num_landmarks(); ++slot) {
    const int id = f.id_at(slot);
    if (lmap_[id].status != LandmarkStatus::kStatic) continue;
    sum += f.landmark_cov(id).trace();
    n += StateLayout::kLandmarkDim;
  }
  return sum / n;
}

// Step 5 (between frames): main_robot says the landmark moves.
bool Robot::apply_notice(int landmark_id, int frame) {
  // ekf is the paper's baseline: every landmark static, also one the team (or main's
  // body rule, main.body_radius_m) found moving.
  if (options_.mode == Mode::kEkf || !lmap_.valid_id(landmark_id)) return false;
  const bool in_filter = filters_.own().has_landmark(landmark_id);
  const bool held = in_filter && lmap_[landmark_id].status == LandmarkStatus::kStatic;
  const bool removed = in_filter && filters_.remove(last_frame_, landmark_id) == EkfStatus::kOk;
  lmap_.told_moving(landmark_id, frame, removed || lmap_[landmark_id].archived);
  return removed && held;
}

bool Robot::added(EkfStatus st, FrameSummary* s) {
  if (st == EkfStatus::kOk) return true;
  ++s->filter_faults;
  if (st == EkfStatus::kFull) ++s->filter_full;  // a capacity limit: the node says so (FAULT_CAPACITY)
  return false;
}

void Robot::emit(EventKind kind, int id) {
  lmap_.reported(id, last_frame_);
  emit_at(kind, id, filters_.own().landmark(id), filters_.own().landmark_cov(id));
}

void Robot::emit_at(EventKind kind, int id, const Eigen::Vector2d& p, const Eigen::Matrix2d& C) {
  if (events_.size() >= events_.capacity()) {  // never grow: the buffer is sized for a frame
    ++events_dropped_;
    return;
  }
  events_.push_back({kind, id, last_frame_, p, C});
}

}  // namespace elaslam

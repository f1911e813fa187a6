#include "elaslam/robot_node/robot.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/LU>

#include "elaslam/common/stats.hpp"

namespace elaslam {
namespace {

// Room for one frame's events: every observation can yield one event, every mapped
// landmark can go missing, plus UPDATEs for the corrected ones.
std::size_t event_capacity(const RobotOptions& o) {
  return static_cast<std::size_t>(2 * kMaxObservations + o.ekf.capacity + 8);
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
      ekf_(options.ekf),
      lmap_(options.ekf.max_landmark_id),
      solver_(options.ela_gate_probability),
      ela_threshold_(chi2_quantile(options.ela_gate_probability, 2)),
      candidate_threshold_(chi2_quantile(options.ela_gate_probability, 2)),
      drift_threshold_(chi2_quantile(options.drift_gate_probability, 2)) {
  missing_needed_ = options.missing_frames;
  if (options.detection_probability < 1.0 && options.missing_frames > 0) {
    // (1 - p_d)^n <= 1 - gate probability.
    const double n = std::log(1.0 - options.ela_gate_probability) / std::log(1.0 - options.detection_probability);
    missing_needed_ = std::max(missing_needed_, static_cast<int>(std::ceil(n)));
  }
  view_.reserve(kMaxObservations);
  view_obs_.reserve(kMaxObservations);
  inside_.reserve(kMaxObservations);
  prior_.reserve(kMaxObservations);
  d2_.reserve(kMaxObservations);
  updated_.reserve(kMaxObservations);
  out_count_.assign(static_cast<std::size_t>(options.ekf.max_landmark_id), 0);
  handled_.assign(static_cast<std::size_t>(options.ekf.max_landmark_id), -1);
  events_.reserve(event_capacity(options));
  gates_.reserve(kMaxObservations);
}

void Robot::reset() {
  initialised_ = false;
  last_frame_ = -1;
  lmap_.clear();
  std::fill(out_count_.begin(), out_count_.end(), 0);
  std::fill(handled_.begin(), handled_.end(), -1);
  events_.clear();
  gates_.clear();
}

FrameSummary Robot::process(const FrameInput& in) {
  FrameSummary s;
  events_.clear();
  gates_.clear();
  updated_.clear();
  s.num_obs = in.num_obs;
  predict(in, &s);
  last_frame_ = in.frame;
  for (int k = 0; k < in.num_obs; ++k) lmap_[in.obs[static_cast<std::size_t>(k)].landmark_id].last_seen_frame = in.frame;

  if (options_.mode == Mode::kEkf || options_.mode == Mode::kGated) {
    process_classic(in, &s);
  } else {
    process_ela(in, &s);
    check_missing(&s);
    drop_unseen_candidates();
  }
  // UPDATEs are rate-limited per landmark: they refresh main_robot's copy, which
  // snapshots also repair, and one message per observation per frame would be most
  // of the team's traffic (DESIGN: messages per frame bound the team's rate).
  for (int id : updated_) {
    LMapEntry& e = lmap_[id];
    if (lmap_[id].status == LandmarkStatus::kStatic && in.frame - e.reported_frame >= options_.update_period_frames)
      emit(EventKind::kUpdate, id);
  }
  s.events_dropped = events_dropped_;
  events_dropped_ = 0;
  return s;
}

// Prediction from the odometer increment (eqs 4-5). The first frame sets the prior
// at the odometer reading: robots start at known poses (paper section 4), and the
// odometry frame O of each robot coincides with W at its start.
void Robot::predict(const FrameInput& in, FrameSummary* s) {
  if (!initialised_) {
    Eigen::Matrix3d P0 = Eigen::Matrix3d::Zero();
    P0(0, 0) = P0(1, 1) = options_.initial_sigma_xy * options_.initial_sigma_xy;
    P0(2, 2) = options_.initial_sigma_theta * options_.initial_sigma_theta;
    ekf_.reset(in.odometer, P0);
    initialised_ = true;
  } else {
    const Pose2 increment = between(last_odometer_, in.odometer);
    if (ekf_.predict(increment, odometry_covariance(increment, in.noise)) != EkfStatus::kOk) ++s->filter_faults;
  }
  last_odometer_ = in.odometer;
}

// Modes ekf and gated: every observation of a mapped landmark corrects the filter
// (gated: unless its innovation fails the chi-square gate); new ones are added at once.
void Robot::process_classic(const FrameInput& in, FrameSummary* s) {
  const bool gate = options_.mode == Mode::kGated;
  for (int k = 0; k < in.num_obs; ++k) {
    const Observation& o = in.obs[static_cast<std::size_t>(k)];
    if (!ekf_.has_landmark(o.landmark_id)) continue;
    const UpdateReport r = ekf_.update(o.landmark_id, o.z, gate);
    gates_.push_back({o.landmark_id, gate ? GateKind::kInnovation : GateKind::kNone, r.d2, r.threshold,
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
    if (ekf_.has_landmark(o.landmark_id)) continue;
    ++s->num_candidates;
    if (ekf_.add_landmark(o.landmark_id, o.z) != EkfStatus::kOk) {
      ++s->filter_faults;
      continue;
    }
    lmap_.set_status(o.landmark_id, LandmarkStatus::kStatic, in.frame);
    emit(EventKind::kAdd, o.landmark_id);
    ++s->num_added;
  }
}

// Modes ela and consensus: Algorithm 1 with the L-map.
void Robot::process_ela(const FrameInput& in, FrameSummary* s) {
  // 1. Mapped landmarks in view.
  view_.clear();
  view_obs_.clear();
  for (int k = 0; k < in.num_obs; ++k) {
    const Observation& o = in.obs[static_cast<std::size_t>(k)];
    if (lmap_[o.landmark_id].status != LandmarkStatus::kStatic) continue;
    InView v;
    v.id = o.landmark_id;
    v.z = o.z;
    set_local(&v, ekf_.measurement_cov());
    view_.push_back(v);
    view_obs_.push_back(k);
  }
  // 2. Their verdicts, all from the same prior.
  gate_view(s);
  if (options_.drift_memory > 0.0) drift_test();
  // 3. Correct with the accepted ones.
  for (std::size_t k = 0; k < view_.size(); ++k) {
    if (!inside_[k]) continue;
    const UpdateReport r = ekf_.update(view_[k].id, view_[k].z, false);
    if (r.status == EkfStatus::kOk) {
      ++s->num_accepted;
      updated_.push_back(view_[k].id);
    } else {
      ++s->filter_faults;
    }
  }
  // 4. Remove the ones found moving (after `moving_after` consecutive verdicts).
  for (std::size_t k = 0; k < view_.size(); ++k) {
    const int id = view_[k].id;
    int& outs = out_count_[static_cast<std::size_t>(id)];
    if (inside_[k]) {
      outs = 0;
      continue;
    }
    ++s->num_rejected;
    // A landmark tested alone (no other mapped landmark in view to compare with)
    // cannot tell its own motion from the robot's pose error: unless configured
    // otherwise, it is only skipped.
    if (!options_.lone_verdicts && gates_[k].kind == GateKind::kInnovation) continue;
    if (++outs >= options_.moving_after)
      mark_moving(id, &in.obs[static_cast<std::size_t>(view_obs_[k])], s);
  }
  // 5. New landmarks and candidates.
  handle_candidates(in, s);
}

// d2 of view_[i]'s innovation against the prior; infinite when it has none.
double Robot::prior_d2(int i) const {
  const UpdateReport& r = prior_[static_cast<std::size_t>(i)];
  return r.status == EkfStatus::kOk ? r.d2 : std::numeric_limits<double>::infinity();
}

void Robot::gate_view(FrameSummary* /*s*/) {
  const int n = static_cast<int>(view_.size());
  inside_.assign(view_.size(), 1);
  // Every landmark's innovation against the prior, once: the single tests, the
  // consensus ranking and the drift test all read it.
  prior_.clear();
  for (const InView& v : view_) prior_.push_back(ekf_.check(v.id, v.z));
  if (n == 0) return;
  if (options_.mode == Mode::kConsensus && n >= 2) {
    gate_view_consensus();
    return;
  }
  // Eq 16 for every landmark in view. A landmark found outside its ELA stops
  // shaping the others' ELAs: the worst one is set aside and the rest re-tested,
  // until all that remain agree (one moving neighbour would otherwise shift every
  // other landmark's ELA by its displacement / (n - 1) and flag them too).
  d2_.assign(view_.size(), 0.0);
  int active = n;
  while (active >= 2) {
    int worst = -1;
    for (int i = 0; i < n; ++i) {
      if (!inside_[static_cast<std::size_t>(i)]) continue;
      d2_[static_cast<std::size_t>(i)] = ela_multi_d2(ekf_, view_.data(), n, i, inside_.data());
      if (d2_[static_cast<std::size_t>(i)] > ela_threshold_ &&
          (worst < 0 || d2_[static_cast<std::size_t>(i)] > d2_[static_cast<std::size_t>(worst)]))
        worst = i;
    }
    if (worst < 0) break;
    inside_[static_cast<std::size_t>(worst)] = 0;
    --active;
  }
  for (int i = 0; i < n; ++i) {
    GateRecord g{view_[static_cast<std::size_t>(i)].id, GateKind::kMulti, d2_[static_cast<std::size_t>(i)],
                 ela_threshold_, inside_[static_cast<std::size_t>(i)] != 0};
    if (active < 2 && g.inside) {
      // A single landmark in view (or left): its ELA is the EKF's predicted observation.
      g.kind = GateKind::kInnovation;
      g.d2 = prior_d2(i);
      g.inside = g.d2 <= g.threshold;
      inside_[static_cast<std::size_t>(i)] = g.inside;
    }
    gates_.push_back(g);
  }
}

// A slow mover passes every single-frame test while the filter follows it, but its
// innovations are not white. Each STATIC landmark in view that passed its test
// keeps an exponentially weighted sum of its whitened innovations (against the
// prior, before this frame's corrections); under the model the sum has covariance
// I / (1 - lambda^2), so |sum|^2 (1 - lambda^2) is chi-square with 2 dof. Tested
// every frame on a memory of ~1 / (1 - lambda) sightings, it has its own, stricter
// gate (drift_gate_probability); beyond it the sighting is an out-of-ELA verdict
// like any other. (The ELA residual of eq 16 in place of the innovation cancels
// the robot's pose error, but also hides a drift shared with co-moving
// neighbours; measured worse, docs/decisions.md.)
void Robot::drift_test() {
  const double lambda = options_.drift_memory;
  const double scale = 1.0 - lambda * lambda;
  for (std::size_t k = 0; k < view_.size(); ++k) {
    if (!inside_[k]) continue;
    if (prior_[k].status != EkfStatus::kOk) continue;
    LMapEntry& e = lmap_[view_[k].id];
    e.drift = lambda * e.drift + prior_[k].whitened;
    if (e.drift.squaredNorm() * scale > drift_threshold_) {
      inside_[k] = 0;
      gates_[k].inside = false;
    }
  }
}

// Largest mutually consistent set of the landmarks in view; outside it = moving.
// A best set of fewer than two falls back to each landmark's single test.
void Robot::gate_view_consensus() {
  const int n = static_cast<int>(view_.size());
  solver_.reset(n);
  for (int i = 0; i < n; ++i) {
    const InView& vi = view_[static_cast<std::size_t>(i)];
    const double d2 = prior_d2(i);
    solver_.set_prior_d2(i, std::isfinite(d2) ? d2 : 1e12);
    for (int j = i + 1; j < n; ++j)
      if (pair_d2(ekf_, vi, view_[static_cast<std::size_t>(j)]) <= ela_threshold_) solver_.add_edge(i, j);
  }
  const std::uint64_t chosen = solver_.solve();
  const bool fallback = __builtin_popcountll(chosen) < 2;
  // The clique is the static reference. A landmark outside it may only have failed
  // one pair test by chance (1 % per pair at the default gate, several pairs per
  // landmark): it is re-tested against the whole clique with the fused ELA (eq 16
  // restricted to the clique, inside_ as the mask) and admitted when it agrees.
  for (int i = 0; i < n; ++i) inside_[static_cast<std::size_t>(i)] = (chosen >> i) & 1u;
  const std::size_t first = gates_.size();
  for (int i = 0; i < n; ++i) {
    const InView& vi = view_[static_cast<std::size_t>(i)];
    GateRecord g{vi.id, GateKind::kConsensus, 0.0, ela_threshold_, true};
    if (fallback) {  // fewer than two agree: each landmark's single test
      g.kind = GateKind::kInnovation;
      g.d2 = prior_d2(i);
      g.inside = g.d2 <= g.threshold;
    } else if (!inside_[static_cast<std::size_t>(i)]) {
      g.d2 = ela_multi_d2(ekf_, view_.data(), n, i, inside_.data());
      g.inside = g.d2 <= g.threshold;
    }
    gates_.push_back(g);
  }
  for (int i = 0; i < n; ++i) inside_[static_cast<std::size_t>(i)] = gates_[first + static_cast<std::size_t>(i)].inside;
}

// Steps 1-2 of section 5, with candidates kept in the filter as inert states: a
// new landmark is added to the filter at its first sighting (so its estimate is
// anchored where the robot's pose was best known, and its correlation with the
// pose is tracked from then on) but corrects nothing until it is confirmed. Each
// re-sighting is its ELA test: the innovation against the filter's prediction,
// whose covariance carries exactly the pose uncertainty accrued since the anchor.
// Inconsistent: re-anchored here; `moving_after` times in a row: reported MOVING.
void Robot::handle_candidates(const FrameInput& in, FrameSummary* s) {
  for (int k = 0; k < in.num_obs; ++k) {
    const Observation& o = in.obs[static_cast<std::size_t>(k)];
    const int id = o.landmark_id;
    LMapEntry& e = lmap_[id];
    if (e.status == LandmarkStatus::kStatic || handled_[static_cast<std::size_t>(id)] == in.frame) continue;
    ++s->num_candidates;
    record_sighting(id, o.z);
    if (e.status == LandmarkStatus::kCandidate && ekf_.has_landmark(id)) {
      const UpdateReport r = ekf_.check(id, o.z);
      bool inside = r.status == EkfStatus::kOk && r.d2 <= candidate_threshold_;
      if (inside && options_.candidate_drift_test) {
        // The innovations of a refined candidate are white if it stands still; their
        // running sum is the test for a mover the estimate keeps following.
        const Eigen::Vector2d sum = e.innovation_sum + r.whitened;
        const int n = e.innovations + 1;
        if (sum.squaredNorm() / n > candidate_threshold_) inside = false;
        e.innovation_sum = sum;
        e.innovations = n;
      }
      gates_.push_back({id, GateKind::kCandidate, r.d2, candidate_threshold_, inside});
      if (inside) {
        out_count_[static_cast<std::size_t>(id)] = 0;
        if (++e.consistent_sightings >= sightings_to_confirm(e)) {
          confirm(id, o.z, s);
        } else if (options_.candidate_updates && ekf_.update_landmark_only(id, o.z).status != EkfStatus::kOk) {
          ++s->filter_faults;
        }
        continue;
      }
      ekf_.remove_landmark(id);
      if (++out_count_[static_cast<std::size_t>(id)] >= options_.moving_after && !e.reported_moving) {
        e.was_moving = e.reported_moving = true;
        ++e.times_moving;
        emit_at(EventKind::kMoving, id, e.position, e.cov);
        ++s->num_moving;
      }
    }
    // New, seen again after moving or after a gap, or inconsistent: (re)anchor here.
    lmap_.set_status(id, LandmarkStatus::kCandidate, in.frame);
    e.restart_streak(1);
    if (ekf_.add_landmark(id, o.z) != EkfStatus::kOk) ++s->filter_faults;  // kFull: candidate outside the filter
  }
}

// Sightings a candidate needs: confirm_frames when new; return_frames after it
// has moved, doubled for every further time it was found moving when
// return_backoff is on (a landmark that stops and goes again and again, such as a
// robot, earns less trust each time).
int Robot::sightings_to_confirm(const LMapEntry& e) const {
  if (!e.was_moving) return options_.confirm_frames;
  if (!options_.return_backoff) return options_.return_frames;
  return options_.return_frames << std::min(std::max(e.times_moving - 1, 0), 10);
}

// A candidate consistent for long enough becomes STATIC: it corrects the filter
// from now on, starting with this frame's sighting.
void Robot::confirm(int id, const RangeBearing& z, FrameSummary* s) {
  LMapEntry& e = lmap_[id];
  lmap_.set_status(id, LandmarkStatus::kStatic, last_frame_);
  e.missing_frames = 0;
  e.drift.setZero();
  e.reported_moving = false;
  out_count_[static_cast<std::size_t>(id)] = 0;
  if (ekf_.update(id, z, false).status == EkfStatus::kOk) {
    ++s->num_accepted;
  } else {
    ++s->filter_faults;
  }
  emit(e.was_moving ? EventKind::kReturn : EventKind::kAdd, id);
  ++s->num_added;
}

// Candidates in the filter that have not been seen for `candidate_gap_frames`
// frames lose their streak: they leave the filter (they never corrected the
// robot) and start over when seen again.
void Robot::drop_unseen_candidates() {
  for (int slot = ekf_.num_landmarks() - 1; slot >= 0; --slot) {
    const int id = ekf_.id_at(slot);
    LMapEntry& e = lmap_[id];
    if (e.status == LandmarkStatus::kStatic || last_frame_ - e.last_seen_frame < options_.candidate_gap_frames) continue;
    ekf_.remove_landmark(id);
    e.restart_streak(0);
  }
}

// The L-map's record of a sighting: world position g(R, y) and its covariance.
void Robot::record_sighting(int id, const RangeBearing& z) {
  LMapEntry& e = lmap_[id];
  Eigen::Matrix<double, 2, 3> Gx;
  Eigen::Matrix2d Gz;
  e.position = inverse_observe(ekf_.pose(), z, &Gx, &Gz);
  e.cov = Gx * ekf_.pose_cov() * Gx.transpose() + Gz * ekf_.measurement_cov() * Gz.transpose();
}

// Step 4: a STATIC landmark well inside the field of view that has not been seen
// for missing_needed_ frames has left: `missing_frames`, or more for a sensor that
// misses landmarks (detection_probability < 1), so that a present landmark goes
// unreported that long only with the ELA gate's false-alarm probability. The field
// of view is the disc of sensor_range_m, or the cone of +-fov_half_angle_deg in it,
// shrunk by fov_margin_m at its edges.
void Robot::check_missing(FrameSummary* s) {
  if (options_.missing_frames <= 0) return;
  const Pose2 pose = ekf_.pose();
  const double expect_range = options_.sensor_range - options_.fov_margin;
  const bool cone = options_.fov_half_angle < kPi;
  for (int slot = ekf_.num_landmarks() - 1; slot >= 0; --slot) {
    const int id = ekf_.id_at(slot);
    LMapEntry& e = lmap_[id];
    if (e.status != LandmarkStatus::kStatic) continue;
    if (e.last_seen_frame == last_frame_) {
      e.missing_frames = 0;
      continue;
    }
    const Eigen::Vector2d d = ekf_.landmark(id) - pose.translation();
    const double range = d.norm();
    bool expected = range < expect_range;
    if (expected && cone) {
      const double bearing = wrap_angle(std::atan2(d.y(), d.x()) - pose.theta);
      expected = std::fabs(bearing) < options_.fov_half_angle - options_.fov_margin / std::max(range, 1e-3);
    }
    if (!expected) {
      e.missing_frames = 0;
      continue;
    }
    if (++e.missing_frames >= missing_needed_) mark_moving(id, nullptr, s);
  }
}

// Remove a landmark as moving; it may come back as a candidate when it stops.
void Robot::mark_moving(int id, const Observation* seen, FrameSummary* s) {
  const Eigen::Vector2d last = ekf_.landmark(id);
  const Eigen::Matrix2d last_cov = ekf_.landmark_cov(id);
  if (ekf_.remove_landmark(id) != EkfStatus::kOk) {
    ++s->filter_faults;
    return;
  }
  LMapEntry& e = lmap_[id];
  e.was_moving = e.reported_moving = true;
  ++e.times_moving;
  e.missing_frames = 0;
  out_count_[static_cast<std::size_t>(id)] = 0;
  handled_[static_cast<std::size_t>(id)] = last_frame_;
  if (seen) {  // re-anchored as a candidate where it is now
    record_sighting(id, seen->z);
    lmap_.set_status(id, LandmarkStatus::kCandidate, last_frame_);
    e.restart_streak(1);
    if (ekf_.add_landmark(id, seen->z) != EkfStatus::kOk) ++s->filter_faults;
  } else {
    lmap_.set_status(id, LandmarkStatus::kMoving, last_frame_);
  }
  emit_at(EventKind::kMoving, id, last, last_cov);
  ++s->num_moving;
}

double Robot::map_mean_diag() const {
  // Block accessors only: covariance() would complete the whole matrix.
  double sum = ekf_.pose_cov().trace();
  int n = StateLayout::kPoseDim;
  for (int slot = 0; slot < ekf_.num_landmarks(); ++slot) {
    const int id = ekf_.id_at(slot);
    if (lmap_[id].status != LandmarkStatus::kStatic) continue;
    sum += ekf_.landmark_cov(id).trace();
    n += StateLayout::kLandmarkDim;
  }
  return sum / n;
}

bool Robot::apply_notice(int landmark_id, int frame) {
  if (!lmap_.valid_id(landmark_id)) return false;
  LMapEntry& e = lmap_[landmark_id];
  e.was_moving = e.reported_moving = true;  // coming back needs return_frames consistent sightings
  ++e.times_moving;
  if (!ekf_.has_landmark(landmark_id)) return false;
  const bool held = e.status == LandmarkStatus::kStatic;
  if (ekf_.remove_landmark(landmark_id) != EkfStatus::kOk) return false;
  lmap_.set_status(landmark_id, LandmarkStatus::kMoving, frame);
  e.restart_streak(0);
  e.missing_frames = 0;
  out_count_[static_cast<std::size_t>(landmark_id)] = 0;
  return held;
}

void Robot::emit(EventKind kind, int id) {
  lmap_[id].reported_frame = last_frame_;
  emit_at(kind, id, ekf_.landmark(id), ekf_.landmark_cov(id));
}

void Robot::emit_at(EventKind kind, int id, const Eigen::Vector2d& p, const Eigen::Matrix2d& C) {
  if (events_.size() >= events_.capacity()) {  // never grow: the buffer is sized for a frame
    ++events_dropped_;
    return;
  }
  events_.push_back({kind, id, last_frame_, p, C});
}

}  // namespace elaslam

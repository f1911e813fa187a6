// SPDX-License-Identifier: Apache-2.0
#include "elaslam/common/contract.hpp"
#include "elaslam/robot_node/robot_options.hpp"

#include "elaslam/common/geometry.hpp"

namespace elaslam {

const char* to_string(Mode m) {
  switch (m) {
    case Mode::kEkf: return "ekf";
    case Mode::kGated: return "gated";
    case Mode::kEla: return "ela";
    case Mode::kConsensus: return "consensus";
  }
  return "?";
}

bool parse_mode(const std::string& s, Mode* m) {
  for (Mode c : {Mode::kEkf, Mode::kGated, Mode::kEla, Mode::kConsensus})
    if (s == to_string(c)) {
      *m = c;
      return true;
    }
  return false;
}

namespace {

// A key in degrees for an angle the options keep in radians.
void read_degrees(config::Reader& r, const std::string& key, double* radians, double lo, double hi, bool optional) {
  double degrees = rad2deg(*radians);
  if (optional) {
    r.read_optional(key, &degrees, lo, hi);
  } else {
    r.read(key, &degrees, lo, hi);
  }
  *radians = deg2rad(degrees);
}

void parse_filter(config::Reader& f, RobotOptions* o) {
  f.read("capacity", &o->ekf.capacity, 1, 1024);
  f.read_optional("max_observations", &o->max_observations, 1, contract::kMaxObsPerFrameLimit);
  f.read("max_landmark_id", &o->ekf.max_landmark_id, 1, contract::kMaxLandmarkIdLimit);
  f.read("range_sigma_m", &o->ekf.range_sigma, 1e-6, 100.0);
  read_degrees(f, "bearing_sigma_deg", &o->ekf.bearing_sigma, 1e-6, 90.0, false);
  f.read("gate_probability", &o->ekf.gate_probability, 0.5, 1.0 - 1e-9);
  f.read_optional("joseph", &o->ekf.joseph);
  f.read("initial_sigma_xy_m", &o->initial_sigma_xy, 0.0, 100.0);
  read_degrees(f, "initial_sigma_theta_deg", &o->initial_sigma_theta, 0.0, 180.0, false);
}

void parse_ela(config::Reader& e, RobotOptions* o) {
  e.read("gate_probability", &o->ela_gate_probability, 0.5, 1.0 - 1e-9);
  e.read("confirm_frames", &o->confirm_frames, 1, 1000);
  e.read_optional("confirm_frames_few", &o->confirm_frames_few, 0, 1000);
  e.read("return_frames", &o->return_frames, 1, 1000);
  e.read_optional("return_backoff", &o->return_backoff);
  e.read_optional("candidate_updates", &o->candidate_updates);
  e.read_optional("candidate_drift_test", &o->candidate_drift_test);
  e.read_optional("candidate_history_frames", &o->candidate_history_frames, 0, 100);
  e.read_optional("drift_memory", &o->drift_memory, 0.0, 0.99);
  e.read_optional("drift_gate_probability", &o->drift_gate_probability, 0.5, 1.0 - 1e-12);
  e.read_optional("candidate_gap_frames", &o->candidate_gap_frames, 1, 1000);
  e.read("moving_after", &o->moving_after, 1, 1000);
  e.read_optional("lone_verdicts", &o->lone_verdicts);
  e.read_optional("lone_needs_check", &o->lone_needs_check);
  e.read("missing_frames", &o->missing_frames, 0, 1000);
  e.read("sensor_range_m", &o->sensor_range, 0.01, 1000.0);
  e.read("fov_margin_m", &o->fov_margin, 0.0, 1000.0);
  double half_deg = 180.0;  // all around unless the key says otherwise
  e.read_optional("fov_half_angle_deg", &half_deg, 1.0, 180.0);
  o->fov_half_angle = half_deg >= 180.0 ? kPi : deg2rad(half_deg);
  e.read_optional("detection_probability", &o->detection_probability, 0.01, 1.0);
  if (o->fov_margin >= o->sensor_range)
    e.fail("fov_margin_m", "must be smaller than sensor_range_m, or no landmark is ever expected in view");
}

void parse_node(config::Reader& n, RobotOptions* o) {
  n.read("snapshot_period_frames", &o->snapshot_period_frames, 1, 100000);
  n.read("update_period_frames", &o->update_period_frames, 1, 100000);
  n.read_optional("candidates_period_frames", &o->candidates_period_frames, 0, 100000);
  n.read_optional("batch_events", &o->batch_events);
  n.read("max_frame_gap", &o->max_frame_gap, 1, 100000);
  n.read_optional("late_start_step_m", &o->late_start_step_m, 0.0, 100.0);
  read_degrees(n, "late_start_turn_deg", &o->late_start_turn, 0.0, 180.0, true);
  n.read_optional("state_save_interval_s", &o->state_save_interval_s, 0.0, 3600.0);
  n.read_optional("max_step_m", &o->max_step_m, 1e-3, 1e4);
  read_degrees(n, "max_turn_deg", &o->max_turn, 1e-3, 360.0, true);
  n.read_optional("odometry_reanchor_frames", &o->odometry_reanchor_frames, 1, 1000);
  n.read_optional("confirm_jump_frames", &o->confirm_jump_frames, 1, 100000);
  n.read_optional("main_silent_s", &o->main_silent_s, 0.0, 3600.0);
  if (o->confirm_jump_frames > o->max_frame_gap)
    n.fail("confirm_jump_frames", "larger than max_frame_gap: a jump that far is refused anyway");
}

void parse_consistency(config::Reader& c, RobotOptions* o) {
  c.read("window_frames", &o->consistency_window_frames, 0, 100000);
  c.read_optional("probability", &o->consistency_probability, 0.5, 1.0 - 1e-12);
  c.read_optional("recover", &o->consistency_recover);
  c.read_optional("recovery_sigma_xy_m", &o->recovery_sigma_xy, 0.0, 100.0);
  read_degrees(c, "recovery_sigma_theta_deg", &o->recovery_sigma_theta, 0.0, 180.0, true);
}

// The odometer's calibration states (EkfSlam, CalibrationOptions): prior mean and
// std dev, random walk per sqrt(second). All sigmas and walks 0 (the defaults):
// frozen at the means.
void parse_calibration(config::Reader& c, CalibrationOptions* k) {
  c.read_optional("turn_scale", &k->prior.turn_scale, 0.5, 2.0);
  c.read_optional("turn_scale_sigma", &k->turn_scale_sigma, 0.0, 1.0);
  c.read_optional("turn_scale_walk_per_sqrt_s", &k->turn_scale_walk, 0.0, 1.0);
  c.read_optional("speed_scale", &k->prior.speed_scale, 0.5, 2.0);
  c.read_optional("speed_scale_sigma", &k->speed_scale_sigma, 0.0, 1.0);
  c.read_optional("speed_scale_walk_per_sqrt_s", &k->speed_scale_walk, 0.0, 1.0);
  c.read_optional("turn_bias_rad_s", &k->prior.turn_bias, -1.0, 1.0);
  c.read_optional("turn_bias_sigma_rad_s", &k->turn_bias_sigma, 0.0, 1.0);
  c.read_optional("turn_bias_walk_rad_s_per_sqrt_s", &k->turn_bias_walk, 0.0, 1.0);
}

void parse_team_map(config::Reader& t, RobotOptions* o) {
  t.read("fuse", &o->team_map_fuse);
  t.read_optional("min_gain", &o->team_map_min_gain, 0.0, 100.0);
  t.read_optional("gate_probability", &o->team_map_gate_probability, 0.5, 1.0);
  t.read_optional("gauge_test", &o->team_map_gauge_test);
  t.read_optional("drift_check", &o->team_map_drift_check);
  t.read_optional("hold_candidates", &o->team_map_hold_candidates);
}

// The moving landmarks' tracks (MoverTracks, MoverTrack; docs/tracking.md).
void parse_tracking(config::Reader& t, TrackingOptions* o) {
  t.read_optional("enabled", &o->enabled);
  t.read_optional("max_tracks", &o->max_tracks, 0, 4096);
  t.read_optional("lost_after_s", &o->lost_after_s, 1e-3, 3600.0);
  t.read_optional("return_when_stopped", &o->return_when_stopped);
  t.read_optional("correct_pose", &o->correct_pose);
  MoverTrackOptions& k = o->track;
  t.read_optional("model_sojourn_s", &k.model_sojourn_s, 1e-3, 3600.0);
  t.read_optional("static_walk_m_per_sqrt_s", &k.static_walk_m_per_sqrt_s, 1e-9, 10.0);
  t.read_optional("bounded_sigma_m", &k.bounded_sigma_m, 1e-3, 100.0);
  t.read_optional("bounded_omega_rad_s", &k.bounded_omega_rad_s, 1e-3, 100.0);
  t.read_optional("bounded_damping", &k.bounded_damping, 1e-3, 10.0);
  t.read_optional("cv_accel_sigma", &k.cv_accel_sigma, 1e-6, 100.0);
  t.read_optional("initial_speed_sigma_mps", &k.initial_speed_sigma_mps, 1e-6, 100.0);
  t.read_optional("validation_sightings", &k.validation_sightings, 1, MoverTrack::kMaxValidationSightings);
  t.read_optional("validation_probability", &k.validation_probability, 0.5, 1.0 - 1e-12);
  t.read_optional("restart_probability", &k.restart_probability, 0.5, 1.0 - 1e-12);
  t.read_optional("adapt_noise", &k.adapt_noise);
  t.read_optional("noise_memory_sightings", &k.noise_memory_sightings, 1.0, 1000.0);
  t.read_optional("max_noise_scale", &k.max_noise_scale, 1.0, 1e6);
}

}  // namespace

void parse(config::Reader& r, RobotOptions* o) {
  std::string mode = to_string(o->mode);
  r.read_enum("mode", &mode, {"ekf", "gated", "ela", "consensus"});
  parse_mode(mode, &o->mode);
  r.section("filter", [&](config::Reader& f) { parse_filter(f, o); });
  r.section("ela", [&](config::Reader& e) { parse_ela(e, o); });
  r.section("node", [&](config::Reader& n) { parse_node(n, o); });
  r.section("consistency", [&](config::Reader& c) { parse_consistency(c, o); }, /*optional=*/true);
  r.section("odometry_calibration", [&](config::Reader& c) { parse_calibration(c, &o->ekf.calibration); },
            /*optional=*/true);
  r.section("team_map", [&](config::Reader& t) { parse_team_map(t, o); }, /*optional=*/true);
  r.section("tracking", [&](config::Reader& t) { parse_tracking(t, &o->tracking); }, /*optional=*/true);
  parse(r, &o->limits);
  if (o->ekf.capacity > o->ekf.max_landmark_id)
    r.fail("filter.capacity", "larger than filter.max_landmark_id: slots that can never be used");
}

std::string config_advice(const RobotOptions& o) {
  if (o.lone_needs_check && !o.team_map_fuse && (o.mode == Mode::kEla || o.mode == Mode::kConsensus))
    return "robot.ela.lone_needs_check is on while robot.team_map.fuse is off: a robot without the team map "
           "needs every lone correction (docs/mrclam.md): turn lone_needs_check off, or the team map on";
  return "";
}

RobotOptions load_robot_options(const std::string& path, std::string* effective_yaml) {
  config::Document doc = config::Document::from_file(path);
  RobotOptions o = config::read_component<RobotOptions>(doc, "robot");
  if (auto problems = check_shared_config(path); !problems.empty()) throw config::ConfigError(path, std::move(problems));
  if (effective_yaml) *effective_yaml = doc.effective_yaml();
  return o;
}

}  // namespace elaslam

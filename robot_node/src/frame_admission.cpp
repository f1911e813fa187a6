// SPDX-License-Identifier: Apache-2.0
#include "elaslam/robot_node/frame_admission.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "elaslam/common/contract.hpp"

namespace elaslam {
namespace {

constexpr double kMaxRange = 1e4;       // [m] anything beyond is a corrupt message
constexpr double kMaxOdomVar = 1e3;     // [m^2/m], [rad^2/rad]: sanity bound on the noise model
constexpr double kBearingSlack = 1e-9;  // [rad] tolerance on [-pi, pi]

bool finite(double v) { return std::isfinite(v); }

}  // namespace

FrameAdmission::FrameAdmission(const RobotOptions& options, int robot_id) : options_(options), robot_id_(robot_id) {
  id_seen_.assign(static_cast<std::size_t>(options.ekf.max_landmark_id), 0);
}

std::string FrameAdmission::validate(const sensor_frame_t& m, Refusal* reason) const {
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

std::string FrameAdmission::check_duplicate_ids(const sensor_frame_t& msg, Refusal* reason) {
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

bool FrameAdmission::breaks_from_last(const sensor_frame_t& msg) const {
  return msg.frame < last_frame_ || std::int64_t{msg.frame} - last_frame_ > options_.confirm_jump_frames;
}

FrameAdmission::Order FrameAdmission::order(const sensor_frame_t& msg) {
  if (msg.frame == last_frame_) return Order::kDuplicate;
  if (msg.frame < last_frame_) {
    ++behind_;  // with none processed since: a source that started over (frames_behind)
    return Order::kOlder;
  }
  return Order::kNewer;
}

// Frames further ahead than confirm_jump_frames wait for the next frame to confirm
// them (JumpGuard); odometer increments beyond what the robot can drive in the
// frames elapsed are refused, and re-anchored on once odometry_reanchor_frames
// readings in a row continue the jump (a real change of the odometer's origin).
std::string FrameAdmission::check_progress(const sensor_frame_t& msg, const Robot& robot, bool* reanchor,
                                           Refusal* reason) {
  *reanchor = false;
  if (last_frame_ < 0 || !robot.initialised()) return "";
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
  if (within(robot.last_odometer(), ahead)) {
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
    *reanchor = true;
    odo_candidate_frame_ = -1;
    odo_streak_ = 0;
    return "";
  }
  const Pose2 d = between(robot.last_odometer(), reading);
  *reason = Refusal::kOdometry;
  std::ostringstream os;
  os << "odometer moved " << std::hypot(d.x, d.y) << " m and " << rad2deg(std::fabs(d.theta)) << " deg in " << ahead
     << " frame(s), beyond node.max_step_m " << options_.max_step_m << " / max_turn_deg " << rad2deg(options_.max_turn)
     << " per frame (frame " << msg.frame << "; re-anchored after " << options_.odometry_reanchor_frames
     << " consistent readings)";
  return os.str();
}

}  // namespace elaslam

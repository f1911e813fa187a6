// SPDX-License-Identifier: Apache-2.0
#include "elaslam/transport/team_progress.hpp"

#include <cstdio>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/common/faults.hpp"
#include "elaslam/transport/node_shell.hpp"

namespace elaslam::transport {
namespace {

template <typename Msg, typename Fn>
void on(NodeShell& shell, const std::string& channel, int queue, Fn fn) {
  shell.subscribe<Msg>(channel, [fn](const Msg& m, const std::string&) { fn(m); }, queue);
}

}  // namespace

void TeamProgress::subscribe(NodeShell& shell) {
  const std::string& sfx = shell.suffix();
  on<run_info_t>(shell, channels::run_info(sfx), 10, [this](const run_info_t& m) { on_run_info(m); });
  on<sensor_frame_t>(shell, channels::any_sensor(sfx), 200, [this](const sensor_frame_t& m) { on_sensor(m); });
  on<pose_estimate_t>(shell, channels::any_pose(sfx), 200, [this](const pose_estimate_t& m) { on_pose(m); });
  on<global_map_t>(shell, channels::global_map(sfx), 20, [this](const global_map_t& m) { on_global_map(m); });
  on<dynamic_notice_t>(shell, channels::dynamic_notice(sfx), 200, [this](const dynamic_notice_t& m) { on_notice(m); });
  on<node_status_t>(shell, channels::any_status_robot(sfx), 50,
                    [this](const node_status_t& m) { on_robot_status(m); });
  on<node_status_t>(shell, channels::status_main(sfx), 10, [this](const node_status_t& m) { on_main_status(m); });
}

void TeamProgress::on_run_info(const run_info_t& m) {
  if (m.frames > 0) frames_ = m.frames;
}

void TeamProgress::on_sensor(const sensor_frame_t& m) {
  if (m.frame > frame_) frame_ = m.frame;
}

void TeamProgress::on_pose(const pose_estimate_t& m) {
  ++poses_;
  pose_robots_.insert(m.robot_id);
}

void TeamProgress::on_global_map(const global_map_t& m) {
  for (int i = 0; i < contract::bounded(m.num_moving, static_cast<int>(m.moving_ids.size())); ++i)
    moving_.insert(m.moving_ids[i]);
}

void TeamProgress::on_notice(const dynamic_notice_t& m) {
  ++notices_;
  moving_.insert(m.landmark_id);
}

void TeamProgress::on_robot_status(const node_status_t& m) {
  dropped_by_robot_[m.node_id] = m.frames_dropped;
  // The odometer's calibration, when the robot estimates it (robot.odometry_calibration).
  if (m.odom_turn_scale_sigma > 0.0f || m.odom_speed_scale_sigma > 0.0f || m.odom_turn_bias_sigma_rad_s > 0.0f)
    calibration_[m.node_id] = {m.odom_turn_scale, m.odom_speed_scale};
  dropped_ = 0;
  for (const auto& [id, n] : dropped_by_robot_) dropped_ += n;
  note_health("robot " + std::to_string(m.node_id), m);
}

void TeamProgress::on_main_status(const node_status_t& m) { note_health("main", m); }

void TeamProgress::note_health(const std::string& node, const node_status_t& m) {
  Health& h = health_[node];
  h.refused = 0;
  for (std::int64_t n : m.refused) h.refused += n;
  h.faults = m.fault_flags;
}

std::string TeamProgress::line(const NodeShell& shell) const {
  return line(shell.counters().inputs.decode_errors, shell.counters().auth_refused);
}

std::string TeamProgress::line(long long undecodable, long long auth_refused) const {
  if (frame_ < 0) return "waiting for the first frame" + std::string(frames_ > 0 ? " of " + std::to_string(frames_) : "");
  char buf[512];
  const std::string of = frames_ > 0 ? "/" + std::to_string(frames_) : "";
  // Frames are numbered from 0: after frame k, k + 1 are done ("frame 150/150").
  std::snprintf(buf, sizeof buf, "frame %d%s | poses %lld from %zu robot%s | moving landmarks found %zu | notices %lld",
                frame_ + 1, of.c_str(), poses_, pose_robots_.size(), pose_robots_.size() == 1 ? "" : "s",
                moving_.size(), notices_);
  std::string out = buf;
  if (dropped_ > 0) out += " | robots report " + std::to_string(dropped_) + " dropped frames";
  if (undecodable > 0) out += " | undecodable " + std::to_string(undecodable);
  if (auth_refused > 0) out += " | refused (authentication) " + std::to_string(auth_refused);
  long long refused = 0;
  std::string faults;  // "FAULT robot 2: frames lost, main silent"
  for (const auto& [node, h] : health_) {
    refused += h.refused;
    std::string names;
    for (const std::string& n : fault_names(h.faults)) names += (names.empty() ? "" : ", ") + n;
    if (!names.empty()) faults += " | FAULT " + node + ": " + names;
  }
  if (refused > 0) out += " | messages refused " + std::to_string(refused);
  if (!calibration_.empty()) {
    out += " | odometer turn/speed scale:";
    for (const auto& [id, c] : calibration_) {
      char s[64];
      std::snprintf(s, sizeof s, " robot %d %.3f/%.3f", id, static_cast<double>(c[0]), static_cast<double>(c[1]));
      out += s;
    }
  }
  return out + faults;
}

}  // namespace elaslam::transport

// SPDX-License-Identifier: Apache-2.0
#include "frame_assembler.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>

#include "elaslam/common/geometry.hpp"

namespace elaslam::examples {

FrameAssembler::FrameAssembler(const AssemblerOptions& options, Emit emit) : options_(options), emit_(std::move(emit)) {
  obs_.reserve(static_cast<std::size_t>(options_.max_observations) + 1);
  msg_.obs.reserve(static_cast<std::size_t>(options_.max_observations));
}

void FrameAssembler::advance_to(double t) {
  if (!started_) {
    started_ = true;
    t0_ = t;
    frame_ = 0;
    return;
  }
  while (t >= frame_start(frame_ + 1)) emit_current();
}

double FrameAssembler::frame_start(std::int64_t k) const { return t0_ + static_cast<double>(k) / options_.rate_hz; }

bool FrameAssembler::take_time(double t) {
  if (started_ && t < frame_start(frame_)) {  // older than the frame being filled
    ++counters_.out_of_order;
    return false;
  }
  advance_to(t);
  return true;
}

void FrameAssembler::emit_current() {
  // The nearest observations when there are too many (the far ones carry the least).
  if (static_cast<int>(obs_.size()) > options_.max_observations) {
    std::sort(obs_.begin(), obs_.end(), [](const range_bearing_t& a, const range_bearing_t& b) { return a.range < b.range; });
    counters_.over_capacity += static_cast<std::int64_t>(obs_.size()) - options_.max_observations;
    obs_.resize(static_cast<std::size_t>(options_.max_observations));
  }
  msg_.utime = static_cast<std::int64_t>(std::llround(frame_start(frame_ + 1) * 1e6));
  msg_.frame = static_cast<std::int32_t>(frame_);
  msg_.robot_id = static_cast<std::int16_t>(options_.robot_id);
  msg_.odom_x = odom_[0];
  msg_.odom_y = odom_[1];
  msg_.odom_theta = odom_[2];
  msg_.odom_var_trans_per_m = options_.odom_var_trans_per_m;
  msg_.odom_var_rot_per_rad = options_.odom_var_rot_per_rad;
  msg_.odom_var_rot_per_m = options_.odom_var_rot_per_m;
  msg_.num_obs = static_cast<std::int16_t>(obs_.size());
  msg_.obs.assign(obs_.begin(), obs_.end());
  if (!have_odom_) ++counters_.frames_without_odometry;
  if (obs_.empty()) ++counters_.empty_frames;
  counters_.detections += static_cast<std::int64_t>(obs_.size());
  ++counters_.frames;
  emit_(msg_);
  obs_.clear();
  ++frame_;
}

void FrameAssembler::odometry(double t, double x, double y, double theta) {
  if (!std::isfinite(t) || !std::isfinite(x) || !std::isfinite(y) || !std::isfinite(theta)) {
    ++counters_.bad_lines;
    return;
  }
  if (!take_time(t)) return;
  odom_[0] = x, odom_[1] = y, odom_[2] = wrap_angle(theta);
  have_odom_ = true;
}

void FrameAssembler::detection(double t, int id, double range, double bearing) {
  if (!std::isfinite(t)) {
    ++counters_.bad_lines;
    return;
  }
  if (id < 0 || id >= options_.max_landmark_id || !std::isfinite(range) || range <= 0.0 ||
      range > options_.max_range_m || !std::isfinite(bearing)) {
    ++counters_.bad_detections;
    return;
  }
  if (!take_time(t)) return;
  range_bearing_t o{};
  o.landmark_id = id, o.range = range, o.bearing = wrap_angle(bearing);
  for (auto& seen : obs_) {
    if (seen.landmark_id == id) {  // the contract allows one sighting per landmark per frame
      seen = o;
      ++counters_.repeated_in_frame;
      return;
    }
  }
  obs_.push_back(o);
}

bool FrameAssembler::line(const std::string& text) {
  std::istringstream in(text);
  std::string kind;
  if (!(in >> kind) || kind[0] == '#') return true;
  double t = 0.0, a = 0.0, b = 0.0, c = 0.0;
  std::string rest;
  if (kind == "odom" && (in >> t >> a >> b >> c) && !(in >> rest)) {
    odometry(t, a, b, c);
    return true;
  }
  long long id = 0;
  if (kind == "det" && (in >> t >> id >> a >> b) && !(in >> rest) && id >= -1 && id <= 1'000'000'000LL) {
    detection(t, static_cast<int>(id), a, b);
    return true;
  }
  ++counters_.bad_lines;
  return false;
}

void FrameAssembler::flush() {
  if (started_) emit_current();
}

}  // namespace elaslam::examples

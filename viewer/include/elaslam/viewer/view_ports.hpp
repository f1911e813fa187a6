// SPDX-License-Identifier: Apache-2.0
// The viewer's inputs on the message layer (transport/node_shell.hpp): RUN_INFO,
// POSE_<r>, GLOBAL_MAP, DYNAMIC_NOTICE, STATUS_ROBOT_<r>, CANDIDATES_<r>, TRACKS_<r>,
// GLOBAL_TRACKS and GROUND_TRUTH into a ViewState, on bounded queues. The viewer process and the fuzz
// target (fuzz/fuzz_viewer.cpp) both run this. It publishes nothing.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <string>

#include "elaslam/common/channels.hpp"
#include "elaslam/viewer/view_state.hpp"

namespace elaslam::viewer {

template <class Shell>
class ViewPorts {
 public:
  ViewPorts(Shell& shell, ViewState& state) : shell_(shell), state_(state), t0_(std::chrono::steady_clock::now()) {}

  /// Subscribe every input; false when the transport refused one.
  bool open() {
    const std::string& sfx = shell_.suffix();
    bool ok = true;
    ok &= on<run_info_t>(channels::run_info(sfx), 10, [this](const run_info_t& m) { state_.on_run_info(m); });
    ok &= on<pose_estimate_t>(channels::any_pose(sfx), 200, [this](const pose_estimate_t& m) { on_pose(m); });
    ok &= on<global_map_t>(channels::global_map(sfx), 100, [this](const global_map_t& m) { state_.on_global_map(m); });
    ok &= on<dynamic_notice_t>(channels::dynamic_notice(sfx), 200,
                               [this](const dynamic_notice_t& m) { state_.on_notice(m); });
    ok &= on<node_status_t>(channels::any_status_robot(sfx), 50,
                            [this](const node_status_t& m) { state_.on_status(m, now_s()); });
    ok &= on<candidate_list_t>(channels::any_candidates(sfx), 100,
                               [this](const candidate_list_t& m) { state_.on_candidates(m); });
    ok &= on<track_list_t>(channels::any_tracks(sfx), 100, [this](const track_list_t& m) { state_.on_tracks(m); });
    ok &= on<global_tracks_t>(channels::global_tracks(sfx), 100,
                              [this](const global_tracks_t& m) { state_.on_global_tracks(m); });
    ok &= on<ground_truth_t>(channels::ground_truth(sfx), 20, [this](const ground_truth_t& m) { state_.on_truth(m); });
    return ok;
  }

  /// POSE frames a robot skipped: what LCM dropped from a full queue (or the robot
  /// did not publish), the viewer's `queue_drops`.
  long long missed_poses() const { return missed_poses_; }
  double now_s() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count(); }

 private:
  template <typename Msg, typename Fn>
  bool on(const std::string& channel, int queue, Fn fn) {
    return shell_.template subscribe<Msg>(channel, [fn](const Msg& m, const std::string&) { fn(m); }, queue) > 0;
  }

  void on_pose(const pose_estimate_t& m) {
    if (!state_.on_pose(m)) return;
    auto it = last_pose_frame_.find(m.robot_id);
    if (it != last_pose_frame_.end() && m.frame > it->second + 1) missed_poses_ += m.frame - it->second - 1;
    last_pose_frame_[m.robot_id] = m.frame;
  }

  Shell& shell_;
  ViewState& state_;
  std::chrono::steady_clock::time_point t0_;
  std::map<int, int> last_pose_frame_;  // robot ids 1..ViewState::kMaxRobots: bounded
  long long missed_poses_ = 0;
};

}  // namespace elaslam::viewer

// SPDX-License-Identifier: Apache-2.0
// A MainNode on the message layer: the channels it reads and writes, the receive
// queues' bounds. The main_robot process and the in-process team run both wire their
// MainNode with MainPorts.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <string>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/log.hpp"
#include "elaslam/main_robot/main_node.hpp"

namespace elaslam {

/// Receive queue bounds of main_robot's inputs (LCM's default of 30 drops silently:
/// LCM.md). Events come in bursts (one per observed landmark per robot per frame): a
/// deep queue, on purpose; losses show up as seq gaps and snapshots repair them.
struct MainQueues {
  int event = 10000;
  int events = 1000;  // LMAP_EVENTS: one message per robot per frame
  int snapshot = 100;
  int pose = 1000;
  int tracks = 1000;  // TRACKS_<r>: one message per robot per frame while it tracks movers
};

/// A MainNode on the message layer (transport/node_shell.hpp): receives LMAP_EVENT,
/// LMAP_EVENTS, LMAP_SNAPSHOT and every robot's POSE_<r> and TRACKS_<r>; publishes
/// GLOBAL_TRACKS with every GLOBAL_MAP; DYNAMIC_NOTICE as soon as an
/// event or snapshot produces one, GLOBAL_MAP for frame k as soon as every robot seen
/// so far has finished k (its POSE marks the end of its frame and says up to which
/// event seq the frame goes: the frame is finished when those events are applied),
/// and GLOBAL_MAP / STATUS_MAIN on request. The main_robot process and
/// the in-process team run both run this. A template on the shell only so that this
/// library builds without the transport; Shell is NodeShell.
template <class Shell>
class MainPorts {
 public:
  MainPorts(Shell& shell, MainNode& node)
      : shell_(shell),
        node_(node),
        map_(channels::global_map(shell.suffix())),
        moving_(channels::global_moving(shell.suffix())),
        notice_(channels::dynamic_notice(shell.suffix())),
        status_(channels::status_main(shell.suffix())),
        resync_(channels::lmap_resync(shell.suffix())),
        tracks_(channels::global_tracks(shell.suffix())) {
    for (int r = 1; r <= kMaxTeamRobots; ++r) team_map_[static_cast<std::size_t>(r - 1)] = channels::team_map(r, shell.suffix());
  }

  /// Subscribe the inputs; false when the transport refused.
  bool open(const MainQueues& queues = {}) {
    shell_.on_decode_error([this] { node_.count_decode_error(); });
    const std::string& sfx = shell_.suffix();
    const int e = shell_.template subscribe<landmark_event_t>(
        channels::lmap_event(sfx), [this](const landmark_event_t& m, const std::string&) { on_event(m); }, queues.event);
    const int b = shell_.template subscribe<lmap_events_t>(
        channels::lmap_events(sfx), [this](const lmap_events_t& m, const std::string&) { on_events(m); }, queues.events);
    const int s = shell_.template subscribe<lmap_snapshot_t>(
        channels::lmap_snapshot(sfx), [this](const lmap_snapshot_t& m, const std::string&) { on_snapshot(m); },
        queues.snapshot);
    const int p = shell_.template subscribe<pose_estimate_t>(
        channels::any_pose(sfx), [this](const pose_estimate_t& m, const std::string&) { on_pose(m); }, queues.pose);
    const int t = shell_.template subscribe<track_list_t>(
        channels::any_tracks(sfx), [this](const track_list_t& m, const std::string&) { on_tracks(m); }, queues.tracks);
    return e > 0 && b > 0 && s > 0 && p > 0 && t > 0;
  }

  /// GLOBAL_MAP now, stamped `frame` (default: the newest frame every robot has finished).
  /// With main.team_map_period_frames, every robot heard from also gets its team
  /// map (TEAM_MAP_<r>) when one is due for `frame`.
  void publish_map(int frame = -1) {
    last_map_utime_ = shell_.now_utime();
    const int n = node_.make_global_map(last_map_utime_, frame);
    for (int i = 0; i < n; ++i) shell_.publish(map_, node_.map_chunk(i));
    const int t = node_.make_global_tracks(last_map_utime_, frame);
    for (int i = 0; i < t; ++i) shell_.publish(tracks_, node_.global_tracks(i));
    const int k = node_.make_moving_set(last_map_utime_, frame);
    if (node_.moving_set_due(k, last_map_utime_))
      for (int i = 0; i < k; ++i) shell_.publish(moving_, node_.map_chunk(i));
    if (!node_.team_map_due(frame)) return;
    for (int r = 1; r <= kMaxTeamRobots; ++r) {
      if (!node_.robot_seen(r)) continue;
      const int m = node_.make_team_map(r, shell_.now_utime(), frame);
      for (int i = 0; i < m; ++i) shell_.publish(team_map_[static_cast<std::size_t>(r - 1)], node_.map_chunk(i));
    }
  }
  /// The timer's GLOBAL_MAP (main.publish_rate_hz): only when no map went out in the
  /// last `period_us`. While the team's frames finish, each finished frame publishes
  /// its map and the timer adds none (a second one every period would double the map
  /// traffic at 10 Hz, docs/benchmarks.md "Scale"); when they stall (a robot
  /// down, POSEs lost) the timer keeps the map going out.
  void publish_map_if_quiet(std::int64_t period_us) {
    if (last_map_utime_ != kNever && shell_.now_utime() - last_map_utime_ < period_us) return;
    publish_map();
  }
  void publish_status() {
    node_status_t m = node_.status_msg(shell_.now_utime());
    shell_.stamp_auth(&m);
    shell_.publish(status_, m);
  }

 private:
  void on_event(const landmark_event_t& m) {
    std::string why;
    if (!node_.on_event(m, &why)) shell_.refuse("event refused: " + why);
    send_notices();
    publish_finished();
  }
  void on_events(const lmap_events_t& m) {
    std::string why;
    if (!node_.on_events(m, &why)) shell_.refuse("events refused: " + why);
    send_notices();
    publish_finished();
  }
  void on_snapshot(const lmap_snapshot_t& m) {
    std::string why;
    if (!node_.on_snapshot(m, &why)) shell_.refuse("snapshot refused: " + why);
    send_notices();
    publish_finished();
  }
  /// A held POSE's events are in: that frame's map (MainNode::take_finished).
  void publish_finished() {
    if (const int done = node_.take_finished(); done >= 0) publish_map(done);
  }
  void on_tracks(const track_list_t& m) {
    std::string why;
    if (!node_.on_tracks(m, &why)) shell_.refuse("tracks refused: " + why);
  }
  void on_pose(const pose_estimate_t& m) {
    std::string why;
    const int done = node_.on_pose(m, &why);
    if (!why.empty()) shell_.refuse("pose refused: " + why);
    send_notices();
    if (done >= 0) publish_map(done);
  }
  void send_notices() {
    for (const auto& n : node_.take_notices(shell_.now_utime())) shell_.publish(notice_, n);
    for (const auto& r : node_.take_resyncs(shell_.now_utime())) shell_.publish(resync_, r);
    const std::string alert = node_.take_alert();
    if (!alert.empty()) shell_.say(alert, log::Priority::kWarning);
  }

  static constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::min();
  Shell& shell_;
  MainNode& node_;
  std::int64_t last_map_utime_ = kNever;  // when the last GLOBAL_MAP went out
  const std::string map_, moving_, notice_, status_, resync_, tracks_;  // channel names, built once (tracks_: GLOBAL_TRACKS)
  std::array<std::string, kMaxTeamRobots> team_map_;  // TEAM_MAP_<r>
};

}  // namespace elaslam

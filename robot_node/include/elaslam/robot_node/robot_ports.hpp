// SPDX-License-Identifier: Apache-2.0
// A RobotNode on the message layer: the channels it reads and writes, the receive
// queues' bounds, and where a frame's time goes. The robot_node process and the
// in-process team run both wire their RobotNode with RobotPorts.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <string>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/histogram.hpp"
#include "elaslam/common/log.hpp"
#include "elaslam/robot_node/robot_node.hpp"

namespace elaslam {

/// Receive queue bounds of the robot's inputs. LCM's default of 30 drops silently
/// (LCM.md): both sized on purpose. Lost sensor frames show up as frame gaps, lost
/// notices as seq gaps (RobotNodeCounters::queue_drops).
struct RobotQueues {
  int sensor = 200;
  int notice = 1000;
  int global_map = 1000;  // GLOBAL_MOVING chunks (one per publication unless the moving set is large)
  int resync = 100;
  int own_pose = 100;     // this robot's own POSE (or STATUS) channel: a second sender with this id
  int team_map = 1000;    // TEAM_MAP_<r> chunks (robot.team_map.fuse)
};

/// A RobotNode on the message layer (transport/node_shell.hpp): receives SENSOR_<r>,
/// DYNAMIC_NOTICE, GLOBAL_MAP (the moving set: lost notices repaired), TEAM_MAP_<r>
/// (with robot.team_map.fuse: the other robots' map), LMAP_RESYNC
/// (main_robot asks for a snapshot) and its own POSE_<r> (a second sender with this
/// id); for every processed frame publishes POSE_<r> (the end of the robot's
/// frame; it carries the seq of the frame's last event, event_seq), then its events
/// (LMAP_EVENTS, or one LMAP_EVENT each without robot.node.batch_events) and its
/// LMAP_SNAPSHOT chunks when one is due; STATUS_ROBOT_<r> on request. The robot_node process and the
/// in-process team run both run this, so the live and in-process paths share it.
/// A template on the shell only so that this library builds without the transport
/// (the no-allocation test compiles its sources alone); Shell is NodeShell.
///
/// Where a frame's time goes, per processed frame, wall-clock [us]:
///   receive: the SENSOR's publish stamp (its utime) to this handler: the sender's
///            encode and send, the network, the wake-up and scheduling of this
///            process, LCM's receive thread and queue, decode and the MAC check.
///            Meaningful only when the sender's clock is this one's (one machine,
///            or synchronised clocks); across unsynchronised clocks it is clamped
///            at 0 or absurd.
///   frame:   RobotNode::on_sensor: the filter, the gate, the outgoing messages filled.
///   pose:    the POSE encoded and sent (its utime is stamped just before); first.
///   outputs: then this frame's LMAP_EVENTS (or LMAP_EVENTs), snapshot chunks and
///            CANDIDATES and TRACKS encoded and sent.
struct FrameStages {
  DurationHistogram receive, frame, outputs, pose;
};

/// robot_node's summary at exit, lines each ending in a newline: its counters and
/// frame time, where the frames' time went (p50/p99/max of each FrameStages part
/// [us]), and with robot.team_map_fuse what the other robots' map did.
std::string final_summary(const RobotNode& node, const FrameStages& stages);

template <class Shell>
class RobotPorts {
 public:
  RobotPorts(Shell& shell, RobotNode& node)
      : shell_(shell),
        node_(node),
        event_(channels::lmap_event(shell.suffix())),
        events_(channels::lmap_events(shell.suffix())),
        snapshot_(channels::lmap_snapshot(shell.suffix())),
        pose_(channels::pose(node.robot_id(), shell.suffix())),
        status_(channels::status_robot(node.robot_id(), shell.suffix())),
        candidates_(channels::candidates(node.robot_id(), shell.suffix())),
        tracks_(channels::tracks(node.robot_id(), shell.suffix())) {}

  /// Subscribe the inputs; false when the transport refused.
  bool open(const RobotQueues& queues = {}) {
    shell_.on_decode_error([this] { node_.count_decode_error(); });
    const int sensor = shell_.template subscribe<sensor_frame_t>(
        channels::sensor(node_.robot_id(), shell_.suffix()),
        [this](const sensor_frame_t& m, const std::string&) { on_sensor(m); }, queues.sensor);
    const int notice = shell_.template subscribe<dynamic_notice_t>(
        channels::dynamic_notice(shell_.suffix()), [this](const dynamic_notice_t& m, const std::string&) { on_notice(m); },
        queues.notice);
    // The global map's moving lists (they repair lost notices), in GLOBAL_MOVING: the
    // whole GLOBAL_MAP is tens of kB a frame a robot would decode for them.
    const int map = shell_.template subscribe<global_map_t>(
        channels::global_moving(shell_.suffix()), [this](const global_map_t& m, const std::string&) { on_map(m); },
        queues.global_map);
    const int resync = shell_.template subscribe<resync_request_t>(
        channels::lmap_resync(shell_.suffix()), [this](const resync_request_t& m, const std::string&) { on_resync(m); },
        queues.resync);
    // A second sender with this id shows on this robot's own POSE, every frame; in
    // channel groups on its STATUS, about once a second, as reading POSE_<r> would
    // wake this robot for every robot's POSE (channels.hpp).
    const int own = shell_.transport().channel_groups()
                        ? shell_.template subscribe<node_status_t>(
                              status_, [this](const node_status_t& m, const std::string&) { on_own(status_, m.incarnation, m.frame); },
                              queues.own_pose)
                        : shell_.template subscribe<pose_estimate_t>(
                              pose_, [this](const pose_estimate_t& m, const std::string&) { on_own(pose_, m.incarnation, m.frame); },
                              queues.own_pose);
    int team = 1;
    if (node_.robot().options().team_map_fuse)
      team = shell_.template subscribe<global_map_t>(
          channels::team_map(node_.robot_id(), shell_.suffix()),
          [this](const global_map_t& m, const std::string&) { on_team_map(m); }, queues.team_map);
    return sensor > 0 && notice > 0 && map > 0 && resync > 0 && own > 0 && team > 0;
  }

  void publish_status() {
    node_.check_main(shell_.now_utime());
    say_alert();
    node_status_t m = node_.status_msg(shell_.now_utime());
    shell_.stamp_auth(&m);
    shell_.publish(status_, m);
  }

  /// Called after every processed frame, before its messages go out (the in-process
  /// run reads the frame's gate records there).
  void after_frame(std::function<void(const RobotNode&)> fn) { after_frame_ = std::move(fn); }

  /// Where the processed frames' time went (FrameStages).
  const FrameStages& stages() const { return stages_; }

 private:
  void on_sensor(const sensor_frame_t& msg) {
    std::string why;
    const std::int64_t received = shell_.now_utime();
    const auto v = node_.on_sensor(msg, received, &why);
    if (v == RobotNode::Verdict::kInvalid) shell_.refuse("sensor frame refused: " + why);
    if (v != RobotNode::Verdict::kProcessed) return;
    node_.check_main(received);
    say_alert();
    if (after_frame_) after_frame_(node_);
    // The POSE first: it ends the robot's frame for whoever waits on it (a lockstep
    // simulator, the latency); it carries the seq of the frame's last event, which
    // main_robot waits for before it counts the frame finished.
    pose_estimate_t pose = node_.pose_msg();
    const std::int64_t now = shell_.now_utime();
    pose.utime = now;
    shell_.publish(pose_, pose);
    const std::int64_t posed = shell_.now_utime();
    node_.stamp_events(posed);
    if (node_.robot().options().batch_events)
      for (int i = 0; i < node_.num_event_batches(); ++i) shell_.publish(events_, node_.event_batch(i));
    else
      for (const auto& ev : node_.event_msgs()) shell_.publish(event_, ev);
    if (node_.snapshot_ready()) publish_snapshot();
    if (node_.candidates_ready()) shell_.publish(candidates_, node_.candidates_msg());
    for (int i = 0; i < node_.num_track_chunks(); ++i) shell_.publish(tracks_, node_.track_chunk(i));
    const std::int64_t sent = shell_.now_utime();
    stages_.receive.add(span_us(msg.utime, received));
    stages_.frame.add(now - received);
    stages_.pose.add(posed - now);
    stages_.outputs.add(sent - posed);
  }

  /// `to - from` [us], saturated: `from` is a message's stamp, any int64 (one near
  /// INT64_MIN overflowed the subtraction: found by fuzz_datagrams).
  static std::int64_t span_us(std::int64_t from, std::int64_t to) {
    std::int64_t d = 0;
    if (!__builtin_sub_overflow(to, from, &d)) return d;
    return to > from ? std::numeric_limits<std::int64_t>::max() : std::numeric_limits<std::int64_t>::min();
  }

  void publish_snapshot() {
    for (int i = 0; i < node_.num_snapshot_chunks(); ++i) shell_.publish(snapshot_, node_.snapshot_chunk(i));
  }

  // Main's messages (its moving set, notices, team map, resync requests) each tell
  // that main is heard (FAULT_MAIN_SILENT); refused ones too: they came (and, with
  // the team's keys, verified as main's), their content is what was wrong.
  void heard_main() {
    node_.main_heard(shell_.now_utime());
    say_alert();
  }

  void say_alert() {
    if (const std::string alert = node_.take_alert(); !alert.empty()) shell_.say(alert, log::Priority::kWarning);
  }

  void on_map(const global_map_t& msg) {
    heard_main();
    std::string why;
    if (!node_.on_global_map(msg, &why)) shell_.refuse("global map refused: " + why);
  }

  void on_team_map(const global_map_t& msg) {
    heard_main();
    std::string why;
    if (!node_.on_team_map(msg, &why)) shell_.refuse("team map refused: " + why);
  }

  void on_resync(const resync_request_t& msg) {
    heard_main();
    if (node_.on_resync(msg, shell_.now_utime())) publish_snapshot();
  }

  void on_own(const std::string& channel, std::int64_t incarnation, int frame) {
    if (node_.on_own_channel(incarnation, frame))  // loudly, not rate-limited: an operator must see it
      shell_.say("FAULT: another process publishes " + channel + " (incarnation " + std::to_string(incarnation) +
                 ", this one " + std::to_string(node_.incarnation()) + "): two robots with one id",
                 log::Priority::kWarning);
  }

  void on_notice(const dynamic_notice_t& msg) {
    heard_main();
    std::string why;
    if (!node_.on_notice(msg, &why)) return shell_.refuse("dynamic notice refused: " + why);
    // Only an accepted notice moves the tracker: a forged seq must not hide real losses.
    const std::int64_t lost = notice_seq_.observe(msg.seq, msg.incarnation);
    if (lost > 0) node_.count_queue_drops(lost);
  }

  Shell& shell_;
  RobotNode& node_;
  const std::string event_, events_, snapshot_, pose_, status_, candidates_, tracks_;  // channel names, built once
  typename Shell::SequenceGaps notice_seq_;            // DYNAMIC_NOTICE's seq: lost notices
  std::function<void(const RobotNode&)> after_frame_;
  FrameStages stages_;
};

}  // namespace elaslam

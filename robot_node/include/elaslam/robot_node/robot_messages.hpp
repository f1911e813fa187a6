// SPDX-License-Identifier: Apache-2.0
// The Robot's state as the robot's outgoing messages: POSE_<r>, its LMAP_EVENTs
// (singly and batched in LMAP_EVENTS, numbered by a per-robot seq), LMAP_SNAPSHOT
// chunks, CANDIDATES_<r> and TRACKS_<r>. Every message is a buffer sized at construction for the
// largest map the options allow, so filling them allocates nothing. Each carries the
// node's incarnation. It reads the Robot and never changes it.
#pragma once

#include <cstdint>
#include <vector>

#include "elaslam/candidate_list_t.hpp"
#include "elaslam/common/chunks.hpp"
#include "elaslam/landmark_event_t.hpp"
#include "elaslam/lmap_events_t.hpp"
#include "elaslam/lmap_snapshot_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/robot_node/robot.hpp"
#include "elaslam/sensor_frame_t.hpp"
#include "elaslam/track_list_t.hpp"

namespace elaslam {

class RobotMessages {
 public:
  RobotMessages(const RobotOptions& options, int robot_id);

  /// A new frame: no events, no snapshot, no candidates, no tracks until filled.
  void begin_frame();
  /// The Robot's events of its last frame, each with the next seq.
  void fill_events(const Robot& robot, int frame, std::int64_t now_utime);
  /// CANDIDATES_<r> when `frame` is one of robot.node.candidates_period_frames: the
  /// candidates in the filter (from their first sighting), while there are some and
  /// once more when the last has gone, so that a viewer clears them.
  void fill_candidates(const Robot& robot, int frame, std::int64_t now_utime);
  /// TRACKS_<r>: the moving landmarks' confirmed tracks (Robot::tracks) in the order
  /// they started, in chunks of contract::kMaxTracks, at most
  /// contract::kMaxTrackChunks (the rest counted in num_omitted), every frame while
  /// there are some and once more (one empty chunk) when the last has ended, so that
  /// readers clear them.
  void fill_tracks(const Robot& robot, int frame, std::int64_t now_utime);
  /// The map's snapshot, in chunks that each fit one datagram; returns their count.
  int make_snapshot(const Robot& robot, int frame, std::int64_t now_utime);
  /// This frame sends the snapshot made last.
  void send_snapshot() { snapshot_ready_ = true; }
  /// POSE_<r> last: it carries the seq of the frame's last event and the snapshot's
  /// chunk count.
  void fill_pose(const Robot& robot, const sensor_frame_t& msg, std::int64_t now_utime, const FrameSummary& s,
                 std::int64_t processing_us, std::int64_t frames_this_run);
  /// Stamp this frame's events (singly and in batches) with `utime`: the moment they go out.
  void stamp_events(std::int64_t utime);

  const pose_estimate_t& pose() const { return pose_; }
  const std::vector<landmark_event_t>& events() const { return events_; }
  int num_event_batches() const { return num_batches_; }
  const lmap_events_t& event_batch(int i) const { return batches_[static_cast<std::size_t>(i)]; }
  bool snapshot_ready() const { return snapshot_ready_; }
  int num_snapshot_chunks() const { return num_chunks_; }
  const lmap_snapshot_t& snapshot_chunk(int i) const { return chunks_[static_cast<std::size_t>(i)]; }
  bool candidates_ready() const { return candidates_ready_; }
  const candidate_list_t& candidates() const { return candidates_; }
  /// This frame's TRACKS_<r> chunks: 0 when it sends none.
  int num_track_chunks() const { return num_track_chunks_; }
  const track_list_t& track_chunk(int i) const { return track_chunks_[static_cast<std::size_t>(i)]; }

  std::int64_t incarnation() const { return incarnation_; }
  void set_incarnation(std::int64_t v) { incarnation_ = v; }
  std::int64_t seq() const { return seq_; }  // seq of the last event filled
  void skip_seq(std::int64_t n) { seq_ += n; }

 private:
  friend struct RobotStateAccess;  // the state file saves and restores seq_

  int robot_id_;
  std::int64_t incarnation_ = 0;
  std::int64_t seq_ = 0;
  pose_estimate_t pose_{};
  std::vector<landmark_event_t> events_;
  std::vector<lmap_events_t> batches_;  // events_ in LMAP_EVENTS messages; the first num_batches_ in use
  int num_batches_ = 0;
  // Snapshot chunks: a pool sized at construction for the largest map.
  ChunkSizes chunk_sizes_;
  std::vector<int> static_ids_, moving_ids_;  // scratch: the map's ids, ascending
  std::vector<ChunkSpan> spans_;
  std::vector<lmap_snapshot_t> chunks_;
  int num_chunks_ = 0;
  bool snapshot_ready_ = false;
  int candidates_period_ = 0;
  bool candidates_ready_ = false;
  candidate_list_t candidates_{};  // reserved for contract::kMaxCandidates at construction
  // contract::kMaxTrackChunks chunks, each reserved for contract::kMaxTracks at
  // construction; the first num_track_chunks_ go out this frame.
  std::vector<track_list_t> track_chunks_;
  int num_track_chunks_ = 0;
  int tracks_published_ = 0;  // tracks (sent and omitted) of the last TRACKS_<r>
};

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
#include "elaslam/main_robot/frame_completion.hpp"

#include <algorithm>
#include <limits>

namespace elaslam {

FrameCompletion::FrameCompletion() {
  robot_frame_.fill(-1);
  snapshot_done_frame_.fill(-1);
}

bool FrameCompletion::stale(int robot_id, int frame) const {
  const std::size_t r = index(robot_id);
  return frame <= std::max(held_[r].frame, robot_frame_[r]);
}

FrameCompletion::PoseOutcome FrameCompletion::take_pose(int robot_id, int frame, std::int64_t event_seq,
                                                        int snapshot_chunks, std::int64_t applied_seq) {
  const std::size_t r = index(robot_id);
  HeldPose& held = held_[r];
  PoseOutcome out;
  const HeldPose older = held;
  const bool snapshot_in = snapshot_chunks == 0 || snapshot_done_frame_[r] == frame;  // (or came first)
  if (event_seq <= applied_seq && snapshot_in) {
    held = HeldPose{};
    out.finished = finished_frame(robot_id, frame);
  } else {
    held = HeldPose{frame, event_seq, !snapshot_in};
    if (older.frame >= 0) out.finished = finished_frame(robot_id, older.frame);
  }
  out.let_go_frame = older.frame;
  out.let_go_event_seq = older.event_seq;
  return out;
}

void FrameCompletion::events_applied(int robot_id, std::int64_t applied_seq) {
  HeldPose& held = held_[index(robot_id)];
  if (held.frame < 0 || held.snapshot || applied_seq < held.event_seq) return;
  const int frame = held.frame;
  held = HeldPose{};
  const int done = finished_frame(robot_id, frame);
  if (done >= 0) finished_ = std::max(finished_, done);
}

void FrameCompletion::snapshot_applied(int robot_id, int frame, std::int64_t applied_seq) {
  const std::size_t r = index(robot_id);
  snapshot_done_frame_[r] = frame;
  if (held_[r].frame == frame) held_[r].snapshot = false;
  events_applied(robot_id, applied_seq);
}

void FrameCompletion::restart(int robot_id) {
  const std::size_t r = index(robot_id);
  robot_frame_[r] = -1;
  held_[r] = HeldPose{};  // it waited for the old stream's seq
  snapshot_done_frame_[r] = -1;
}

int FrameCompletion::finished_frame(int robot_id, int frame) {
  int& f = robot_frame_[index(robot_id)];
  f = std::max(f, frame);
  // The oldest frame of the robots seen; a robot whose POSE is held (its events not
  // in yet) has finished only the frame before that POSE's, also when that POSE is
  // the first heard of it (then nothing: -1 holds every map back).
  int all = std::numeric_limits<int>::max();
  bool any = false;
  for (std::size_t r = 0; r < robot_frame_.size(); ++r) {
    int done = robot_frame_[r];
    if (const int held = held_[r].frame; held >= 0) done = done < 0 ? held - 1 : std::min(done, held - 1);
    else if (done < 0)
      continue;
    all = any ? std::min(all, done) : done;
    any = true;
  }
  if (!any || all <= completed_) return -1;
  completed_ = all;
  return all;
}

}  // namespace elaslam

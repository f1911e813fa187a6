// SPDX-License-Identifier: Apache-2.0
// frame_accounting.hpp: every frame of a run, per robot, accounted for.
#include "elaslam/logs/frame_accounting.hpp"

#include <algorithm>
#include <limits>

namespace elaslam {
namespace {

// a - b without overflow (frames_processed comes from the wire and may be garbage).
std::int64_t sat_sub(std::int64_t a, std::int64_t b) {
  std::int64_t r = 0;
  if (__builtin_sub_overflow(a, b, &r))
    return b < 0 ? std::numeric_limits<std::int64_t>::max() : std::numeric_limits<std::int64_t>::min();
  return r;
}

int clamp_count(std::int64_t v, int hi) {
  return static_cast<int>(std::clamp<std::int64_t>(v, 0, std::max(hi, 0)));
}

// The STATUS with the largest frame above `after` (the later one given on a tie).
const StatusCheckpoint* latest_status(const std::vector<StatusCheckpoint>& statuses, long long after) {
  const StatusCheckpoint* best = nullptr;
  for (const auto& s : statuses)
    if (s.frame > after && (!best || s.frame >= best->frame)) best = &s;
  return best;
}

std::vector<int> sorted_in_range(std::vector<int> v, int first, int last) {
  v.erase(std::remove_if(v.begin(), v.end(), [&](int f) { return f < first || f > last; }), v.end());
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  return v;
}

}  // namespace

std::vector<std::pair<int, int>> absent_ranges(int first, int last, const std::vector<int>& present) {
  std::vector<std::pair<int, int>> out;
  long long next = first;  // first frame not yet classified
  for (int f : present) {
    if (f < next || f > last) continue;
    if (f > next) out.emplace_back(static_cast<int>(next), f - 1);
    next = static_cast<long long>(f) + 1;
  }
  if (next <= last) out.emplace_back(static_cast<int>(next), last);
  return out;
}

std::string format_ranges(const std::vector<std::pair<int, int>>& ranges) {
  if (ranges.empty()) return "none";
  std::string s;
  for (const auto& [a, b] : ranges) {
    if (!s.empty()) s += ", ";
    s += a == b ? std::to_string(a) : std::to_string(a) + "-" + std::to_string(b);
  }
  return s;
}

RobotFrameAccount account_frames(int robot_id, int first_frame, int last_frame, std::vector<PoseCheckpoint> poses,
                                 const std::vector<StatusCheckpoint>& statuses, const std::vector<int>& sensor_frames) {
  RobotFrameAccount a;
  a.robot_id = robot_id;
  if (const StatusCheckpoint* s = latest_status(statuses, std::numeric_limits<long long>::min()))
    a.node_reported_dropped = s->frames_dropped;
  a.sensor_recorded = !sensor_frames.empty();
  if (last_frame < first_frame) return a;
  // Frame numbers come from the wire: keep every difference below within int.
  constexpr int kMaxSpan = std::numeric_limits<int>::max() / 2;
  if (static_cast<std::int64_t>(last_frame) - first_frame >= kMaxSpan) last_frame = first_frame + (kMaxSpan - 1);
  a.frames_in_run = last_frame - first_frame + 1;

  // 1. The POSEs of the run, one per frame (the first given), in frame order.
  poses.erase(std::remove_if(poses.begin(), poses.end(),
                             [&](const PoseCheckpoint& p) { return p.frame < first_frame || p.frame > last_frame; }),
              poses.end());
  std::stable_sort(poses.begin(), poses.end(),
                   [](const PoseCheckpoint& x, const PoseCheckpoint& y) { return x.frame < y.frame; });
  poses.erase(std::unique(poses.begin(), poses.end(),
                          [](const PoseCheckpoint& x, const PoseCheckpoint& y) { return x.frame == y.frame; }),
              poses.end());
  a.poses_logged = static_cast<int>(poses.size());

  if (poses.empty()) {
    // 2a. Nothing logged: a STATUS may still prove the robot processed frames.
    const StatusCheckpoint* s = latest_status(statuses, std::numeric_limits<long long>::min());
    a.missing_from_log = s && s->frames > 0 ? clamp_count(s->frames, a.frames_in_run) : 0;
    a.not_started = a.frames_in_run - a.missing_from_log;
  } else {
    // 2b. Before the first POSE: processed but lost, else not started yet.
    const int before = poses.front().frame - first_frame;
    const int q = clamp_count(sat_sub(poses.front().frames_processed, 1), before);
    a.missing_from_log += q;
    a.not_started += before - q;
    // 3. Between POSEs: the growth of frames_processed says how many were processed.
    for (std::size_t i = 1; i < poses.size(); ++i) {
      const PoseCheckpoint& pa = poses[i - 1];
      const PoseCheckpoint& pb = poses[i];
      const int g = pb.frame - pa.frame - 1;
      int p = 0;
      if (pb.frames_processed > pa.frames_processed) {
        p = clamp_count(sat_sub(sat_sub(pb.frames_processed, pa.frames_processed), 1), g);
      } else {
        ++a.restarts;
        p = clamp_count(sat_sub(pb.frames_processed, 1), g);
      }
      a.missing_from_log += p;
      a.dropped += g - p;
    }
    // 4. After the last POSE: only a later STATUS can tell.
    const PoseCheckpoint& pl = poses.back();
    const int after = last_frame - pl.frame;
    int processed = 0;
    if (const StatusCheckpoint* s = latest_status(statuses, pl.frame)) {
      if (s->frames >= pl.frames_processed) {
        processed = clamp_count(sat_sub(s->frames, pl.frames_processed), after);
      } else {
        ++a.restarts;
        processed = clamp_count(s->frames, after);
      }
    }
    a.missing_from_log += processed;
    a.dropped += after - processed;
  }

  // 5. Where the holes are.
  std::vector<int> logged;
  logged.reserve(poses.size());
  for (const auto& p : poses) logged.push_back(p.frame);
  a.missing_pose_ranges = absent_ranges(first_frame, last_frame, logged);
  if (a.sensor_recorded) {
    const std::vector<int> sensed = sorted_in_range(sensor_frames, first_frame, last_frame);
    a.sensors_logged = static_cast<int>(sensed.size());
    a.missing_sensor_ranges = absent_ranges(first_frame, last_frame, sensed);
  }
  return a;
}

}  // namespace elaslam

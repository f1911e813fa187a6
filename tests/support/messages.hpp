// SPDX-License-Identifier: Apache-2.0
// Message builders shared by the tests and benchmarks of main_robot's inputs: a
// landmark event and a POSE with plausible values (positions in metres, variances in
// square metres) and the fields the caller names.
#pragma once

#include <cstdint>

#include <vector>

#include "elaslam/landmark_event_t.hpp"
#include "elaslam/lmap_events_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/track_list_t.hpp"

namespace elaslam::test {

/// Robot `robot`'s event number `seq` of `kind` about landmark `id`, at (x, y) with
/// covariance var * I, sent in `frame`.
inline landmark_event_t event_msg(int robot, std::int64_t seq, int kind, int id, int frame = 0, double x = 1.0,
                                  double y = 2.0, double var = 0.01) {
  landmark_event_t m{};
  m.robot_id = static_cast<std::int16_t>(robot);
  m.seq = seq;
  m.frame = frame;
  m.kind = static_cast<std::int8_t>(kind);
  m.landmark_id = id;
  m.x = x;
  m.y = y;
  m.cov[0][0] = m.cov[1][1] = var;
  return m;
}

/// `events` in one LMAP_EVENTS message, its header taken from the first.
inline lmap_events_t events_msg(const std::vector<landmark_event_t>& events) {
  lmap_events_t m{};
  if (!events.empty()) {
    m.robot_id = events.front().robot_id;
    m.frame = events.front().frame;
    m.incarnation = events.front().incarnation;
  }
  m.num_events = static_cast<std::int16_t>(events.size());
  m.events = events;
  return m;
}

/// Robot `robot`'s POSE at the end of `frame`, at the origin with covariance var * I.
inline pose_estimate_t pose_msg(int robot, int frame, double var = 1e-4) {
  pose_estimate_t p{};
  p.robot_id = static_cast<std::int16_t>(robot);
  p.frame = frame;
  p.cov[0][0] = p.cov[1][1] = p.cov[2][2] = var;
  return p;
}

/// A track of landmark `id` at (x, y) moving at (vx, vy), covariance diag(pos_var,
/// pos_var, vel_var, vel_var), model probabilities (static, bounded, constant velocity).
inline track_t track_of(int id, double x, double y, double vx, double vy, double pos_var = 0.01, double vel_var = 0.04,
                        std::vector<float> probabilities = {0.1f, 0.2f, 0.7f}) {
  track_t t{};
  t.id = id;
  t.x = x;
  t.y = y;
  t.vx = vx;
  t.vy = vy;
  t.cov[0] = t.cov[4] = static_cast<float>(pos_var);  // xx, yy
  t.cov[7] = t.cov[9] = static_cast<float>(vel_var);  // vxvx, vyvy
  for (std::size_t i = 0; i < 3; ++i) t.probabilities[i] = probabilities[i];
  t.likeliest = track_t::CONSTANT_VELOCITY;
  t.sightings = 10;
  return t;
}

/// Robot `robot`'s TRACKS of `frame`: chunk `chunk` of `num_chunks` (default: the
/// publication's only chunk).
inline track_list_t tracks_msg(int robot, int frame, const std::vector<track_t>& tracks, int chunk = 0,
                               int num_chunks = 1) {
  track_list_t m{};
  m.robot_id = static_cast<std::int16_t>(robot);
  m.frame = frame;
  m.chunk = static_cast<std::int16_t>(chunk);
  m.num_chunks = static_cast<std::int16_t>(num_chunks);
  m.num_tracks = static_cast<std::int16_t>(tracks.size());
  m.tracks = tracks;
  return m;
}

}  // namespace elaslam::test

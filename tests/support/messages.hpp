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

}  // namespace elaslam::test

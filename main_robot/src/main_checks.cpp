// SPDX-License-Identifier: Apache-2.0
#include "elaslam/main_robot/main_checks.hpp"

#include "elaslam/common/contract.hpp"
#include "elaslam/common/track_checks.hpp"

namespace elaslam::main_checks {

std::string robot(int robot_id, const MessageLimits& l, Refusal* reason) {
  if (robot_id < 1 || robot_id > contract::kMaxRobots) {
    *reason = Refusal::kMalformed;
    return contract::got(contract::outside("robot_id", 1, contract::kMaxRobots), robot_id);
  }
  if (!l.in_team(robot_id)) {
    *reason = Refusal::kOutsideTeam;
    return contract::got("robot_id not in limits.team " + team_text(l.team_mask), robot_id);
  }
  return "";
}

namespace {

/// robot(), then *r kMalformed for the checks that follow it.
std::string sender(int robot_id, const MessageLimits& lim, Refusal* r) {
  if (std::string p = robot(robot_id, lim, r); !p.empty()) return p;
  *r = Refusal::kMalformed;
  return "";
}

/// What a robot's event or snapshot starts with: its robot in the team (the refusal's
/// reason that check's), then, malformed otherwise, seq in [min_seq, kMaxSeq] and
/// incarnation and frame not negative.
template <typename Message>
std::string sender_run_frame(const Message& m, std::int64_t min_seq, const MessageLimits& lim, Refusal* r) {
  if (std::string p = sender(m.robot_id, lim, r); !p.empty()) return p;
  if (m.seq < min_seq || m.seq > kMaxSeq)
    return contract::got("seq not in [" + std::to_string(min_seq) + ", 2^62]", m.seq);
  if (m.incarnation < 0) return contract::got("incarnation is negative", m.incarnation);
  if (m.frame < 0) return contract::got("frame is negative", m.frame);
  return "";
}

}  // namespace

std::string event(const landmark_event_t& m, const MessageLimits& lim, int max_landmark_id, Refusal* reason) {
  Refusal& r = *reason;
  if (std::string p = sender_run_frame(m, 1, lim, &r); !p.empty()) return p;
  if (m.kind < landmark_event_t::ADD || m.kind > landmark_event_t::RETURN) return contract::got("unknown kind", int(m.kind));
  if (m.landmark_id < 0 || m.landmark_id >= max_landmark_id)
    return contract::got("landmark_id outside [0, max_landmark_id)", m.landmark_id);
  if (m.kind != landmark_event_t::MOVING) {
    r = Refusal::kImplausible;
    if (std::string p = check_position(m.x, m.y, lim, "position"); !p.empty()) return p;
    if (std::string p = check_cov2(m.cov, lim, "cov"); !p.empty()) return p;
  }
  return "";
}

std::string events(const lmap_events_t& m, const MessageLimits& lim, Refusal* reason) {
  Refusal& r = *reason;
  if (std::string p = sender(m.robot_id, lim, &r); !p.empty()) return p;
  if (m.incarnation < 0) return contract::got("incarnation is negative", m.incarnation);
  if (m.frame < 0) return contract::got("frame is negative", m.frame);
  if (m.num_events < 1 || m.num_events > contract::kMaxBatchEvents)
    return contract::got("num_events outside [1, " + std::to_string(contract::kMaxBatchEvents) + "]", m.num_events);
  if (!contract::count_fits(m.events, m.num_events)) return contract::got("num_events does not match the array", m.num_events);
  std::int64_t previous = 0;
  for (int k = 0; k < m.num_events; ++k) {
    const landmark_event_t& e = m.events[static_cast<std::size_t>(k)];
    // The header speaks for every event: one robot, one incarnation, one frame.
    if (e.robot_id != m.robot_id) return contract::got("an event's robot_id differs from the message's", e.robot_id);
    if (e.incarnation != m.incarnation) return contract::got("an event's incarnation differs from the message's", e.incarnation);
    if (e.frame != m.frame) return contract::got("an event's frame differs from the message's", e.frame);
    if (e.seq <= previous) return contract::got("event seqs not ascending, seq", e.seq);
    previous = e.seq;
  }
  return "";
}

std::string snapshot(const lmap_snapshot_t& m, const MessageLimits& lim, int max_landmark_id, Refusal* reason) {
  Refusal& r = *reason;
  if (std::string p = sender_run_frame(m, 0, lim, &r); !p.empty()) return p;
  if (m.num_chunks < 1 || m.chunk < 0 || m.chunk >= m.num_chunks) return contract::got("chunk outside [0, num_chunks)", m.chunk);
  if (m.id_begin < 0 || m.id_end <= m.id_begin || m.id_end > max_landmark_id)
    return contract::got("id range not within [0, max_landmark_id), id_begin", m.id_begin);
  if (!contract::count_fits(m.landmarks, m.num_landmarks)) return contract::got("num_landmarks does not match the array", m.num_landmarks);
  if (!contract::count_fits(m.moving_ids, m.num_moving) || !contract::count_fits(m.moving_frames, m.num_moving))
    return contract::got("num_moving does not match the arrays", m.num_moving);
  int previous = -1;
  for (int k = 0; k < m.num_landmarks; ++k) {
    const landmark_estimate_t& l = m.landmarks[static_cast<std::size_t>(k)];
    r = Refusal::kMalformed;
    if (l.id < m.id_begin || l.id >= m.id_end) return contract::got("landmark id outside the chunk's range", l.id);
    if (l.id == previous) return r = Refusal::kDuplicateId, contract::got("landmark id listed twice", l.id);
    if (l.id < previous) return contract::got("landmark ids not ascending, id", l.id);
    previous = l.id;
    r = Refusal::kImplausible;  // (no string built unless refused: the frame path allocates nothing)
    if (std::string p = check_position(l.x, l.y, lim, "position"); !p.empty()) return "landmark " + std::to_string(l.id) + " " + p;
    if (std::string p = check_cov2(l.cov, lim, "cov"); !p.empty()) return "landmark " + std::to_string(l.id) + " " + p;
  }
  previous = -1;
  for (int k = 0; k < m.num_moving; ++k) {
    const int id = m.moving_ids[static_cast<std::size_t>(k)];
    r = Refusal::kMalformed;
    if (id < m.id_begin || id >= m.id_end) return contract::got("moving id outside the chunk's range", id);
    // Ascending like the landmarks (snapshot chunks list both in id order): a repeat is one id twice.
    if (id == previous) return r = Refusal::kDuplicateId, contract::got("moving id listed twice", id);
    if (id < previous) return contract::got("moving ids not ascending, id", id);
    previous = id;
    const int found = m.moving_frames[static_cast<std::size_t>(k)];
    if (found < -1 || found > m.frame) return contract::got("moving frame not in [-1, the snapshot's frame]", found);
  }
  // One id both static and moving: two contradicting entries for it.
  for (int a = 0, b = 0; a < m.num_landmarks && b < m.num_moving;) {
    const int ia = m.landmarks[static_cast<std::size_t>(a)].id, ib = m.moving_ids[static_cast<std::size_t>(b)];
    if (ia == ib) return r = Refusal::kDuplicateId, contract::got("id listed as static and as moving", ia);
    (ia < ib ? a : b)++;
  }
  return "";
}

std::string pose(const pose_estimate_t& m, const MessageLimits& lim, Refusal* reason) {
  Refusal& r = *reason;
  if (std::string p = sender(m.robot_id, lim, &r); !p.empty()) return p;
  if (m.event_seq < 0 || m.event_seq > kMaxSeq) return contract::got("event_seq not in [0, 2^62]", m.event_seq);
  if (m.snapshot_chunks < 0) return contract::got("snapshot_chunks is negative", m.snapshot_chunks);
  return check_pose(m, lim, &r);
}

std::string tracks(const track_list_t& m, const MessageLimits& lim, int max_landmark_id, Refusal* reason) {
  Refusal& r = *reason;
  if (std::string p = robot(m.robot_id, lim, &r); !p.empty()) return p;
  return check_track_list(m, lim, max_landmark_id, &r);
}

}  // namespace elaslam::main_checks

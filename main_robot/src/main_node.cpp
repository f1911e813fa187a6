#include "elaslam/main_robot/main_node.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "elaslam/common/contract.hpp"

namespace elaslam {
namespace {

template <typename T>
std::string str(const char* what, T v) {
  std::ostringstream os;
  os << what << " (got " << v << ")";
  return os.str();
}

bool finite_cov(const double (&c)[2][2]) {
  for (const auto& row : c)
    for (double v : row)
      if (!std::isfinite(v)) return false;
  // A covariance: symmetric, non-negative diagonal and determinant.
  return c[0][0] >= 0.0 && c[1][1] >= 0.0 && std::fabs(c[0][1] - c[1][0]) <= 1e-9 * (1.0 + std::fabs(c[0][1])) &&
         c[0][0] * c[1][1] - c[0][1] * c[1][0] >= -1e-18;
}

Eigen::Matrix2d to_matrix(const double (&c)[2][2]) {
  Eigen::Matrix2d m;
  m << c[0][0], c[0][1], c[1][0], c[1][1];
  return m;
}

}  // namespace

MainNode::MainNode(const GlobalMapOptions& options) : map_(options) {
  robot_frame_.fill(-1);
  pending_.reserve(contract::kMaxLandmarksPerMessage);
  notices_.reserve(contract::kMaxLandmarksPerMessage);
  snap_lms_.reserve(contract::kMaxLandmarksPerMessage);
  snap_moving_.reserve(contract::kMaxLandmarksPerMessage);
}

std::string MainNode::validate(const landmark_event_t& m) const {
  if (m.robot_id < 1 || m.robot_id > kMaxTeamRobots) return str("robot_id outside [1, 8]", m.robot_id);
  if (m.seq < 1) return str("seq must be >= 1", m.seq);
  if (m.frame < 0) return str("frame is negative", m.frame);
  if (m.kind < landmark_event_t::ADD || m.kind > landmark_event_t::RETURN) return str("unknown kind", int(m.kind));
  if (m.landmark_id < 0 || m.landmark_id >= map_.max_landmark_id())
    return str("landmark_id outside [0, max_landmark_id)", m.landmark_id);
  if (m.kind != landmark_event_t::MOVING) {
    if (!std::isfinite(m.x) || !std::isfinite(m.y) || std::fabs(m.x) > 1e6 || std::fabs(m.y) > 1e6)
      return "position is not finite or beyond 1e6 m";
    if (!finite_cov(m.cov)) return "covariance is not a finite symmetric positive semi-definite matrix";
  }
  return "";
}

std::string MainNode::validate(const lmap_snapshot_t& m) const {
  if (m.robot_id < 1 || m.robot_id > kMaxTeamRobots) return str("robot_id outside [1, 8]", m.robot_id);
  if (m.seq < 0) return str("seq is negative", m.seq);
  if (m.frame < 0) return str("frame is negative", m.frame);
  if (m.num_landmarks < 0 || m.num_landmarks > contract::kMaxLandmarksPerMessage)
    return str(contract::count_outside("num_landmarks", contract::kMaxLandmarksPerMessage).c_str(), m.num_landmarks);
  if (m.num_moving < 0 || m.num_moving > contract::kMaxLandmarksPerMessage)
    return str(contract::count_outside("num_moving", contract::kMaxLandmarksPerMessage).c_str(), m.num_moving);
  for (int k = 0; k < m.num_landmarks; ++k) {
    const landmark_estimate_t& l = m.landmarks[k];
    if (l.id < 0 || l.id >= map_.max_landmark_id()) return str("landmark id outside [0, max_landmark_id)", l.id);
    if (!std::isfinite(l.x) || !std::isfinite(l.y)) return str("landmark position not finite, id", l.id);
    if (!finite_cov(l.cov)) return str("landmark covariance invalid, id", l.id);
  }
  for (int k = 0; k < m.num_moving; ++k)
    if (m.moving_ids[k] < 0 || m.moving_ids[k] >= map_.max_landmark_id())
      return str("moving id outside [0, max_landmark_id)", m.moving_ids[k]);
  return "";
}

bool MainNode::on_event(const landmark_event_t& m, std::string* why) {
  const std::string problem = validate(m);
  if (!problem.empty()) {
    ++counters_.rejected_inputs;
    if (why) *why = problem;
    return false;
  }
  GlobalEvent e;
  e.robot_id = m.robot_id;
  e.seq = m.seq;
  e.frame = m.frame;
  e.kind = m.kind;
  e.landmark_id = m.landmark_id;
  e.position = {m.x, m.y};
  e.cov = to_matrix(m.cov);
  switch (map_.apply(e, &pending_)) {
    case EventResult::kApplied: ++counters_.events; break;
    case EventResult::kAppliedAfterGap: ++counters_.events, ++counters_.gaps; break;
    case EventResult::kDuplicate:
    case EventResult::kStale: ++counters_.duplicates; break;
  }
  return true;
}

bool MainNode::on_snapshot(const lmap_snapshot_t& m, std::string* why) {
  const std::string problem = validate(m);
  if (!problem.empty()) {
    ++counters_.rejected_inputs;
    if (why) *why = problem;
    return false;
  }
  snap_lms_.clear();
  snap_moving_.clear();
  for (int k = 0; k < m.num_landmarks; ++k) {
    const landmark_estimate_t& l = m.landmarks[k];
    snap_lms_.push_back({l.id, RobotEstimate{true, {l.x, l.y}, to_matrix(l.cov), m.frame}});
  }
  for (int k = 0; k < m.num_moving; ++k) snap_moving_.push_back(m.moving_ids[k]);
  map_.apply_snapshot(m.robot_id, m.seq, m.frame, snap_lms_, snap_moving_, &pending_);
  ++counters_.snapshots;
  return true;
}

const std::vector<dynamic_notice_t>& MainNode::take_notices(std::int64_t now_utime) {
  notices_.clear();
  for (const Notice& n : pending_) {
    dynamic_notice_t d{};
    d.utime = now_utime;
    d.frame = n.frame;
    d.seq = ++notice_seq_;
    d.landmark_id = n.landmark_id;
    d.detected_by = static_cast<int16_t>(n.detected_by);
    notices_.push_back(d);
  }
  pending_.clear();
  counters_.notices_sent += static_cast<std::int64_t>(notices_.size());
  return notices_;
}

int MainNode::on_robot_frame(int robot_id, int frame) {
  if (robot_id < 1 || robot_id > kMaxTeamRobots || frame < 0) {
    ++counters_.rejected_inputs;
    return -1;
  }
  int& f = robot_frame_[static_cast<std::size_t>(robot_id - 1)];
  f = std::max(f, frame);
  int all = -1;
  for (int r : robot_frame_)
    if (r >= 0) all = all < 0 ? r : std::min(all, r);
  if (all <= completed_frame_) return -1;
  completed_frame_ = all;
  return all;
}

const global_map_t& MainNode::global_map_msg(std::int64_t now_utime, int frame) {
  msg_.utime = now_utime;
  msg_.frame = frame >= 0 ? frame : (completed_frame_ >= 0 ? completed_frame_ : map_.newest_frame());
  msg_.version = map_.version();
  int n = 0, m = 0;
  for (int id = 0; id < map_.max_landmark_id(); ++id) {
    const GlobalEntry& g = map_.entry(id);
    if (g.status == GlobalStatus::kStatic && n < contract::kMaxLandmarksPerMessage) {
      global_landmark_t& l = msg_.landmarks[n++];
      l.id = id;
      l.x = g.fused.x();
      l.y = g.fused.y();
      for (int r = 0; r < 2; ++r)
        for (int c = 0; c < 2; ++c) l.cov[r][c] = g.fused_cov(r, c);
      l.contributors = static_cast<int16_t>(g.contributors());
      l.status = global_landmark_t::STATIC;
      l.status_frame = g.status_frame;
    } else if (g.status == GlobalStatus::kMoving && m < contract::kMaxLandmarksPerMessage) {
      msg_.moving_ids[m++] = id;
    }
  }
  msg_.num_landmarks = static_cast<int16_t>(n);
  msg_.num_moving = static_cast<int16_t>(m);
  ++counters_.maps_published;
  return msg_;
}

node_status_t MainNode::status_msg(std::int64_t now_utime) const {
  node_status_t s{};
  s.utime = now_utime;
  s.frame = map_.newest_frame();
  s.node_kind = node_status_t::MAIN;
  s.node_id = 0;
  s.frames = counters_.events;
  s.frames_dropped = counters_.gaps;
  s.rejected_inputs = counters_.rejected_inputs;
  s.decode_errors = counters_.decode_errors;
  s.events_sent = counters_.notices_sent;
  return s;
}

}  // namespace elaslam

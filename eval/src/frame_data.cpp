// SPDX-License-Identifier: Apache-2.0
#include "elaslam/eval/frame_data.hpp"

#include <cmath>

#include <algorithm>

#include "elaslam/common/contract.hpp"

namespace elaslam {

void set_truth(const ground_truth_t& gt, FrameData* f) {
  f->frame = gt.frame;
  f->robot_ids.clear();
  f->true_poses.clear();
  // A logged message may be anything: read no further than its arrays hold.
  const int nr = contract::bounded(gt.num_robots, static_cast<int>(std::min(gt.robot_ids.size(), gt.robots.size())));
  for (std::size_t i = 0; i < static_cast<std::size_t>(nr); ++i) {
    f->robot_ids.push_back(gt.robot_ids[i]);
    f->true_poses.push_back({gt.robots[i].x, gt.robots[i].y, gt.robots[i].theta});
  }
  const auto n = static_cast<std::size_t>(contract::bounded(gt.num_landmarks, static_cast<int>(gt.landmarks.size())));
  const auto known = [](const landmark_truth_t& l) { return l.id >= 0 && l.id < contract::kMaxLandmarkIdLimit; };
  int max_id = -1;
  for (std::size_t i = 0; i < n; ++i)
    if (known(gt.landmarks[i])) max_id = std::max(max_id, gt.landmarks[i].id);
  f->true_landmarks.assign(static_cast<std::size_t>(max_id + 1), Eigen::Vector2d::Zero());
  f->truly_moving.assign(static_cast<std::size_t>(max_id + 1), 0);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& l = gt.landmarks[i];
    if (!known(l)) continue;
    f->true_landmarks[static_cast<std::size_t>(l.id)] = {l.x, l.y};
    f->truly_moving[static_cast<std::size_t>(l.id)] = l.moving ? 1 : 0;
  }
}

void clear_estimates(std::size_t robots, FrameData* f) {
  f->has_pose.assign(robots, 0);
  f->est_poses.assign(robots, Pose2{});
  f->mean_diag_p.assign(robots, 0.0);
  f->processing_us.assign(robots, 0);
  f->observed.clear();
}

void set_pose(std::size_t index, const pose_estimate_t& p, FrameData* f) {
  if (index >= f->has_pose.size()) return;
  f->has_pose[index] = 1;
  f->est_poses[index] = {p.x, p.y, p.theta};
  f->mean_diag_p[index] = p.mean_diag_p;
  f->processing_us[index] = p.processing_us;
}

void add_observed(const sensor_frame_t& s, std::vector<int>* observed) {
  for (int o = 0; o < contract::bounded(s.num_obs, static_cast<int>(s.obs.size())); ++o)
    observed->push_back(s.obs[static_cast<std::size_t>(o)].landmark_id);
}

void read_map(const global_map_t& g, std::vector<std::pair<int, Eigen::Vector2d>>* landmarks, std::vector<int>* moving) {
  landmarks->clear();
  moving->clear();
  for (int i = 0; i < contract::bounded(g.num_landmarks, static_cast<int>(g.landmarks.size())); ++i)
    landmarks->push_back({g.landmarks[i].id, {g.landmarks[i].x, g.landmarks[i].y}});
  for (int i = 0; i < contract::bounded(g.num_moving, static_cast<int>(g.moving_ids.size())); ++i)
    moving->push_back(g.moving_ids[i]);
}

bool GlobalMapAssembly::add(const global_map_t& c) {
  const bool consistent = c.num_chunks >= 1 && c.chunk >= 0 && c.chunk < c.num_chunks &&
                          contract::count_fits(c.landmarks, c.num_landmarks) &&
                          contract::count_fits(c.moving_ids, c.num_moving) &&
                          contract::count_fits(c.moving_frames, c.num_moving) && contract::count_fits(c.moving_by, c.num_moving);
  if (!consistent) return false;
  const bool same = count_ > 0 && c.utime == building_.utime && c.incarnation == building_.incarnation &&
                    c.version == building_.version && c.frame == building_.frame && c.num_chunks == building_.num_chunks;
  if (!same) {  // a new publication (the arrays keep their capacity)
    building_.landmarks.clear();
    building_.moving_ids.clear();
    building_.moving_frames.clear();
    building_.moving_by.clear();
    building_.utime = c.utime;
    building_.frame = c.frame;
    building_.incarnation = c.incarnation;
    building_.version = c.version;
    building_.num_chunks = c.num_chunks;
    received_.assign(static_cast<std::size_t>(c.num_chunks), false);
    count_ = 0;
  }
  if (received_[static_cast<std::size_t>(c.chunk)]) return false;  // a duplicate
  received_[static_cast<std::size_t>(c.chunk)] = true;
  ++count_;
  building_.landmarks.insert(building_.landmarks.end(), c.landmarks.begin(), c.landmarks.begin() + c.num_landmarks);
  building_.moving_ids.insert(building_.moving_ids.end(), c.moving_ids.begin(), c.moving_ids.begin() + c.num_moving);
  building_.moving_frames.insert(building_.moving_frames.end(), c.moving_frames.begin(),
                                 c.moving_frames.begin() + c.num_moving);
  building_.moving_by.insert(building_.moving_by.end(), c.moving_by.begin(), c.moving_by.begin() + c.num_moving);
  if (count_ < building_.num_chunks) return false;
  complete_ = building_;
  complete_.chunk = 0;
  complete_.num_chunks = 1;
  complete_.id_begin = 0;
  complete_.id_end = c.id_end;
  complete_.num_landmarks = static_cast<std::int16_t>(std::min<std::size_t>(complete_.landmarks.size(), contract::kMaxCount));
  complete_.num_moving = static_cast<std::int16_t>(std::min<std::size_t>(complete_.moving_ids.size(), contract::kMaxCount));
  std::sort(complete_.landmarks.begin(), complete_.landmarks.end(),
            [](const global_landmark_t& a, const global_landmark_t& b) { return a.id < b.id; });
  count_ = 0;
  return true;
}

std::string check_logged(const pose_estimate_t& p, std::int64_t received_us, const MessageLimits& l, Refusal* reason) {
  *reason = Refusal::kMalformed;
  if (p.robot_id < 1 || p.robot_id > contract::kMaxRobots) return contract::got(contract::outside("robot_id", 1, contract::kMaxRobots), p.robot_id);
  // Latency is receive - source_utime: a source stamp after the receipt (beyond the
  // clock skew of synchronised computers) is forged or from a wrong clock.
  if (p.source_utime < 0 || p.source_utime > received_us + kClockSlackUs)
    return contract::got("source_utime after the message was received (a forged stamp or a wrong clock)", p.source_utime);
  return check_pose(p, l, reason);
}

std::string check_logged(const sensor_frame_t& s, const MessageLimits& l, Refusal* reason) {
  *reason = Refusal::kMalformed;
  if (s.robot_id < 1 || s.robot_id > contract::kMaxRobots) return contract::got(contract::outside("robot_id", 1, contract::kMaxRobots), s.robot_id);
  if (s.frame < 0) return contract::got("frame is negative", s.frame);
  if (!contract::count_fits(s.obs, s.num_obs) || s.num_obs > contract::kMaxObsPerFrameLimit)
    return contract::got("num_obs does not match the array", s.num_obs);
  *reason = Refusal::kImplausible;
  return check_position(s.odom_x, s.odom_y, l, "odometer position");
}

std::string check_logged(const global_map_t& g, const MessageLimits& l, Refusal* reason) {
  return check_global_map(g, l, contract::kMaxCount, reason);  // a recording's ids: the contract's bound
}

}  // namespace elaslam

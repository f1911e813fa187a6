#include "elaslam/team/frame_data.hpp"

#include <algorithm>

#include "elaslam/common/contract.hpp"

namespace elaslam {

void set_truth(const ground_truth_t& gt, FrameData* f) {
  f->frame = gt.frame;
  f->robot_ids.clear();
  f->true_poses.clear();
  for (int i = 0; i < contract::bounded(gt.num_robots, contract::kMaxRobots); ++i) {
    f->robot_ids.push_back(gt.robot_ids[i]);
    f->true_poses.push_back({gt.robots[i].x, gt.robots[i].y, gt.robots[i].theta});
  }
  const int n = contract::bounded(gt.num_landmarks, contract::kMaxLandmarksPerMessage);
  int max_id = -1;
  for (int i = 0; i < n; ++i) max_id = std::max(max_id, gt.landmarks[i].id);
  f->true_landmarks.assign(static_cast<std::size_t>(max_id + 1), Eigen::Vector2d::Zero());
  f->truly_moving.assign(static_cast<std::size_t>(max_id + 1), 0);
  for (int i = 0; i < n; ++i) {
    const auto& l = gt.landmarks[i];
    if (l.id < 0) continue;
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
  for (int o = 0; o < contract::bounded(s.num_obs, contract::kMaxObsPerFrame); ++o)
    observed->push_back(s.obs[o].landmark_id);
}

void read_map(const global_map_t& g, std::vector<std::pair<int, Eigen::Vector2d>>* landmarks, std::vector<int>* moving) {
  landmarks->clear();
  moving->clear();
  for (int i = 0; i < contract::bounded(g.num_landmarks, contract::kMaxLandmarksPerMessage); ++i)
    landmarks->push_back({g.landmarks[i].id, {g.landmarks[i].x, g.landmarks[i].y}});
  for (int i = 0; i < contract::bounded(g.num_moving, contract::kMaxLandmarksPerMessage); ++i)
    moving->push_back(g.moving_ids[i]);
}

}  // namespace elaslam

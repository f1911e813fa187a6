// SPDX-License-Identifier: Apache-2.0
#include "elaslam/robot_node/deferred_inputs.hpp"

#include "elaslam/common/cov.hpp"

namespace elaslam {

DeferredInputs::DeferredInputs(const RobotOptions& options) : max_frame_gap_(options.max_frame_gap) {
  held_.reserve(kMaxHeldMoving);
  report_frame_.assign(static_cast<std::size_t>(options.ekf.max_landmark_id), -1);
  if (options.team_map_fuse) {
    team_pending_.resize(static_cast<std::size_t>(options.ekf.max_landmark_id));
    team_due_.reserve(static_cast<std::size_t>(options.ekf.max_landmark_id));
  }
}

bool DeferredInputs::is_news(const MovingReport& m, const LMap& lmap) const {
  return report_frame_[static_cast<std::size_t>(m.landmark_id)] < m.frame && lmap[m.landmark_id].status_frame <= m.frame;
}

DeferredInputs::Take DeferredInputs::take_moving(const MovingReport& m, const LMap& lmap, int last_frame) {
  if (!is_news(m, lmap)) return Take::kStale;
  report_frame_[static_cast<std::size_t>(m.landmark_id)] = m.frame;
  if (last_frame >= 0 && m.frame > last_frame && std::int64_t{m.frame} <= std::int64_t{last_frame} + max_frame_gap_ &&
      held_.size() < held_.capacity()) {
    held_.push_back(m);
    return Take::kHeld;
  }
  return Take::kNow;
}

bool DeferredInputs::take_team_map(const global_map_t& msg) {
  if (msg.incarnation < team_map_incarnation_ ||
      (msg.incarnation == team_map_incarnation_ && msg.version < team_map_version_))
    return false;
  team_map_incarnation_ = msg.incarnation;
  team_map_version_ = msg.version;
  for (int k = 0; k < msg.num_landmarks; ++k) {
    const global_landmark_t& l = msg.landmarks[static_cast<std::size_t>(k)];
    TeamPending& p = team_pending_[static_cast<std::size_t>(l.id)];
    if (!p.valid) ++team_pending_count_;
    p = {true, msg.frame, Eigen::Vector2d(l.x, l.y), read_cov(l.cov)};
  }
  return true;
}

const std::vector<TeamEstimate>& DeferredInputs::due_team_estimates(int last_frame) {
  team_due_.clear();  // reserved at construction: one per landmark id
  if (team_pending_count_ == 0) return team_due_;
  for (std::size_t id = 0; id < team_pending_.size(); ++id) {
    TeamPending& p = team_pending_[id];
    if (!p.valid || p.frame >= last_frame) continue;
    team_due_.push_back({static_cast<int>(id), p.position, p.cov});
    p.valid = false;
    --team_pending_count_;
  }
  return team_due_;
}

}  // namespace elaslam

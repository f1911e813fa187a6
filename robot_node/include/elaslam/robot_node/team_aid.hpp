// SPDX-License-Identifier: Apache-2.0
// The team's map back to a robot without double counting (the argument is
// in docs/adr/0025-team-map-two-filters.md).
//
// main_robot sends each robot r the map of the other robots: per landmark, the
// information fusion of every robot's own estimate but r's (TEAM_MAP_<r>). Those
// estimates are independent of r's data, since a robot reports only what its own
// filter learned (Robot keeps that filter apart from the one that fuses the team
// map: the "own" and the "aided" filter, as DDF-SAM keeps a robot's condensed map
// apart from its neighbourhood map). But consecutive team maps share what the others
// learned before: fusing each one whole would count it again and again. This is the
// channel filter of decentralised data fusion, per landmark: it remembers the
// information it has fused (Y_f, y_f in information form) and offers only what a new
// team estimate adds, Y_new - Y_f and y_new - y_f. When the others learned more, that
// is exactly the likelihood of their new data; the robot fuses it as a direct
// measurement of the landmark, z = l + v with v ~ N(0, (Y_new - Y_f)^-1).
//
// Directions in which the team's information fell (a robot's estimate dropped, a
// covariance that grew) are not fused; a rule that never double counts.
//
// The channel outlives the landmark's stay in the aided filter. A landmark that
// leaves it (evicted for room) takes its own estimate along, but what the team's
// estimate taught the robot's pose and the other landmarks stays. While main_robot's
// estimate goes on from the same data, its next team estimate is still only worth
// its increment; forgetting the channel would fuse all of it again. What changes the
// data is a move: main drops every robot's estimate of a landmark found moving and
// starts it afresh when it comes back. So the channel counts under an epoch, the
// number of times the robot has known the landmark to move (its own finding or a
// notice: LMapEntry::times_moving); a new epoch starts the channel again. The epoch
// is the robot's own, not main's (global_landmark_t.status_frame would do in a
// steady team, but a main_robot restarted without its state re-stamps every
// landmark, and every robot would then fuse the team's whole map again). A move
// the robot never learned of leaves the channel as it was: the team's new estimate
// then counts as less information than was fused and waits until it has more,
// which under-fuses and never double counts. Fixed memory; no allocation after
// construction.
#pragma once

#include <vector>

#include <Eigen/Core>

namespace elaslam {

class EkfSlam;

/// The own filter's pose against the aided filter's, beyond the own filter's pose
/// covariance: d^T P_own^-1 d > threshold (d = own - aided, heading wrapped; the
/// caller's chi-square quantile, 3 dof). The aided filter holds the own filter's data
/// and the team's increments besides, so their difference has covariance
/// P_own - P_aided, at most P_own; that difference is near singular where the team
/// added little, and rounding alone (the two filters group their covariance steps
/// differently) then looks like drift: P_own is the bound that stays well
/// conditioned. False when P_own is not positive definite.
bool pose_drifted(const EkfSlam& own, const EkfSlam& aided, double threshold);

struct TeamIncrement {
  int epoch = -1;                               // the team estimate's epoch (TeamChannel)
  Eigen::Vector2d z = Eigen::Vector2d::Zero();  // [m] the measurement of the landmark's position
  Eigen::Matrix2d R = Eigen::Matrix2d::Zero();  // [m^2] its covariance (positive definite)
  Eigen::Matrix2d Y = Eigen::Matrix2d::Zero();  // R^-1: the information it carries
};

class TeamChannel {
 public:
  /// `min_gain`: an increment is offered only when it would shrink the landmark's
  /// variance noticeably, tr(P_ll (Y_new - Y_f)) >= min_gain (0.05: five percent);
  /// smaller ones wait until they add up (it bounds the filter work per team map).
  TeamChannel(int max_landmark_id, double min_gain);

  /// A team estimate (g, G) of landmark `id` in `epoch` (see above), whose
  /// current estimate in the aided filter has covariance P_ll and mean l. True with
  /// the increment to fuse in `out`; false when there is nothing worth fusing (or G
  /// is not a covariance). An epoch other than the one fused so far counts from zero.
  bool offer(int id, int epoch, const Eigen::Vector2d& g, const Eigen::Matrix2d& G, const Eigen::Vector2d& l,
             const Eigen::Matrix2d& P_ll, TeamIncrement* out) const;
  /// The increment `inc` of landmark `id` was fused: count it.
  void commit(int id, const TeamIncrement& inc);

  /// Forget what was fused for `id` (the next estimate is fused whole).
  void forget(int id);
  void clear();

  /// The information fused so far for `id` (zero when none).
  const Eigen::Matrix2d& fused_information(int id) const { return Y_[static_cast<std::size_t>(id)]; }
  const Eigen::Vector2d& fused_vector(int id) const { return y_[static_cast<std::size_t>(id)]; }
  /// The epoch of what was fused for `id` (-1 when nothing).
  int epoch(int id) const { return epoch_[static_cast<std::size_t>(id)]; }
  /// What a state file says was fused for `id` (robot_state.cpp checks it).
  void restore(int id, int epoch, const Eigen::Matrix2d& Y, const Eigen::Vector2d& y);
  int max_landmark_id() const { return static_cast<int>(Y_.size()); }

 private:
  double min_gain_;
  std::vector<Eigen::Matrix2d> Y_;  // per id: information fused
  std::vector<Eigen::Vector2d> y_;  // per id: information vector fused
  std::vector<int> epoch_;          // per id: the epoch of Y_, y_ (-1: none)
};

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// The team map's application to a Robot (Robot::apply_team_map): the gauge test on
// the own and the aided filter, a relocalisation when the robot's map is right in
// itself and wrong as a whole, and the team's estimates fused into the aided filter
// (or held for a candidate). Algorithm 1 itself is in robot.cpp.
#include "elaslam/robot_node/robot.hpp"

#include "elaslam/common/stats.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>

namespace elaslam {

bool Robot::team_eligible(int id) const {
  return filters_.has_aided() && lmap_.valid_id(id) && lmap_[id].status == LandmarkStatus::kStatic && filters_.aided().has_landmark(id);
}

const char* to_string(TeamVerdict v) {
  switch (v) {
    case TeamVerdict::kNone: return "none";
    case TeamVerdict::kHeld: return "held";
    case TeamVerdict::kLost: return "lost";
    case TeamVerdict::kRelocalised: return "relocalised";
  }
  return "?";
}

// The gauge test on filter `f` (rigid_fit.hpp): the team's estimates of the
// landmarks the robot holds as STATIC, each tested against f's (the team-map test,
// team_map_gate_probability); when at least kTeamMinTested were tested and more
// than half disagree, the weighted rigid motion that carries f's estimates onto the
// team's. It fires when more than half agree after it, and jointly, at the same
// probability: the motion explains the disagreement (its likelihood ratio against no
// motion, 3 dof) and leaves nothing unexplained (the cost after it, 2n - 3 dof).
Robot::GaugeTest Robot::gauge_test(const EkfSlam& f, const TeamEstimate* estimates, int n) {
  GaugeTest g;
  pairs_.clear();  // reserved: one per slot of the filter, and eligible ones are held
  double cost_before = 0.0;  // the sum of the d2: the cost of no motion
  for (int k = 0; k < n; ++k) {
    const TeamEstimate& e = estimates[k];
    if (!team_eligible(e.landmark_id) || !f.has_landmark(e.landmark_id) || pairs_.size() >= pairs_.capacity()) continue;
    PointPair p;
    p.a = f.landmark(e.landmark_id);
    p.A = f.landmark_cov(e.landmark_id);
    p.b = e.position;
    p.B = e.cov;
    const double d2 = f.check_position(e.landmark_id, e.position, e.cov).d2;
    g.disagreed += d2 > team_gate_threshold_ ? 1 : 0;
    cost_before += d2;
    pairs_.push_back(p);
  }
  g.tested = static_cast<int>(pairs_.size());
  if (g.tested < kTeamMinTested || 2 * g.disagreed <= g.tested) return g;
  if (!fit_rigid_motion(pairs_.data(), g.tested, &g.motion)) return g;
  for (const PointPair& p : pairs_) g.agreed_after += aligned_d2(p, g.motion) <= team_gate_threshold_ ? 1 : 0;
  const double prob = options_.team_map_gate_probability;
  g.fires = 2 * g.agreed_after > g.tested && cost_before - g.motion.cost > chi2_quantile(prob, 3) &&
            g.motion.cost <= chi2_quantile(prob, 2 * g.tested - 3);
  return g;
}

TeamVerdict Robot::apply_team_map(const TeamEstimate* estimates, int n) {
  if (!filters_.has_aided()) return TeamVerdict::kNone;
  // The robot is wrong as a whole when both its filters are: the own one (what it
  // reports, what its gate runs on; the team map is the fusion of the others' own
  // maps, like with like) and the aided one each fail the team map and are carried
  // onto it by one rigid motion, the same for both (their motions agree within their
  // covariances, at the same probability). A robot whose aided filter the team's
  // estimates kept right, or whose two filters disagree with each other, is not
  // moved: then it is likelier the team's own maps that drifted together (a turn
  // bias every odometer shares turns every own map the same way;
  // docs/adr/0029-gauge-test.md).
  GaugeTest own;
  if (options_.team_map_gauge_test) own = gauge_test(filters_.own(), estimates, n);
  if (own.fires) {
    const GaugeTest aided = gauge_test(filters_.aided(), estimates, n);
    const Eigen::Vector3d d(wrap_angle(own.motion.rotation - aided.motion.rotation),
                            own.motion.translation.x() - aided.motion.translation.x(),
                            own.motion.translation.y() - aided.motion.translation.y());
    const Eigen::LDLT<Eigen::Matrix3d> C(own.motion.cov + aided.motion.cov);
    own.fires = aided.fires && C.info() == Eigen::Success &&
                d.dot(C.solve(d)) <= chi2_quantile(options_.team_map_gate_probability, 3);
    if (own.fires) relocalise(own, aided);
  }
  int tested = 0, disagree = 0;
  for (int k = 0; k < n; ++k) {
    const TeamEstimate& e = estimates[k];
    if (!team_eligible(e.landmark_id)) continue;
    ++tested;
    if (filters_.aided().check_position(e.landmark_id, e.position, e.cov).d2 > team_gate_threshold_) ++disagree;
  }
  team_counters_.offered += tested;
  // Candidates' estimates are held, never fused now: whatever the verdict, and also
  // when the robot holds nothing STATIC yet.
  if (options_.team_map_hold_candidates && filters_.aided_history().enabled())
    for (int k = 0; k < n; ++k) hold_team_estimate(estimates[k]);
  if (tested == 0 && !own.fires) return TeamVerdict::kNone;
  TeamVerdict verdict = own.fires ? TeamVerdict::kRelocalised : TeamVerdict::kHeld;
  const bool trouble = trouble_frame_ >= 0 && last_frame_ - trouble_frame_ <= kTroubleMemoryFrames;
  if (!own.fires && tested >= kTeamMinTested && 2 * disagree > tested && trouble) {
    // Most of it disagrees and the robot saw trouble itself lately: the robot, not
    // the team, is wrong.
    verdict = TeamVerdict::kLost;
    ++team_counters_.lost;
  }
  for (int k = 0; k < n; ++k)
    if (team_eligible(estimates[k].landmark_id))
      fuse_team_estimate(estimates[k], /*test=*/verdict != TeamVerdict::kLost);
  return verdict;
}

// Each motion is taken as exact: the state moves, its covariance turns with it and
// grows by nothing. The robot's covariance already holds the uncertainty of the
// pose it lost (it drifted without landmarks); the team's estimates fused next into
// the aided filter (tested, now that they agree) are the information its fit used,
// counted once. The L-map's positions are the own filter's (record_sighting).
void Robot::relocalise(const GaugeTest& own, const GaugeTest& aided) {
  const RigidMotion& T = own.motion;
  if (filters_.apply_rigid_motion(T.rotation, T.translation, aided.motion.rotation, aided.motion.translation) !=
      EkfStatus::kOk)
    return;
  lmap_.apply_rigid_motion(T.rotation, T.translation);
  tracks_.clear();  // estimated in the frame the motion corrects
  filters_.restart_history();
  monitor_.restart();
  trouble_frame_ = -1;
  ++team_counters_.relocalised;
  relocalisation_ = Relocalisation{};
  relocalisation_.frame = last_frame_;
  relocalisation_.rotation = T.rotation;
  relocalisation_.translation = T.translation;
  relocalisation_.rotation_sigma = std::sqrt(std::max(0.0, T.cov(0, 0)));
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> t_cov(T.cov.bottomRightCorner<2, 2>(), Eigen::EigenvaluesOnly);
  relocalisation_.translation_sigma = std::sqrt(std::max(0.0, t_cov.eigenvalues()(1)));
  relocalisation_.shared = own.tested;
  relocalisation_.disagreed = own.disagreed;
  relocalisation_.agreed_after = own.agreed_after;
}

// A team estimate that contradicts the robot's own (its chi-square test at
// team_map_gate_probability) is not fused unless the robot was found lost; nothing
// is counted as fused then, and the next team map tries again.
bool Robot::fuse_team_estimate(const TeamEstimate& e, bool test) {
  if (test && filters_.aided().check_position(e.landmark_id, e.position, e.cov).d2 > team_gate_threshold_) {
    ++team_counters_.gated;
    return false;
  }
  TeamIncrement inc;
  // The epoch: how many times this robot has known the landmark to move (team_aid.hpp).
  if (!team_.offer(e.landmark_id, lmap_[e.landmark_id].times_moving, e.position, e.cov, filters_.aided().landmark(e.landmark_id),
                   filters_.aided().landmark_cov(e.landmark_id), &inc))
    return false;
  const UpdateReport r = filters_.update_aided_position(last_frame_, e.landmark_id, inc.z, inc.R);
  if (r.status != EkfStatus::kOk) {
    ++team_counters_.refused;
    return false;
  }
  team_.commit(e.landmark_id, inc);
  ++team_counters_.fused;
  team_counters_.nis_sum += r.d2;
  return true;
}

// A candidate's team estimate (team_map_hold_candidates): the robot does not trust
// the landmark yet, so the team's estimate of it must not move the pose yet either;
// but the filter history makes a confirmed candidate's sightings count from its
// first one (confirm), and the team estimate that came meanwhile is one more of
// them. Tested like a STATIC landmark's (the aided filter's candidate estimate
// against the team's), it is kept in the aided history as an operation that does
// nothing; confirmed within the window, it becomes the position update it would
// have been (FilterHistory::upgrade) and the channel commits it; a candidate that
// starts over or leaves drops it. The increment is taken against the channel as it
// is: the newest held one carries everything the channel has not counted.
bool Robot::hold_team_estimate(const TeamEstimate& e) {
  const int id = e.landmark_id;
  if (!lmap_.valid_id(id) || lmap_[id].status != LandmarkStatus::kCandidate || !filters_.aided().has_landmark(id)) return false;
  if (filters_.aided().check_position(id, e.position, e.cov).d2 > team_gate_threshold_) {
    ++team_counters_.gated;
    return false;
  }
  TeamIncrement inc;
  if (!team_.offer(id, lmap_[id].times_moving, e.position, e.cov, filters_.aided().landmark(id), filters_.aided().landmark_cov(id), &inc))
    return false;
  filters_.hold_aided_position(last_frame_, id, inc.z, inc.R);
  ++team_counters_.held;
  return true;
}

}  // namespace elaslam

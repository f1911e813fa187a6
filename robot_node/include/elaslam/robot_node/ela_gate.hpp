// SPDX-License-Identifier: Apache-2.0
// The expected landmark area (ELA) gate (paper section 3.3, eq 16; docs/design.md
// section 4) and the pairwise relative-vector test that `consensus` mode builds on.
// ElaGate decides, per frame, one verdict for every mapped landmark in view and for
// every candidate sighting, and keeps one record of the test that decided it.
//
// Everything is computed in the robot frame B: a landmark's local position m_i
// comes straight from its range and bearing, and the map's relative vector
// d_ij = l_i - l_j (mean and covariance from P) is rotated into B by the heading
// estimate. The robot's position error cancels; only its heading error enters.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "elaslam/robot_node/consensus.hpp"
#include "elaslam/robot_node/ekf_slam.hpp"
#include "elaslam/robot_node/lmap.hpp"
#include "elaslam/robot_node/robot_options.hpp"

namespace elaslam {

/// A mapped (STATIC) landmark observed in this frame.
struct InView {
  int id = -1;
  RangeBearing z;
  Eigen::Vector2d m = Eigen::Vector2d::Zero();  // [m] local position p_LinB from z
  Eigen::Matrix2d M = Eigen::Matrix2d::Zero();  // [m^2] its covariance (measurement noise only)
};

/// Fill m and M of an InView from its measurement and the measurement noise W.
void set_local(InView* v, const Eigen::Matrix2d& W);

/// Which test decided an observation's verdict.
enum class GateKind : std::uint8_t {
  kNone = 0,        // not tested (mode ekf)
  kInnovation,      // innovation chi-square test against the EKF prior (gated mode, single ELA)
  kMulti,           // eq 16: fused ELA from the other landmarks in view
  kConsensus,       // in the largest mutually consistent set (d2 0), or re-tested against it by eq 16
  kCandidate,       // candidate re-sighting consistency (innovation against the candidate's anchor)
  kDrift,           // STATIC landmark's drift test: |s|^2 (1 - lambda^2), s its weighted innovation sum
  kCandidateDrift,  // candidate's drift test: |sum|^2 / n over its consistent sightings
};
const char* to_string(GateKind k);

/// The numbers behind one verdict, kept for every tested observation: the test that
/// decided it, its statistic and its threshold, so that inside == (d2 <= threshold)
/// for every kind but kNone. Outputs for tests and diagnostics; no decision reads them.
struct GateRecord {
  int landmark_id = -1;
  GateKind kind = GateKind::kNone;
  double d2 = 0.0;         // the test's statistic (a Mahalanobis distance squared)
  double threshold = 0.0;  // chi-square quantile it was compared with
  bool inside = true;      // verdict
};

/// The verdict on a mapped landmark in view.
struct ElaVerdict {
  bool inside = true;  // inside its ELA: it corrects the filter
  /// Judged by the single-landmark test (nothing in view agreed to compare it with):
  /// it cannot tell its own motion from the robot's pose error (`lone_verdicts`).
  bool alone = false;
};

/// Mahalanobis distance squared of the pair (i, j): (m_i - m_j) - R^T d_ij against
/// M_i + M_j + R^T S_ij R + the heading's share (its variance and its covariance with
/// d_ij). Symmetric in i and j.
double pair_d2(const EkfSlam& ekf, const InView& i, const InView& j);

/// The weight of neighbour j in eq 16's fusion: the information of its own share
/// of any prediction it makes, (M_j + R^T P_jj R)^-1 (its observation's noise and
/// its map uncertainty, in the robot frame); zero when that is not positive
/// definite. It depends on j alone, which makes the exact residual covariance of
/// every landmark in view O(n^2) for the whole view (docs/adr/0034-eq16-neighbour-weights.md).
Eigen::Matrix2d neighbour_weight(const EkfSlam& ekf, const InView& j);

/// Eq 16: the ELA of view[i] as the fusion of the predictions of it from every
/// other landmark in view (only those with active[j] != 0 when `active` is given),
/// p_ij = m_j + R^T (l_i - l_j), weighted by neighbour_weight; returns d2 of m_i
/// against it. The covariance of the residual is computed exactly, to first order,
/// from the joint covariance of the heading and the landmarks (the predictions share
/// l_i, the heading and correlated map errors; the map's errors are correlated with
/// the heading's), so that a static landmark fails at the gate's nominal rate.
/// The reference for ElaGate's O(n^2)-per-view computation: O(n^2) per landmark.
double ela_multi_d2(const EkfSlam& ekf, const InView* view, int n, int i, const std::uint8_t* active = nullptr);

/// Steps 2-3 of docs/design.md section 4 for one frame: which observations are inside
/// their ELA. Every mapped landmark in view is judged against the same prior (the
/// filter before this frame's corrections) by eq 16 (modes ela), the consensus
/// clique (mode consensus) or, with no other landmark to compare with, the
/// single-landmark test; then by the drift test. Candidates are judged one by one,
/// each against the filter as the frame has left it so far. Fixed memory after
/// construction.
class ElaGate {
 public:
  explicit ElaGate(const RobotOptions& options);

  /// Start a frame: no landmark in view, no records.
  void clear();
  /// A STATIC landmark observed in this frame (in observation order).
  void add_to_view(int id, const RangeBearing& z);
  /// Judge every landmark in view against the filter's prior. Updates the L-map's
  /// drift sums of the landmarks that passed (drift_memory > 0).
  void judge_view(const EkfSlam& ekf, LMap* lmap);
  int view_size() const { return static_cast<int>(view_.size()); }
  const InView& in_view(int k) const { return view_[static_cast<std::size_t>(k)]; }
  ElaVerdict verdict(int k) const { return verdicts_[static_cast<std::size_t>(k)]; }

  /// A candidate's re-sighting, `r` its innovation against the filter now: true when
  /// consistent. With candidate_drift_test, a consistent sighting also adds to the
  /// L-map's innovation sum of the candidate, whose test must pass too.
  bool judge_candidate(int id, const UpdateReport& r, LMap* lmap);

  /// Modes ekf and gated: the filter's own gate decided (EkfSlam::update).
  void record(const GateRecord& g) { records_.push_back(g); }
  /// This frame's records: the landmarks in view first (view order), then the rest.
  const std::vector<GateRecord>& records() const { return records_; }
  /// Frames so far in which eq 16's set-aside landmarks outnumbered and outvoted
  /// the kept ones (judge_eq16) and became the reference (tests, diagnostics).
  long regroups() const { return regroups_; }
  /// Mode consensus: the solver of this frame's view (tests, diagnostics).
  const ConsensusSolver& consensus() const { return solver_; }

 private:
  void judge_eq16(const EkfSlam& ekf);
  void prepare_eq16(const EkfSlam& ekf);
  void set_aside_eq16(int m);
  int settle_eq16(int active);
  double eq16_d2(int i) const;
  void judge_consensus(const EkfSlam& ekf);
  void set_joint_prior(const EkfSlam& ekf);
  void judge_drift(LMap* lmap);
  void decide(int k, const GateRecord& g, bool alone);
  void decide_alone(int k);
  double prior_d2(int k) const;
  bool worse(int a, int b) const;

  Mode mode_;
  double ela_threshold_;    // chi2(ela_gate_probability, 2 dof): eq 16, pairs, single, candidates
  double drift_lambda_;     // drift_memory (0: no drift test)
  double drift_scale_;      // 1 - lambda^2: the covariance of the sum is I / (1 - lambda^2)
  double drift_threshold_;  // chi2(drift_gate_probability, 2 dof)
  bool candidate_drift_;
  long regroups_ = 0;
  ConsensusSolver solver_;
  // Per frame, reserved at construction (one entry per landmark in view).
  std::vector<InView> view_;
  std::vector<UpdateReport> prior_;  // innovation against this frame's prior
  std::vector<double> d2_;           // eq 16 d2
  std::vector<std::uint8_t> mask_;   // who shapes the others' ELAs (eq 16 survivors / the clique)
  std::vector<std::uint8_t> kept_;   // judge_eq16: the first survivors, while the set-aside ones are re-tested
  std::vector<double> kept_d2_;      // and their d2
  std::vector<ElaVerdict> verdicts_;
  std::vector<GateRecord> records_;  // view first, then candidates / classic observations
  std::vector<Eigen::Matrix<double, 2, 3>> Hx_;  // per landmark in view: the observation's Jacobians
  std::vector<Eigen::Matrix2d> Hl_;
  // Eq 16 for the whole view at once (judge_eq16; the same numbers as ela_multi_d2).
  // The weights b_j depend on the neighbour alone, so every sum over a landmark's
  // neighbours is a sum over the active set minus its own term: the active set's
  // totals, and per landmark v_i = sum_k Q_ik b_k over the active set. Setting a
  // landmark aside subtracts its terms, O(n); the whole view costs O(n^2).
  struct Eq16Totals {
    Eigen::Matrix2d Lambda, S1, T;  // sum b; sum b M b; sum_jk b_j Q_jk b_k
    Eigen::Vector2d eta, sigma;     // sum b (m - R^T l); sum b D l
    Eigen::RowVector2d S4;          // sum c_j b_j
  };
  std::vector<Eigen::Matrix2d> Q_, b_, v_;  // Q_ij = R^T P_ij R (n x n, row-major); b_j; v_i
  std::vector<Eigen::Vector2d> lm_;         // l_j (world)
  std::vector<Eigen::RowVector2d> c_;       // P_th,lj R
  Eq16Totals tot_;
  Eigen::Matrix2d D_ = Eigen::Matrix2d::Zero();  // d R(th)^T / d th
  Eigen::Matrix2d Rt_ = Eigen::Matrix2d::Identity();
  double var_th_ = 0.0, cos_th_ = 1.0, sin_th_ = 0.0;
};

}  // namespace elaslam

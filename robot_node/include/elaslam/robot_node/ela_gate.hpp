// The expected landmark area (ELA) gate (paper section 3.3, eq 16; DESIGN.md
// section 5) and the pairwise relative-vector test that `consensus` mode builds on.
//
// Everything is computed in the robot frame B: a landmark's local position m_i
// comes straight from its range and bearing, and the map's relative vector
// d_ij = l_i - l_j (mean and covariance from P) is rotated into B by the heading
// estimate. The robot's position error cancels; only its heading error enters.
#pragma once

#include <cstdint>

#include <Eigen/Core>

#include "elaslam/robot_node/ekf_slam.hpp"

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

/// Which test judged an observation.
enum class GateKind : std::uint8_t {
  kNone = 0,    // not tested (mode ekf)
  kInnovation,  // innovation chi-square test against the EKF prior (gated mode, single ELA)
  kMulti,       // eq 16: fused ELA from the other landmarks in view
  kConsensus,   // largest mutually consistent set
  kCandidate,   // candidate re-sighting consistency
};
const char* to_string(GateKind k);

/// The numbers behind one verdict, kept for every tested observation.
struct GateRecord {
  int landmark_id = -1;
  GateKind kind = GateKind::kNone;
  double d2 = 0.0;         // Mahalanobis distance squared
  double threshold = 0.0;  // chi-square quantile it was compared with
  bool inside = true;      // verdict
};

/// A Gaussian prediction of where a landmark should appear in the robot frame.
struct LocalPrediction {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
};

/// Where landmark i should appear, predicted from neighbour j's observation and the
/// map's relative vector: m_j + R(th)^T d_ij, covariance M_j + R^T S_ij R + J s_th^2 J^T
/// with S_ij = P_ii + P_jj - P_ij - P_ji and J = d(R(th)^T d_ij)/d th.
LocalPrediction predict_from_neighbour(const EkfSlam& ekf, int id_i, const InView& j);

/// Mahalanobis distance squared of the pair (i, j): (m_i - m_j) - R^T d_ij against
/// M_i + M_j + R^T S_ij R + heading share. Symmetric in i and j.
double pair_d2(const EkfSlam& ekf, const InView& i, const InView& j);

/// Eq 16: the ELA of view[i] as the product of the Gaussians predicted from every
/// other landmark in view (only those with active[j] != 0 when `active` is given);
/// returns d2 of m_i against it. The mean is the paper's product of Gaussians; the
/// covariance of the residual is computed exactly from its parts (the neighbours'
/// predictions share l_i, the heading and correlated map errors), so that a static
/// landmark fails at the gate's nominal rate. O(n^2) per landmark.
double ela_multi_d2(const EkfSlam& ekf, const InView* view, int n, int i, const std::uint8_t* active = nullptr);

}  // namespace elaslam

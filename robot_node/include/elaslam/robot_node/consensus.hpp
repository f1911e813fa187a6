// SPDX-License-Identifier: Apache-2.0
// `consensus` mode (ours, docs/design.md section 4): pairwise consistency of co-observed
// landmarks' relative vectors and the largest mutually consistent set, found
// exactly (every maximal clique is enumerated; the sets are small).
//
// Co-moving landmarks keep their relative vectors, so a group that moves together
// is a clique too. The choice between cliques therefore also asks the EKF prior:
// a clique whose landmarks jointly agree with the predicted robot pose (the joint
// innovation's d2 within the chi-square quantile for 2k dof) beats one that does
// not; then the larger wins; then the smaller joint d2. The innovations of one frame
// share the pose's error, so the joint d2 uses their joint covariance (set_joint);
// without it, the sum of the single d2s (which, when the pose's uncertainty
// dominates, fires several times more often than the quantile says).
#pragma once

#include <array>
#include <cstdint>

#include <Eigen/Core>

namespace elaslam {

class ConsensusSolver {
 public:
  static constexpr int kMaxNodes = 64;  // one bit per landmark in view

  /// `prior_probability`: probability of the joint prior test (per clique).
  explicit ConsensusSolver(double prior_probability = 0.99);

  /// Start a new graph of n nodes (n <= kMaxNodes), no edges.
  void reset(int n);
  void add_edge(int a, int b);
  /// The prior innovation d2 of node a (2 dof), used to rank cliques.
  void set_prior_d2(int a, double d2) { prior_d2_[static_cast<std::size_t>(a)] = d2; }
  /// The joint prior innovation: node a's innovation, and the 2x2 block (a, b) of the
  /// innovations' joint covariance (H P H^T + W on the diagonal). With every node's
  /// set, the prior test of a clique is the joint d2 (joint(true) before solve()).
  void set_innovation(int a, const Eigen::Vector2d& nu) { nu_.segment<2>(2 * a) = nu; }
  void set_joint_block(int a, int b, const Eigen::Matrix2d& S_ab) { S_.block<2, 2>(2 * a, 2 * b) = S_ab; }
  void joint(bool on) { joint_ = on; }

  /// Solve: the chosen set as a bit mask (bit a = node a is in the set).
  std::uint64_t solve();

  /// Number of maximal cliques visited by the last solve (for tests and stats).
  int cliques_visited() const { return visited_; }
  /// Whether the chosen set passed the joint prior test.
  bool chosen_agrees_with_prior() const { return best_prior_ok_; }
  /// The joint prior d2 of a set of nodes (bit a = node a): nu^T S^-1 nu over their
  /// innovations with the joint covariance; +inf when it is not positive definite or
  /// a node has no innovation. Needs set_joint. O(k^3), no allocation.
  double clique_d2(std::uint64_t clique) const;

 private:
  void bron_kerbosch(std::uint64_t R, std::uint64_t P, std::uint64_t X);
  void consider(std::uint64_t clique);

  int n_ = 0;
  std::array<std::uint64_t, kMaxNodes> adj_{};
  std::array<double, kMaxNodes> prior_d2_{};
  std::array<double, kMaxNodes + 1> joint_threshold_{};  // chi2 quantile, 2k dof, k = 0..64
  std::uint64_t best_ = 0;
  bool best_prior_ok_ = false;
  int best_size_ = 0;
  double best_sum_ = 0.0;
  int visited_ = 0;
  // Joint prior test (allocated at construction; a clique's block is copied into
  // work_ and factorised in place).
  bool joint_ = false;
  Eigen::MatrixXd S_;
  Eigen::VectorXd nu_;
  mutable Eigen::MatrixXd work_;
  mutable Eigen::VectorXd v_;
};

}  // namespace elaslam

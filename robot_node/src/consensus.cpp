// SPDX-License-Identifier: Apache-2.0
#include "elaslam/robot_node/consensus.hpp"

#include <array>
#include <limits>
#include <mutex>

#include <Eigen/Cholesky>

#include "elaslam/common/stats.hpp"

namespace elaslam {

namespace {

// The joint test's thresholds depend on the probability alone: made once per
// probability (64 quantiles by bisection: a node made per fuzz input spent 18 % of
// its time here), shared by every solver of the process (sweep's threads too).
std::array<double, ConsensusSolver::kMaxNodes + 1> joint_thresholds(double p) {
  static std::mutex m;
  static double cached_p = std::numeric_limits<double>::quiet_NaN();
  static std::array<double, ConsensusSolver::kMaxNodes + 1> cached{};
  const std::lock_guard<std::mutex> lock(m);
  if (!(p == cached_p)) {
    cached[0] = 0.0;
    for (int k = 1; k <= ConsensusSolver::kMaxNodes; ++k) cached[static_cast<std::size_t>(k)] = chi2_quantile(p, 2 * k);
    cached_p = p;
  }
  return cached;
}

}  // namespace

ConsensusSolver::ConsensusSolver(double prior_probability)
    : joint_threshold_(joint_thresholds(prior_probability)),
      S_(2 * kMaxNodes, 2 * kMaxNodes),
      nu_(2 * kMaxNodes),
      work_(2 * kMaxNodes, 2 * kMaxNodes),
      v_(2 * kMaxNodes) {}

void ConsensusSolver::reset(int n) {
  n_ = n < 0 ? 0 : (n > kMaxNodes ? kMaxNodes : n);
  adj_.fill(0);
  prior_d2_.fill(0.0);
  joint_ = false;
}

void ConsensusSolver::add_edge(int a, int b) {
  if (a == b || a < 0 || b < 0 || a >= n_ || b >= n_) return;
  adj_[static_cast<std::size_t>(a)] |= std::uint64_t{1} << b;
  adj_[static_cast<std::size_t>(b)] |= std::uint64_t{1} << a;
}

std::uint64_t ConsensusSolver::solve() {
  best_ = 0;
  best_prior_ok_ = false;
  best_size_ = 0;
  best_sum_ = std::numeric_limits<double>::infinity();
  visited_ = 0;
  if (n_ == 0) return 0;
  const std::uint64_t all = n_ == 64 ? ~std::uint64_t{0} : ((std::uint64_t{1} << n_) - 1);
  bron_kerbosch(0, all, 0);
  return best_;
}

// Bron-Kerbosch with Tomita pivoting on bit sets: no allocation, recursion depth <= 64.
void ConsensusSolver::bron_kerbosch(std::uint64_t R, std::uint64_t P, std::uint64_t X) {
  if (P == 0 && X == 0) {
    consider(R);
    return;
  }
  // Pivot: the vertex of P | X with most neighbours in P.
  int pivot = -1, most = -1;
  for (std::uint64_t px = P | X; px; px &= px - 1) {
    const int u = __builtin_ctzll(px);
    const int c = __builtin_popcountll(P & adj_[static_cast<std::size_t>(u)]);
    if (c > most) most = c, pivot = u;
  }
  for (std::uint64_t cand = P & ~adj_[static_cast<std::size_t>(pivot)]; cand; cand &= cand - 1) {
    const int v = __builtin_ctzll(cand);
    const std::uint64_t bit = std::uint64_t{1} << v;
    const std::uint64_t nv = adj_[static_cast<std::size_t>(v)];
    bron_kerbosch(R | bit, P & nv, X & nv);
    P &= ~bit;
    X |= bit;
  }
}

// The clique's joint prior d2: nu_C^T S_C^-1 nu_C over its nodes' innovations (their
// errors share the pose's). O(k^3) for k nodes, in place, no allocation. +inf when
// S_C is not positive definite or a node has no innovation.
double ConsensusSolver::clique_d2(std::uint64_t clique) const {
  const Eigen::Index m = 2 * __builtin_popcountll(clique);
  Eigen::Index r = 0;
  for (std::uint64_t a = clique; a; a &= a - 1, r += 2) {
    const int i = __builtin_ctzll(a);
    if (!(prior_d2_[static_cast<std::size_t>(i)] < 1e12)) return std::numeric_limits<double>::infinity();
    v_.segment<2>(r) = nu_.segment<2>(2 * i);
    Eigen::Index c = 0;
    for (std::uint64_t b = clique; b; b &= b - 1, c += 2)
      work_.block<2, 2>(r, c) = S_.block<2, 2>(2 * i, 2 * __builtin_ctzll(b));
  }
  Eigen::Ref<Eigen::MatrixXd> block = work_.topLeftCorner(m, m);
  const Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(block);
  if (llt.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
  auto v = v_.head(m);
  llt.matrixL().solveInPlace(v);
  return v.squaredNorm();
}

void ConsensusSolver::consider(std::uint64_t clique) {
  ++visited_;
  const int size = __builtin_popcountll(clique);
  double sum = 0.0;
  if (joint_) {
    sum = clique_d2(clique);
  } else {
    for (std::uint64_t c = clique; c; c &= c - 1) sum += prior_d2_[static_cast<std::size_t>(__builtin_ctzll(c))];
  }
  const bool prior_ok = sum <= joint_threshold_[static_cast<std::size_t>(size)];
  const bool better = (prior_ok != best_prior_ok_) ? prior_ok
                      : (size != best_size_)       ? size > best_size_
                                                   : sum < best_sum_;
  if (better) {
    best_ = clique;
    best_prior_ok_ = prior_ok;
    best_size_ = size;
    best_sum_ = sum;
  }
}

}  // namespace elaslam

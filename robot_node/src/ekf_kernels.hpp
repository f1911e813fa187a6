// The O(n) and O(n^2) loops of EkfSlam's correction, on raw column pointers
// (private to robot_node/src/ekf_slam.cpp). Written as plain loops with restrict
// parameters so that the compiler vectorises them; nothing here allocates.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Core>

namespace elaslam {
namespace {

using Index = Eigen::Index;
using Matrix25 = Eigen::Matrix<double, 2, 5>;

// A variance may come out this far below zero from rounding alone (relative to the
// prior variance, plus an absolute (1 um)^2 / (1 urad)^2) before it counts as a
// fault. Anything more negative means P was not positive semi-definite.
constexpr double kNegativeVarianceRelTol = 1e-9;
constexpr double kNegativeVarianceAbsTol = 1e-12;
// |a_i| * |b_j| below this cannot overflow when two such products are summed.
constexpr double kMaxProduct = 1e300;

// Runtime dispatch for the O(n^2) kernels below: on x86-64 the loader picks an
// AVX2+FMA build when the CPU has it (about 1.5-2x faster than SSE2), else the
// baseline SSE2 build. The rank-4 kernel also gets an AVX-512 build: its four
// columns of factors need more than AVX2's 16 vector registers (about 20% faster
// on the benchmark machine, docs/benchmarks.md). Other targets get the plain build.
#if defined(__x86_64__) && defined(__linux__) && defined(__GNUC__) && !defined(__clang__) && \
    (__GNUC__ >= 11) && !defined(ELASLAM_NO_MULTIVERSION)
#define ELASLAM_MULTIVERSION __attribute__((target_clones("arch=x86-64-v3", "default")))
#define ELASLAM_MULTIVERSION_512 \
  __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define ELASLAM_MULTIVERSION
#define ELASLAM_MULTIVERSION_512
#endif

inline double dot2(double u0, double u1, double v0, double v1) { return u0 * v0 + u1 * v1; }

// The covariance downdates touch the lower triangle only (P is symmetric; the
// upper triangle is completed on demand), column by column, four columns at a time
// so that each row's factors are loaded once. A panel of four columns starts at
// the row of its first column: the few upper entries inside the diagonal 4x4 tile
// are updated too, which is harmless.

// P(i, j) -= A_i . A_j for i >= j, A = [a0 a1] (n x 2).
ELASLAM_MULTIVERSION void lower_rank2_downdate(double* __restrict P, Index ld, Index n,
                                               const double* __restrict a0,
                                               const double* __restrict a1) {
  Index j = 0;
  for (; j + 4 <= n; j += 4) {
    double* __restrict c0 = P + j * ld;
    double* __restrict c1 = c0 + ld;
    double* __restrict c2 = c1 + ld;
    double* __restrict c3 = c2 + ld;
    for (Index i = j; i < n; ++i) {
      c0[i] -= dot2(a0[i], a1[i], a0[j], a1[j]);
      c1[i] -= dot2(a0[i], a1[i], a0[j + 1], a1[j + 1]);
      c2[i] -= dot2(a0[i], a1[i], a0[j + 2], a1[j + 2]);
      c3[i] -= dot2(a0[i], a1[i], a0[j + 3], a1[j + 3]);
    }
  }
  for (; j < n; ++j) {
    double* __restrict c = P + j * ld;
    for (Index i = j; i < n; ++i) c[i] -= dot2(a0[i], a1[i], a0[j], a1[j]);
  }
}

// One entry of the rank-4 downdate: one subtraction per product (four fused
// multiply-adds with FMA). The factors of column j come in as scalars.
inline double rank4_entry(double p, double a0, double a1, double b0, double b1, double a0j,
                          double a1j, double b0j, double b1j) {
  p -= a0 * b0j;
  p -= a1 * b1j;
  p -= b0 * a0j;
  p -= b1 * a1j;
  return p;
}

// P(i, j) -= A_i . B_j + B_i . A_j for i >= j, A = [a0 a1], B = [b0 b1] (n x 2).
ELASLAM_MULTIVERSION_512 void lower_rank4_downdate(double* __restrict P, Index ld, Index n,
                                                   const double* __restrict a0,
                                                   const double* __restrict a1,
                                                   const double* __restrict b0,
                                                   const double* __restrict b1) {
  Index j = 0;
  for (; j + 4 <= n; j += 4) {
    double* __restrict c0 = P + j * ld;
    double* __restrict c1 = c0 + ld;
    double* __restrict c2 = c1 + ld;
    double* __restrict c3 = c2 + ld;
    for (Index i = j; i < n; ++i) {
      const double x0 = a0[i], x1 = a1[i], y0 = b0[i], y1 = b1[i];
      c0[i] = rank4_entry(c0[i], x0, x1, y0, y1, a0[j], a1[j], b0[j], b1[j]);
      c1[i] = rank4_entry(c1[i], x0, x1, y0, y1, a0[j + 1], a1[j + 1], b0[j + 1], b1[j + 1]);
      c2[i] = rank4_entry(c2[i], x0, x1, y0, y1, a0[j + 2], a1[j + 2], b0[j + 2], b1[j + 2]);
      c3[i] = rank4_entry(c3[i], x0, x1, y0, y1, a0[j + 3], a1[j + 3], b0[j + 3], b1[j + 3]);
    }
  }
  for (; j < n; ++j) {
    double* __restrict c = P + j * ld;
    for (Index i = j; i < n; ++i) {
      c[i] = rank4_entry(c[i], a0[i], a1[i], b0[i], b1[i], a0[j], a1[j], b0[j], b1[j]);
    }
  }
}

// P(j, i) = P(i, j) for i > j, in square tiles so that both sides stay in cache.
void mirror_lower_to_upper(double* P, Index ld, Index n) {
  constexpr Index kTile = 8;
  for (Index j0 = 0; j0 < n; j0 += kTile) {
    const Index j1 = std::min(j0 + kTile, n);
    for (Index i0 = j0; i0 < n; i0 += kTile) {
      const Index i1 = std::min(i0 + kTile, n);
      for (Index i = i0; i < i1; ++i) {
        for (Index j = j0; j < std::min(j1, i); ++j) P[i * ld + j] = P[j * ld + i];
      }
    }
  }
}

// Row by row (O(n)): P H^T from the robot columns r0..r2 and the landmark columns
// l0, l1 of P, then K (Joseph) or M (standard) into k0, k1, and B (Joseph) into
// b0, b1; see EkfSlam::compute_gain. The coefficients are plain locals and the
// arrays restrict parameters, so that the loop vectorises (GCC honours restrict
// on parameters, not on locals).
struct GainCoefficients {
  double h0[5], h1[5];       // the rows of [H_x H_l]
  double i00, i11, l10;      // 1 / L00, 1 / L11, L10 of the Cholesky factor of Z
  double z00, z01, z11;      // Z / 2
};

GainCoefficients gain_coefficients(const Matrix25& H, const Eigen::Matrix2d& L) {
  GainCoefficients c{};
  for (int k = 0; k < 5; ++k) {
    c.h0[k] = H(0, k);
    c.h1[k] = H(1, k);
  }
  // Reciprocals: four divisions per row would cost more than the rest of it.
  c.i00 = 1.0 / L(0, 0);
  c.i11 = 1.0 / L(1, 1);
  c.l10 = L(1, 0);
  const Eigen::Matrix2d half_Z = 0.5 * L * L.transpose();
  c.z00 = half_Z(0, 0);
  c.z01 = half_Z(0, 1);
  c.z11 = half_Z(1, 1);
  return c;
}

ELASLAM_MULTIVERSION void gain_rows_standard(const GainCoefficients c, Index n, const double* __restrict r0,
                        const double* __restrict r1, const double* __restrict r2,
                        const double* __restrict l0, const double* __restrict l1,
                        double* __restrict k0, double* __restrict k1) {
  for (Index i = 0; i < n; ++i) {
    const double p0 = c.h0[0] * r0[i] + c.h0[1] * r1[i] + c.h0[2] * r2[i] + c.h0[3] * l0[i] +
                      c.h0[4] * l1[i];
    const double p1 = c.h1[0] * r0[i] + c.h1[1] * r1[i] + c.h1[2] * r2[i] + c.h1[3] * l0[i] +
                      c.h1[4] * l1[i];
    const double m0 = p0 * c.i00;  // m_i = L^-1 (P H^T)_i
    k0[i] = m0;
    k1[i] = (p1 - c.l10 * m0) * c.i11;
  }
}

ELASLAM_MULTIVERSION void gain_rows_joseph(const GainCoefficients c, Index n, const double* __restrict r0,
                      const double* __restrict r1, const double* __restrict r2,
                      const double* __restrict l0, const double* __restrict l1,
                      double* __restrict k0, double* __restrict k1, double* __restrict b0,
                      double* __restrict b1) {
  for (Index i = 0; i < n; ++i) {
    const double p0 = c.h0[0] * r0[i] + c.h0[1] * r1[i] + c.h0[2] * r2[i] + c.h0[3] * l0[i] +
                      c.h0[4] * l1[i];
    const double p1 = c.h1[0] * r0[i] + c.h1[1] * r1[i] + c.h1[2] * r2[i] + c.h1[3] * l0[i] +
                      c.h1[4] * l1[i];
    const double m0 = p0 * c.i00, m1 = (p1 - c.l10 * m0) * c.i11;  // m_i = L^-1 (P H^T)_i
    const double g1 = m1 * c.i11, g0 = (m0 - c.l10 * g1) * c.i00;  // k_i = L^-T m_i
    k0[i] = g0;
    k1[i] = g1;
    b0[i] = p0 - (g0 * c.z00 + g1 * c.z01);  // b_i = (P H^T)_i - (K Z)_i / 2
    b1[i] = p1 - (g0 * c.z01 + g1 * c.z11);
  }
}

// The checks of EkfSlam::correction_healthy, row by row: x_i + a_i . v and
// P_ii - scale * a_i . b_i (P_ii at stride `diag_stride`), and max|a| * max|b|.
// Branch-free reductions so that the loop vectorises: a NaN or an infinity
// anywhere makes `sum` non-finite; the variance margins are checked by their
// minimum.
ELASLAM_MULTIVERSION bool rows_healthy(Index n, const double* __restrict P, Index diag_stride,
                                       const double* __restrict x, const double* __restrict a0,
                                       const double* __restrict a1, const double* __restrict b0,
                                       const double* __restrict b1, double v0, double v1,
                                       double scale) {
  double sum = 0.0, margin = 0.0, a_max = 0.0, b_max = 0.0;
  for (Index i = 0; i < n; ++i) {
    const double p = P[i * diag_stride];
    const double p_new = p - scale * dot2(a0[i], a1[i], b0[i], b1[i]);
    const double x_new = x[i] + dot2(a0[i], a1[i], v0, v1);
    sum += p_new + x_new;
    margin = std::min(margin, p_new + (kNegativeVarianceRelTol * p + kNegativeVarianceAbsTol));
    a_max = std::max(a_max, std::max(std::abs(a0[i]), std::abs(a1[i])));
    b_max = std::max(b_max, std::max(std::abs(b0[i]), std::abs(b1[i])));
  }
  return std::isfinite(sum) && margin >= 0.0 && a_max * b_max < kMaxProduct;
}

}  // namespace
}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
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

// Runtime dispatch for the O(n) kernels below: on x86-64 the loader picks an
// AVX-512 or AVX2+FMA build when the CPU has it, else the baseline SSE2 build. The O(n^2)
// covariance step (lower_factor_downdate) has its own AVX-512 and AVX2 builds,
// chosen per call. Other targets and compilers get the plain build.
#if defined(__x86_64__) && defined(__linux__) && defined(__GNUC__) && !defined(__clang__) && \
    (__GNUC__ >= 11) && !defined(ELASLAM_NO_MULTIVERSION)
#define ELASLAM_MULTIVERSION __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define ELASLAM_MULTIVERSION
#endif

inline double dot2(double u0, double u1, double v0, double v1) { return u0 * v0 + u1 * v1; }

// ---- the frame's covariance step: P -= A B^T on the lower triangle, once ---------------
//
// A frame's corrections are collected as factors (EkfSlam::update) and applied
// here in one pass over the lower triangle: P(i, j) -= sum_q A(i, q) B(j, q) for
// i >= j, A and B n x m, column-major with stride ldf (B == A for the symmetric
// form). Register tiles of R rows x C columns: each tile of P is loaded once, the
// m products accumulate in registers, and it is stored once. A tile starting on
// the diagonal also updates the few upper entries inside it, which is harmless (the
// upper triangle is a cache, EkfSlam::complete_upper_triangle). The last tile of a
// panel may have fewer than R rows: it is computed on all R (A's columns must have
// R - 1 readable rows past n; whatever they hold is discarded) and only its rows
// inside P are loaded and stored.
template <int R, int C, bool kFull>
__attribute__((always_inline)) inline void factor_tile(double* __restrict P, Index ld, Index i, Index j, int rows,
                                                       const double* __restrict A, const double* __restrict B,
                                                       Index ldf, Index m) {
  double acc[C][R];
  for (int c = 0; c < C; ++c)
    for (int r = 0; r < R; ++r) acc[c][r] = (kFull || r < rows) ? P[(j + c) * ld + i + r] : 0.0;
  for (Index q = 0; q < m; ++q) {
    const double* __restrict a = A + q * ldf + i;
    const double* __restrict b = B + q * ldf + j;
    for (int c = 0; c < C; ++c) {
      const double bc = b[c];
      for (int r = 0; r < R; ++r) acc[c][r] -= a[r] * bc;
    }
  }
  for (int c = 0; c < C; ++c)
    for (int r = 0; r < R; ++r)
      if (kFull || r < rows) P[(j + c) * ld + i + r] = acc[c][r];
}

template <int R, int C>
__attribute__((always_inline)) inline void lower_factor_downdate_tiles(double* __restrict P, Index ld, Index n,
                                                                       const double* __restrict A,
                                                                       const double* __restrict B, Index ldf,
                                                                       Index m) {
  Index j = 0;
  for (; j + C <= n; j += C) {
    Index i = j;
    for (; i + R <= n; i += R) factor_tile<R, C, true>(P, ld, i, j, R, A, B, ldf, m);
    if (i < n) factor_tile<R, C, false>(P, ld, i, j, static_cast<int>(n - i), A, B, ldf, m);
  }
  for (; j < n; ++j)
    for (Index i = j; i < n; ++i) {
      double p = P[j * ld + i];
      for (Index q = 0; q < m; ++q) p -= A[q * ldf + i] * B[q * ldf + j];
      P[j * ld + i] = p;
    }
}

#if defined(__x86_64__) && defined(__linux__) && defined(__GNUC__) && !defined(__clang__) && \
    (__GNUC__ >= 11) && !defined(ELASLAM_NO_MULTIVERSION)
#define ELASLAM_DOWNDATE_DISPATCH 1
// AVX-512: 8 x 8 tiles, one 512-bit vector per column (8 accumulators of 32
// registers), written with GCC vector types, which GCC keeps in registers here
// where it spills the plain-array form of that tile.
typedef double Vec8d __attribute__((vector_size(64), aligned(8)));
template <bool kFull>
__attribute__((always_inline)) inline void factor_tile_v8(double* __restrict P, Index ld, Index i, Index j, int rows,
                                                          const double* __restrict A, const double* __restrict B,
                                                          Index ldf, Index m) {
  constexpr int C = 8;
  Vec8d acc[C];
  for (int c = 0; c < C; ++c) {
    if (kFull) {
      __builtin_memcpy(&acc[c], P + (j + c) * ld + i, sizeof(Vec8d));
    } else {
      double t[8] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
      for (int r = 0; r < rows; ++r) t[r] = P[(j + c) * ld + i + r];
      __builtin_memcpy(&acc[c], t, sizeof(Vec8d));
    }
  }
  for (Index q = 0; q < m; ++q) {
    Vec8d a;
    __builtin_memcpy(&a, A + q * ldf + i, sizeof(Vec8d));
    const double* __restrict b = B + q * ldf + j;
    for (int c = 0; c < C; ++c) acc[c] -= a * b[c];
  }
  for (int c = 0; c < C; ++c) {
    if (kFull) {
      __builtin_memcpy(P + (j + c) * ld + i, &acc[c], sizeof(Vec8d));
    } else {
      double t[8];
      __builtin_memcpy(t, &acc[c], sizeof(Vec8d));
      for (int r = 0; r < rows; ++r) P[(j + c) * ld + i + r] = t[r];
    }
  }
}
__attribute__((target("arch=x86-64-v4"))) void lower_factor_downdate_v4(double* __restrict P, Index ld, Index n,
                                                                         const double* __restrict A,
                                                                         const double* __restrict B, Index ldf,
                                                                         Index m) {
  constexpr int C = 8;
  Index j = 0;
  for (; j + C <= n; j += C) {
    Index i = j;
    for (; i + 8 <= n; i += 8) factor_tile_v8<true>(P, ld, i, j, 8, A, B, ldf, m);
    if (i < n) factor_tile_v8<false>(P, ld, i, j, static_cast<int>(n - i), A, B, ldf, m);
  }
  lower_factor_downdate_tiles<4, 4>(P + j * ld + j, ld, n - j, A + j, B + j, ldf, m);
}
// AVX2 + FMA: plain 8 x 4 tiles (the compiler's choice of vectors).
__attribute__((target("arch=x86-64-v3"))) void lower_factor_downdate_v3(double* __restrict P, Index ld, Index n,
                                                                         const double* __restrict A,
                                                                         const double* __restrict B, Index ldf,
                                                                         Index m) {
  lower_factor_downdate_tiles<8, 4>(P, ld, n, A, B, ldf, m);
}
#endif

/// Rows past n that lower_factor_downdate may read in A's columns.
constexpr Index kFactorPadRows = 8;

// Rates on the benchmark machine (a 147 x 147 triangle): AVX-512 24 G, AVX2 14 G
// fused multiply-adds per second (docs/benchmarks.md).
void lower_factor_downdate(double* __restrict P, Index ld, Index n, const double* __restrict A,
                           const double* __restrict B, Index ldf, Index m) {
  if (m <= 0 || n <= 0) return;
#ifdef ELASLAM_DOWNDATE_DISPATCH
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq")) {
    lower_factor_downdate_v4(P, ld, n, A, B, ldf, m);
    return;
  }
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) {
    lower_factor_downdate_v3(P, ld, n, A, B, ldf, m);
    return;
  }
#endif
  lower_factor_downdate_tiles<4, 4>(P, ld, n, A, B, ldf, m);
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

// G = P H^T row by row from the robot columns 0..2 of P (complete) and the two
// columns of the landmark at offset `off`, read from the lower triangle: along its
// rows above the landmark block, down its columns from the block on. (The stored
// P: EkfSlam corrects G for pending steps afterwards.)
ELASLAM_MULTIVERSION void pht_rows(const GainCoefficients c, Index n, Index off, const double* __restrict P,
                                   Index ld, double* __restrict g0, double* __restrict g1) {
  const double* __restrict r0 = P;
  const double* __restrict r1 = P + ld;
  const double* __restrict r2 = P + 2 * ld;
  const auto row = [&](Index i, double l0, double l1) {
    g0[i] = c.h0[0] * r0[i] + c.h0[1] * r1[i] + c.h0[2] * r2[i] + c.h0[3] * l0 + c.h0[4] * l1;
    g1[i] = c.h1[0] * r0[i] + c.h1[1] * r1[i] + c.h1[2] * r2[i] + c.h1[3] * l0 + c.h1[4] * l1;
  };
  for (Index i = 0; i < off; ++i) row(i, P[i * ld + off], P[i * ld + off + 1]);
  row(off, P[off * ld + off], P[off * ld + off + 1]);
  const double* __restrict c0 = P + off * ld;
  const double* __restrict c1 = P + (off + 1) * ld;
  for (Index i = off + 1; i < n; ++i) row(i, c0[i], c1[i]);
}

// G -= F E^T: F n x m (column stride ldf), E 2 x m given by its rows e0, e1. Eight
// columns of F per pass over G (then four, then one).
ELASLAM_MULTIVERSION void subtract_factor_rows(Index n, const double* __restrict F, Index ldf, Index m,
                                               const double* __restrict e0, const double* __restrict e1,
                                               double* __restrict g0, double* __restrict g1) {
  Index q = 0;
  for (; q + 8 <= m; q += 8) {
    const double* __restrict f = F + q * ldf;
    double a[8], b[8];
    for (int k = 0; k < 8; ++k) {
      a[k] = e0[q + k];
      b[k] = e1[q + k];
    }
    for (Index i = 0; i < n; ++i) {
      double s0 = 0.0, s1 = 0.0;
      for (int k = 0; k < 8; ++k) {
        const double fk = f[k * ldf + i];
        s0 += fk * a[k];
        s1 += fk * b[k];
      }
      g0[i] -= s0;
      g1[i] -= s1;
    }
  }
  for (; q < m; ++q) {
    const double* __restrict f = F + q * ldf;
    for (Index i = 0; i < n; ++i) {
      g0[i] -= f[i] * e0[q];
      g1[i] -= f[i] * e1[q];
    }
  }
}

// Standard form: m_i = L^-1 g_i.
ELASLAM_MULTIVERSION void gain_standard(const GainCoefficients c, Index n, const double* __restrict g0,
                                        const double* __restrict g1, double* __restrict k0,
                                        double* __restrict k1) {
  for (Index i = 0; i < n; ++i) {
    const double m0 = g0[i] * c.i00;
    k0[i] = m0;
    k1[i] = (g1[i] - c.l10 * m0) * c.i11;
  }
}

// Joseph form: k_i = Z^-1 g_i = L^-T L^-1 g_i and b_i = g_i - (K Z)_i / 2.
ELASLAM_MULTIVERSION void gain_joseph(const GainCoefficients c, Index n, const double* __restrict g0,
                                      const double* __restrict g1, double* __restrict k0,
                                      double* __restrict k1, double* __restrict b0, double* __restrict b1) {
  for (Index i = 0; i < n; ++i) {
    const double p0 = g0[i], p1 = g1[i];
    const double m0 = p0 * c.i00, m1 = (p1 - c.l10 * m0) * c.i11;  // m_i = L^-1 g_i
    const double q1 = m1 * c.i11, q0 = (m0 - c.l10 * q1) * c.i00;  // k_i = L^-T m_i
    k0[i] = q0;
    k1[i] = q1;
    b0[i] = p0 - (q0 * c.z00 + q1 * c.z01);
    b1[i] = p1 - (q0 * c.z01 + q1 * c.z11);
  }
}

// The checks of EkfSlam::correction_healthy, row by row: x_i + a_i . v and
// P_ii - scale * a_i . b_i (P_ii at stride `diag_stride`), and max|a| * max|b|.
// Branch-free, in four independent lanes so that the loop vectorises without
// reassociating floating-point sums: a NaN or an infinity anywhere makes `sum`
// non-finite; the variance margins are checked by their minimum.
ELASLAM_MULTIVERSION bool rows_healthy(Index n, const double* __restrict P, Index diag_stride,
                                       const double* __restrict x, const double* __restrict a0,
                                       const double* __restrict a1, const double* __restrict b0,
                                       const double* __restrict b1, double v0, double v1,
                                       double scale) {
  constexpr int kLanes = 4;
  double sum[kLanes] = {}, margin[kLanes] = {}, a_max[kLanes] = {}, b_max[kLanes] = {};
  const auto row = [&](Index i, int l) {
    const double p = P[i * diag_stride];
    const double p_new = p - scale * dot2(a0[i], a1[i], b0[i], b1[i]);
    const double x_new = x[i] + dot2(a0[i], a1[i], v0, v1);
    sum[l] += p_new + x_new;
    const double m = p_new + (kNegativeVarianceRelTol * p + kNegativeVarianceAbsTol);
    margin[l] = m < margin[l] ? m : margin[l];
    const double a = std::max(std::abs(a0[i]), std::abs(a1[i])), b = std::max(std::abs(b0[i]), std::abs(b1[i]));
    a_max[l] = a > a_max[l] ? a : a_max[l];
    b_max[l] = b > b_max[l] ? b : b_max[l];
  };
  Index i = 0;
  for (; i + kLanes <= n; i += kLanes)
    for (int l = 0; l < kLanes; ++l) row(i + l, l);
  for (; i < n; ++i) row(i, 0);
  double s = 0.0, mg = 0.0, am = 0.0, bm = 0.0;
  for (int l = 0; l < kLanes; ++l) {
    s += sum[l];
    mg = std::min(mg, margin[l]);
    am = std::max(am, a_max[l]);
    bm = std::max(bm, b_max[l]);
  }
  // A NaN compares false everywhere, so it can hide from the min and max; never from the sum.
  return std::isfinite(s) && mg >= 0.0 && am * bm < kMaxProduct;
}

// Prediction's cross terms (eq 5): each landmark row l of P_LR (lower storage:
// columns 0..2 of P below the robot block, pointers c0..c2 at its first row) becomes
// F_x l, into t0..t2. Returns false when any result is not finite.
ELASLAM_MULTIVERSION bool predict_cross_rows(Index m, const double* __restrict c0, const double* __restrict c1,
                                             const double* __restrict c2, const double (&F)[3][3],
                                             double* __restrict t0, double* __restrict t1,
                                             double* __restrict t2) {
  double sum = 0.0;
  for (Index i = 0; i < m; ++i) {
    const double a = c0[i], b = c1[i], c = c2[i];
    t0[i] = F[0][0] * a + F[0][1] * b + F[0][2] * c;
    t1[i] = F[1][0] * a + F[1][1] * b + F[1][2] * c;
    t2[i] = F[2][0] * a + F[2][1] * b + F[2][2] * c;
    sum += 0.0 * (t0[i] + t1[i] + t2[i]);  // NaN or infinity anywhere makes it NaN
  }
  return sum == 0.0;
}

// The same with the odometer's calibration estimated (eq 5 on the vehicle block
// V = [R; C], F_V = [[F_x, F_c], [0, I]]): each landmark row becomes
// F_x l_R + F_c l_C, with l_C its columns 3..5 (pointers d0..d2 at its first row);
// l_C itself is unchanged. Twice the reads of predict_cross_rows, the same writes.
ELASLAM_MULTIVERSION bool predict_cross_rows_calibrated(Index m, const double* __restrict c0,
                                                        const double* __restrict c1, const double* __restrict c2,
                                                        const double* __restrict d0, const double* __restrict d1,
                                                        const double* __restrict d2, const double (&F)[3][3],
                                                        const double (&G)[3][3], double* __restrict t0,
                                                        double* __restrict t1, double* __restrict t2) {
  double sum = 0.0;
  for (Index i = 0; i < m; ++i) {
    const double a = c0[i], b = c1[i], c = c2[i], p = d0[i], q = d1[i], r = d2[i];
    t0[i] = F[0][0] * a + F[0][1] * b + F[0][2] * c + (G[0][0] * p + G[0][1] * q + G[0][2] * r);
    t1[i] = F[1][0] * a + F[1][1] * b + F[1][2] * c + (G[1][0] * p + G[1][1] * q + G[1][2] * r);
    t2[i] = F[2][0] * a + F[2][1] * b + F[2][2] * c + (G[2][0] * p + G[2][1] * q + G[2][2] * r);
    sum += 0.0 * (t0[i] + t1[i] + t2[i]);  // NaN or infinity anywhere makes it NaN
  }
  return sum == 0.0;
}

// The committed update's O(n) part: x += a0 v0 + a1 v1 and diag -= scale (a0 b0 + a1 b1).
ELASLAM_MULTIVERSION void commit_rows(Index n, double* __restrict x, double* __restrict diag,
                                      const double* __restrict a0, const double* __restrict a1,
                                      const double* __restrict b0, const double* __restrict b1, double v0,
                                      double v1, double scale) {
  for (Index i = 0; i < n; ++i) {
    x[i] += a0[i] * v0 + a1[i] * v1;
    diag[i] -= scale * (a0[i] * b0[i] + a1[i] * b1[i]);
  }
}

}  // namespace
}  // namespace elaslam

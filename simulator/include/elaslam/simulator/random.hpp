// SPDX-License-Identifier: Apache-2.0
// Deterministic random numbers: bit-identical for the same seed with any standard
// library. std::mt19937_64 is specified exactly by the standard;
// std::normal_distribution and std::uniform_real_distribution are not, so the
// uniform and normal transforms are our own (they use only log, sqrt, sin, cos of
// the C math library).
//
// Each purpose draws from its own stream, seeded from (master seed, stream id)
// through splitmix64, so that e.g. changing the dynamism does not shift the
// sensor noise draws of the static landmarks.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>

namespace elaslam::sim {

/// Stream ids. Per-robot streams add the robot id (1..16, below the next stream).
namespace stream {
constexpr std::uint64_t kLayout = 1;       // random layout positions
constexpr std::uint64_t kMovingSet = 2;    // permutation that picks the moving landmarks
constexpr std::uint64_t kDirections = 3;   // initial direction of every landmark
constexpr std::uint64_t kMoverPhase = 4;   // where in its cycle every landmark would start stop-and-go
constexpr std::uint64_t kSensorNoise = 100;   // + robot id
constexpr std::uint64_t kOdometryNoise = 200; // + robot id
constexpr std::uint64_t kDetection = 300;     // + robot id
}  // namespace stream

/// splitmix64 (Steele, Lea, Flood 2014): a good 64-bit mixer for seeding.
inline std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

/// The seed of stream `id` under the master seed.
inline std::uint64_t stream_seed(std::uint64_t master, std::uint64_t id) {
  return splitmix64(splitmix64(master) ^ splitmix64(id + 0x5DEECE66DULL));
}

class Rng {
 public:
  Rng() = default;
  Rng(std::uint64_t master_seed, std::uint64_t stream_id) : engine_(stream_seed(master_seed, stream_id)) {}

  std::uint64_t bits() { return engine_(); }

  /// Uniform in [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }

  /// Uniform in [lo, hi).
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

  /// Uniform integer in [0, n), n >= 1 (Lemire-free rejection: exact, portable).
  std::uint64_t below(std::uint64_t n) {
    const std::uint64_t limit = UINT64_MAX - UINT64_MAX % n;
    std::uint64_t x = engine_();
    while (x >= limit) x = engine_();
    return x % n;
  }

  /// Standard normal, Box-Muller; the second value of each pair is kept for the next call.
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u1 = uniform();
    while (u1 <= 0.0) u1 = uniform();  // log(0) guard; probability 2^-53
    const double u2 = uniform();
    const double r = std::sqrt(-2.0 * std::log(u1));
    const double a = 2.0 * 3.14159265358979323846 * u2;
    spare_ = r * std::sin(a);
    has_spare_ = true;
    return r * std::cos(a);
  }

 private:
  std::mt19937_64 engine_{0};
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace elaslam::sim

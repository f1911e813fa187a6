// SPDX-License-Identifier: Apache-2.0
// The range-bearing sensor: noise statistics, field of view, detection probability.
// Tolerances are ~4-5 standard errors of the estimate, so a correct sensor fails
// with probability < 1e-4 per check; the draws are seeded, so a run is repeatable.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "elaslam/simulator/random.hpp"
#include "elaslam/simulator/sensor.hpp"
#include "sim_test_util.hpp"

namespace elaslam::sim {
namespace {

SensorOptions options(double detection = 1.0) {
  SensorOptions s;
  s.fov_diameter_m = 8.0;
  s.min_range_m = 0.1;
  s.range_sigma_m = 0.05;
  s.bearing_sigma_deg = 1.0;
  s.detection_probability = detection;
  return s;
}

Sensor make_sensor(const SensorOptions& s, int n, std::uint64_t seed = 7) {
  return Sensor(s, n, Rng(seed, stream::kSensorNoise + 1), Rng(seed, stream::kDetection + 1));
}

TEST(SimSensor, NoiseHasTheConfiguredMeanAndCovariance) {
  // GIVEN one robot pose and two landmarks, one of them behind the robot (bearing near +-pi)
  const SensorOptions s = options();
  Sensor sensor = make_sensor(s, 2);
  const Pose2 T_WB{1.0, -2.0, 0.3};
  const std::vector<Eigen::Vector2d> p{{3.5, 0.0}, {-1.5, -2.9}};
  const double sigma_b = deg2rad(s.bearing_sigma_deg);
  for (std::size_t l = 0; l < p.size(); ++l) {
    SCOPED_TRACE(l);
    const Observation truth = true_observation(T_WB, p[l], static_cast<int>(l));
    test::Moments er, eb;
    double cross = 0.0;
    const int n = 40000;
    ObservationArray out;
    int truncated = 0;
    for (int i = 0; i < n; ++i) {
      ASSERT_EQ(sensor.observe(T_WB, p, &out, &truncated), 2);
      const double dr = out[l].range_m - truth.range_m;
      const double db = wrap_angle(out[l].bearing_rad - truth.bearing_rad);
      er.add(dr);
      eb.add(db);
      cross += dr * db;
    }
    // THEN errors are unbiased, with the configured variances and no correlation.
    EXPECT_NEAR(er.mean, 0.0, 4.5 * s.range_sigma_m / std::sqrt(n));
    EXPECT_NEAR(eb.mean, 0.0, 4.5 * sigma_b / std::sqrt(n));
    const double rel = 4.5 * std::sqrt(2.0 / n);  // standard error of a sample variance, relative
    EXPECT_NEAR(er.var() / (s.range_sigma_m * s.range_sigma_m), 1.0, rel);
    EXPECT_NEAR(eb.var() / (sigma_b * sigma_b), 1.0, rel);
    EXPECT_NEAR(cross / n / (s.range_sigma_m * sigma_b), 0.0, 4.5 / std::sqrt(n));
  }
}

TEST(SimSensor, FieldOfViewIsADiscOfDiameterD) {
  Sensor sensor = make_sensor(options(), 8);
  const Pose2 T_WB{0.0, 0.0, 1.0};
  // ids 0..3 inside (one just inside D/2), 4..6 outside, 7 closer than min_range
  const std::vector<Eigen::Vector2d> p{{3.9, 0.0},  {0.0, -3.999}, {-2.0, 2.0}, {2.8, 2.8},
                                       {4.01, 0.0}, {3.0, 3.0},  {-9.0, 0.0}, {0.05, 0.0}};
  ObservationArray out;
  int truncated = -1;
  for (int trial = 0; trial < 100; ++trial) {
    ASSERT_EQ(sensor.observe(T_WB, p, &out, &truncated), 4);
    EXPECT_EQ(truncated, 0);
    for (int i = 0; i < 4; ++i) EXPECT_EQ(out[static_cast<std::size_t>(i)].landmark_id, i);
  }
}

TEST(SimSensor, DetectionProbabilityIsRespected) {
  const double pd = 0.7;
  const int n_lm = 40, frames = 2500;
  Sensor sensor = make_sensor(options(pd), n_lm);
  std::vector<Eigen::Vector2d> p;
  for (int i = 0; i < n_lm; ++i) p.emplace_back(0.5 + 0.08 * i, 0.0);  // all within 4 m
  ObservationArray out;
  int truncated = 0;
  long seen = 0;
  for (int f = 0; f < frames; ++f) seen += sensor.observe(Pose2{}, p, &out, &truncated);
  const double trials = static_cast<double>(n_lm) * frames;
  const double frac = static_cast<double>(seen) / trials;
  EXPECT_NEAR(frac, pd, 4.5 * std::sqrt(pd * (1.0 - pd) / trials));  // binomial tolerance
}

TEST(SimSensor, SameStreamsSameDraws) {
  const std::vector<Eigen::Vector2d> p{{1.0, 1.0}, {2.0, -1.0}};
  Sensor a = make_sensor(options(0.5), 2, 3), b = make_sensor(options(0.5), 2, 3);
  ObservationArray oa, ob;
  int t = 0;
  for (int i = 0; i < 100; ++i) {
    const int na = a.observe(Pose2{}, p, &oa, &t);
    ASSERT_EQ(b.observe(Pose2{}, p, &ob, &t), na);
    for (int k = 0; k < na; ++k) EXPECT_EQ(oa[static_cast<std::size_t>(k)].range_m, ob[static_cast<std::size_t>(k)].range_m);
  }
}

}  // namespace
}  // namespace elaslam::sim

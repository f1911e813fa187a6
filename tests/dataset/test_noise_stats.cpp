// SPDX-License-Identifier: Apache-2.0
// The noise statistics of a recording against Vicon (dataset/noise_stats.hpp):
// hand-computed values on small vectors, a synthetic odometry lag, the tiny
// dataset's residuals; and mrclam_stats' report (stats_report.hpp) on the tiny
// dataset against its reference text (tests/dataset/data/tiny_stats.txt).
#include <cmath>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "elaslam/dataset/noise_stats.hpp"
#include "elaslam/dataset/stats_report.hpp"
#include "../support/read_file.hpp"

namespace elaslam::mrclam {
namespace {

const std::string kTiny = std::string(ELASLAM_SOURCE_DIR) + "/tests/dataset/data/tiny";

TEST(NoiseStats, MedianOfOddEvenAndEmpty) {
  EXPECT_DOUBLE_EQ(median_of({3.0, 1.0, 2.0}), 2.0);
  EXPECT_DOUBLE_EQ(median_of({4.0, 1.0, 3.0, 2.0}), 2.5);
  EXPECT_DOUBLE_EQ(median_of({}), 0.0);
}

TEST(NoiseStats, RobustLeavesTheOutlierOut) {
  // median 3; |x - 3| = 2 1 0 1 97: MAD 1, robust sigma 1.4826; 100 is beyond 5 sigmas.
  // Inliers 1 2 3 4: mean 2.5, std sqrt((30 - 25) / 3).
  const Robust s = robust({1.0, 2.0, 3.0, 4.0, 100.0});
  EXPECT_EQ(s.count, 5);
  EXPECT_DOUBLE_EQ(s.median, 3.0);
  EXPECT_DOUBLE_EQ(s.robust_sigma, 1.4826);
  EXPECT_DOUBLE_EQ(s.mean_inliers, 2.5);
  EXPECT_NEAR(s.std_inliers, std::sqrt(5.0 / 3.0), 1e-12);
  EXPECT_NEAR(s.outlier_fraction, 0.2, 1e-12);
  const Robust none = robust({});
  EXPECT_EQ(none.count, 0);
  EXPECT_DOUBLE_EQ(none.outlier_fraction, 0.0);
}

TEST(NoiseStats, MomentsPerMetre) {
  double mean = -1, var = -1, ms = -1;
  moments({1.0, 3.0}, 2.0, &mean, &var, &ms);  // mean 2; variance 2 / 2 m; mean square 5 / 2 m
  EXPECT_DOUBLE_EQ(mean, 2.0);
  EXPECT_DOUBLE_EQ(var, 1.0);
  EXPECT_DOUBLE_EQ(ms, 2.5);
  moments({1.0}, 2.0, &mean, &var, &ms);  // one value: left as they were
  EXPECT_DOUBLE_EQ(mean, 2.0);
}

TEST(NoiseStats, FitNonnegBothTermsOrTheBetterOne) {
  const std::vector<double> x1{1, 2, 0, 1}, x2{0, 1, 1, 2};
  std::vector<double> y(4);
  for (int i = 0; i < 4; ++i) y[i] = 2.0 * x1[i] + 3.0 * x2[i];
  double a = 0, b = 0;
  fit_nonneg(x1, x2, y, &a, &b);
  EXPECT_NEAR(a, 2.0, 1e-12);
  EXPECT_NEAR(b, 3.0, 1e-12);
  // y = x2 - 4 x1: the joint fit has a < 0; x2 alone (b = sum x2 y / sum x2^2) fits
  // better than x1 alone (clamped to 0).
  for (int i = 0; i < 4; ++i) y[i] = x2[i] - 4.0 * x1[i];
  fit_nonneg(x1, x2, y, &a, &b);
  EXPECT_DOUBLE_EQ(a, 0.0);
  double s2y = 0, s22 = 0;
  for (int i = 0; i < 4; ++i) s2y += x2[i] * y[i], s22 += x2[i] * x2[i];
  EXPECT_DOUBLE_EQ(b, std::max(0.0, s2y / s22));
}

TEST(NoiseStats, RangeScaleRecoversK0K1AndSkipsOutliers) {
  Residuals r;
  const double k0 = 0.02, k1 = -0.05;
  for (int i = 0; i < 20; ++i) {
    const double range = 1.0 + 0.2 * i, bearing = -0.5 + 0.05 * i;
    r.measured_range.push_back(range);
    r.measured_bearing.push_back(bearing);
    r.range.push_back(range * (k0 + k1 * bearing * bearing));
    r.bearing.push_back(0.0);
  }
  // Outliers: a range residual of 1 m, a bearing residual of 0.1 rad.
  r.measured_range.insert(r.measured_range.end(), {2.0, 2.0});
  r.measured_bearing.insert(r.measured_bearing.end(), {0.0, 0.0});
  r.range.insert(r.range.end(), {1.0, 0.0});
  r.bearing.insert(r.bearing.end(), {0.0, 0.1});
  const RangeScale f = fit_range_scale(r);
  EXPECT_EQ(f.used, 20);
  EXPECT_NEAR(f.k0, k0, 1e-12);
  EXPECT_NEAR(f.k1, k1, 1e-12);
  EXPECT_GT(f.std_before, 0.0);
  EXPECT_LT(f.std_after, f.std_before);
  Residuals two;
  two.range = {0.1, 0.2};
  two.bearing = {0.0, 0.0};
  two.measured_range = {1.0, 2.0};
  two.measured_bearing = {0.1, 0.2};
  EXPECT_EQ(fit_range_scale(two).used, 2);
  EXPECT_DOUBLE_EQ(fit_range_scale(two).k0, 0.0);  // fewer than 3: no fit
}

TEST(NoiseStats, OdometryLagOfCommandsLeadingByTwoTenths) {
  // Commands change every second; Vicon turns with the command of 0.2 s earlier.
  RobotSeries s;
  const auto w_at = [](int second) { return 0.1 * ((second * 7) % 5 - 2); };
  for (int i = 0; i <= 40; ++i) s.odometry.push_back({i * 1'000'000LL, 0.0, w_at(i)});
  double theta = 0.0;
  for (int k = 0; k <= 2000; ++k) {  // every 20 ms for 40 s
    const std::int64_t u = k * 20'000LL;
    s.ground_truth.push_back({u, Pose2{0.0, 0.0, wrap_angle(theta)}});
    const double t_cmd = (static_cast<double>(u) + 10'000.0) * 1e-6 - 0.2;  // the step's middle, 0.2 s earlier
    theta += w_at(t_cmd < 0 ? 0 : static_cast<int>(std::floor(t_cmd))) * 0.02;
  }
  EXPECT_NEAR(odometry_lag(s), 0.2, 0.02 + 1e-9);  // the search's step is 0.02 s
  RobotSeries empty;
  EXPECT_DOUBLE_EQ(odometry_lag(empty), 0.0);
}

TEST(NoiseStats, SuggestedOdometryWeightsByWindows) {
  OdoNoise a, b;
  a.windows = 1, a.along_ms_per_m = 1.0, a.across_ms_per_m = 3.0, a.heading_ms_per_m = 4.0, a.fit_rot_per_m = 1.0;
  b.windows = 3, b.along_ms_per_m = 5.0, b.across_ms_per_m = 7.0, b.heading_ms_per_m = 8.0, b.fit_rot_per_m = 2.0;
  const SuggestedOdometry s = suggest_odometry({a, b});
  EXPECT_DOUBLE_EQ(s.trans_ms, (1 * 2.0 + 3 * 6.0) / 4);
  EXPECT_DOUBLE_EQ(s.rot_ms, (1 * 4.0 + 3 * 8.0) / 4);
  EXPECT_DOUBLE_EQ(s.fit_rot_per_m, (1 * 1.0 + 3 * 2.0) / 4);
  EXPECT_DOUBLE_EQ(suggest_odometry({}).trans_ms, 0.0);
}

TEST(NoiseStats, TinySensorResiduals) {
  // Robot 1: 7 static-landmark measurements inside its Vicon time (999.9 and 1002.5
  // are outside; barcodes 99, 14 and 5 are a misread, robot 2 and itself).
  const Dataset d = Dataset::load(kTiny, {1, 2});
  const Residuals r = sensor_residuals(d, d.robot(1));
  ASSERT_EQ(r.range.size(), 7u);
  EXPECT_NEAR(r.range[0], 0.0, 1e-12);  // 1000.0: at (0,0,0), landmark 6 at (2,0), 2.0 / 0.0
  EXPECT_NEAR(r.bearing[0], 0.0, 1e-12);
  // 1000.12: Vicon at (0.06, 0, 0); landmark 7 at (0, 2) measured 2.1 / 1.5.
  EXPECT_NEAR(r.range[1], 2.1 - std::hypot(0.06, 2.0), 1e-12);
  EXPECT_NEAR(r.bearing[1], 1.5 - std::atan2(2.0, -0.06), 1e-12);
  EXPECT_DOUBLE_EQ(r.measured_range[1], 2.1);
  EXPECT_DOUBLE_EQ(r.measured_bearing[1], 1.5);
  // 1000.5: Vicon at (0.25, 0, 0); landmark 7 measured 2.0 / 3.5 (wrapped residual).
  EXPECT_NEAR(r.range[5], 2.0 - std::hypot(0.25, 2.0), 1e-12);
  EXPECT_NEAR(r.bearing[5], wrap_angle(3.5 - std::atan2(2.0, -0.25)), 1e-12);
}

TEST(NoiseStats, TinyReportAgainstItsReference) {
  const Dataset d = Dataset::load(kTiny, {1, 2});
  StatsOptions o;
  o.dataset_dir = "tiny";
  o.ids = {1, 2};
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  const nlohmann::json j = noise_report(d, o, f);
  std::rewind(f);
  std::string text;
  for (int c; (c = std::fgetc(f)) != EOF;) text += static_cast<char>(c);
  std::fclose(f);
  EXPECT_EQ(text, test::read_file(kTiny + "_stats.txt"));
  EXPECT_EQ(j["dataset"], "tiny");
  EXPECT_EQ(j["robots"]["1"]["range_m"]["count"], 7);
  EXPECT_EQ(j["overall"]["range_m"]["count"], j["robots"]["1"]["range_m"]["count"].get<long>() +
                                                 j["robots"]["2"]["range_m"]["count"].get<long>());
  EXPECT_FALSE(j.contains("frame_residuals"));  // no config
  EXPECT_TRUE(j["robots"]["2"].contains("odometry_calibration"));
  for (const char* key : {"odometry_lag_s", "range_scale", "detection", "suggested"}) EXPECT_TRUE(j.contains(key)) << key;
}

TEST(NoiseStats, FrameResidualsWithAConfigSection) {
  const Dataset d = Dataset::load(kTiny, {1, 2});
  StatsOptions o;
  o.dataset_dir = "tiny";
  o.ids = {1, 2};
  o.config_path = "given.yaml";
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  const nlohmann::json j = noise_report(d, o, f);
  std::fclose(f);
  ASSERT_TRUE(j.contains("frame_residuals"));
  EXPECT_EQ(j["frame_residuals"]["config"], "given.yaml");
  Options fo;
  fo.robots = {1, 2};
  EXPECT_EQ(j["frame_residuals"]["range_m"]["count"], static_cast<long>(frame_residuals(d, fo).range.size()));
}

}  // namespace
}  // namespace elaslam::mrclam

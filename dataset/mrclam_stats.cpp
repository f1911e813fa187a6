// SPDX-License-Identifier: Apache-2.0
// mrclam_stats: sensor and odometry noise of a UTIAS MRCLAM recording, measured
// against its Vicon ground truth, to choose the noise values of config/mrclam.yaml.
//   mrclam_stats --dataset DIR [--robots 1,2,3,4,5] [--rate F] [--json FILE]
//
// Range/bearing: every measurement of a static landmark (subjects 6-20) whose time
// lies inside the robot's ground truth, against the range and bearing predicted from
// the Vicon pose interpolated at that time; residual = measured - predicted (bearing
// wrapped). Per robot and overall: count, median, robust sigma (1.4826 MAD), the
// plain std of the residuals within 5 robust sigmas of the median, and the fraction
// outside (outliers: misreads, occlusions).
// Odometry: each robot alone over its own full window (FrameSource with one robot at
// --rate). Scale = path length of the dead-reckoned odometer / of Vicon, both sampled
// at the frames. Noise: consecutive windows of >= 1 m driven (Vicon); in each, the
// odometer increment minus the Vicon increment (both in the frame of the robot at the
// window start): along track, across track, heading. var per m = variance / mean
// window length (about the mean: the scale bias excluded); ms per m = mean square /
// mean window length (bias included: what a filter that models no bias should use).
// Odometer calibration (the filter's robot.odometry_calibration): per robot,
// least squares of Vicon's increments on the odometer's over every frame step
// (mrclam::fit_odometry), over the whole run and each half, on the frames as the
// filter gets them (--config's dataset section: the odometry delay matters).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "elaslam/common/cli.hpp"
#include "elaslam/common/quantile.hpp"
#include "elaslam/dataset/mrclam.hpp"

namespace {

using namespace elaslam;
using nlohmann::json;

struct Robust {
  long count = 0;
  double median = 0.0, robust_sigma = 0.0, std_inliers = 0.0, mean_inliers = 0.0, outlier_fraction = 0.0;
};

double median_of(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const std::size_t n = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(n), v.end());
  const double hi = v[n];
  if (v.size() % 2) return hi;
  return 0.5 * (hi + *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(n)));
}

Robust robust(const std::vector<double>& r) {
  Robust s;
  s.count = static_cast<long>(r.size());
  if (r.empty()) return s;
  s.median = median_of(r);
  std::vector<double> dev(r.size());
  for (std::size_t i = 0; i < r.size(); ++i) dev[i] = std::fabs(r[i] - s.median);
  s.robust_sigma = 1.4826 * median_of(dev);
  double sum = 0.0, sum2 = 0.0;
  long n = 0;
  for (double x : r)
    if (std::fabs(x - s.median) <= 5.0 * s.robust_sigma) {
      sum += x;
      sum2 += x * x;
      ++n;
    }
  if (n > 1) {
    s.mean_inliers = sum / static_cast<double>(n);
    s.std_inliers = std::sqrt(std::max(0.0, (sum2 - sum * s.mean_inliers) / static_cast<double>(n - 1)));
  }
  s.outlier_fraction = 1.0 - static_cast<double>(n) / static_cast<double>(r.size());
  return s;
}

json to_json(const Robust& s) {
  return {{"count", s.count},          {"median", s.median},           {"robust_sigma", s.robust_sigma},
          {"std_inliers", s.std_inliers}, {"mean_inliers", s.mean_inliers}, {"outlier_fraction", s.outlier_fraction}};
}

struct Residuals {
  std::vector<double> range, bearing;           // residuals
  std::vector<double> measured_range, measured_bearing;
};

/// Range scale calibration: fit range residual = r (k0 + k1 b^2) by least squares
/// over the measurements with |range residual| < 1 m and |bearing residual| < 0.1
/// rad (r, b as measured); the importer divides each range by 1 + k0 + k1 b^2.
/// How far the velocity commands lead the motion: the delay d [s] for
/// which the command in force at t - d best matches Vicon's angular rate at t (least
/// squares over a 50 Hz grid, d in [-0.5, 0.8] s by 0.02 s).
double odometry_lag(const mrclam::RobotSeries& s) {
  const auto& gt = s.ground_truth;
  const auto& od = s.odometry;
  if (gt.size() < 2 || od.size() < 2) return 0.0;
  const std::int64_t t0 = std::max(gt.front().utime, od.front().utime) + 5'000'000;
  const std::int64_t t1 = std::min(gt.back().utime, od.back().utime) - 5'000'000;
  constexpr std::int64_t kStep = 20'000;
  std::vector<std::int64_t> t;
  std::vector<double> rate;
  std::size_t hint = 0;
  Pose2 prev;
  bool have_prev = false;
  for (std::int64_t u = t0; u <= t1; u += kStep) {
    Pose2 p;
    if (!mrclam::interpolate(gt, u, &p, &hint)) continue;
    if (have_prev) {
      t.push_back(u);
      rate.push_back(wrap_angle(p.theta - prev.theta) / (kStep * 1e-6));
    }
    prev = p;
    have_prev = true;
  }
  double best_lag = 0.0, best_err = HUGE_VAL;
  for (int i = -25; i <= 40; ++i) {
    const std::int64_t lag = i * kStep;
    double err = 0.0;
    std::size_t c = 0;
    for (std::size_t k = 0; k < t.size(); ++k) {
      while (c + 1 < od.size() && od[c + 1].utime <= t[k] - lag) ++c;
      const double e = od[c].w - rate[k];
      err += e * e;
    }
    if (err < best_err) best_err = err, best_lag = lag * 1e-6;
  }
  return best_lag;
}

/// How reliably the camera reports a landmark that is in view: over the frames at
/// `rate` Hz, every static landmark inside `range` m and +-`half_angle` rad of a
/// robot's Vicon pose is either reported in the frame or missed; returns the
/// reported fraction and the lengths of the runs of consecutive misses.
struct Detection {
  long in_view = 0, reported = 0;
  std::vector<double> miss_streaks;  // [frames]
};
Detection detection(const mrclam::Dataset& d, const std::vector<int>& ids, double rate, double range,
                    double half_angle) {
  mrclam::Options o;
  o.robots = ids;
  o.rate_hz = rate;
  const mrclam::FrameSource src(d, o);
  Detection out;
  std::vector<sensor_frame_t> sensors;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    std::vector<int> streak(d.landmarks().size(), 0);
    for (int k = 0; k < src.num_frames(); ++k) {
      src.frame(k, nullptr, &sensors);
      const Pose2& T = src.true_pose(static_cast<int>(i), k);
      const sensor_frame_t& f = sensors[i];
      for (std::size_t l = 0; l < d.landmarks().size(); ++l) {
        const auto& lm = d.landmarks()[l];
        const double dx = lm.x - T.x, dy = lm.y - T.y;
        const bool inside = std::hypot(dx, dy) < range && std::fabs(wrap_angle(std::atan2(dy, dx) - T.theta)) < half_angle;
        bool seen = false;
        for (int o2 = 0; o2 < f.num_obs; ++o2) seen = seen || f.obs[o2].landmark_id == lm.subject;
        if (inside && !seen) {
          ++streak[l];
        } else if (streak[l] > 0) {
          out.miss_streaks.push_back(streak[l]);
          streak[l] = 0;
        }
        if (inside) {
          ++out.in_view;
          out.reported += seen ? 1 : 0;
        }
      }
    }
  }
  return out;
}


struct RangeScale {
  double k0 = 0.0, k1 = 0.0, std_before = 0.0, std_after = 0.0;
  long used = 0;
};
RangeScale fit_range_scale(const Residuals& r) {
  double a00 = 0, a01 = 0, a11 = 0, y0 = 0, y1 = 0;
  std::vector<std::size_t> in;
  for (std::size_t i = 0; i < r.range.size(); ++i) {
    if (!(std::fabs(r.range[i]) < 1.0 && std::fabs(r.bearing[i]) < 0.1)) continue;
    in.push_back(i);
    const double x0 = r.measured_range[i], x1 = r.measured_range[i] * r.measured_bearing[i] * r.measured_bearing[i];
    a00 += x0 * x0, a01 += x0 * x1, a11 += x1 * x1, y0 += x0 * r.range[i], y1 += x1 * r.range[i];
  }
  RangeScale f;
  f.used = static_cast<long>(in.size());
  const double det = a00 * a11 - a01 * a01;
  if (in.size() < 3 || !(std::fabs(det) > 0.0)) return f;
  f.k0 = (a11 * y0 - a01 * y1) / det;
  f.k1 = (a00 * y1 - a01 * y0) / det;
  double s0 = 0, q0 = 0, s1 = 0, q1 = 0;
  for (std::size_t i : in) {
    const double b = r.measured_bearing[i];
    const double corrected = r.measured_range[i] / (1.0 + f.k0 + f.k1 * b * b);
    const double e1 = r.range[i] - (r.measured_range[i] - corrected);
    s0 += r.range[i], q0 += r.range[i] * r.range[i], s1 += e1, q1 += e1 * e1;
  }
  const double n = static_cast<double>(in.size());
  f.std_before = std::sqrt(std::max(0.0, q0 / n - (s0 / n) * (s0 / n)));
  f.std_after = std::sqrt(std::max(0.0, q1 / n - (s1 / n) * (s1 / n)));
  return f;
}

/// Range and bearing residuals of one robot's static-landmark measurements.
Residuals sensor_residuals(const mrclam::Dataset& d, const mrclam::RobotSeries& s) {
  Residuals out;
  std::size_t hint = 0;
  for (const mrclam::Measurement& z : s.measurements) {
    const int subject = d.subject_of_barcode(z.barcode);
    if (subject < mrclam::kFirstLandmarkSubject) continue;
    const auto lm = std::find_if(d.landmarks().begin(), d.landmarks().end(),
                                 [subject](const mrclam::LandmarkTruth& l) { return l.subject == subject; });
    Pose2 T;
    if (lm == d.landmarks().end() || !mrclam::interpolate(s.ground_truth, z.utime, &T, &hint)) continue;
    const double dx = lm->x - T.x, dy = lm->y - T.y;
    out.range.push_back(z.range - std::hypot(dx, dy));
    out.bearing.push_back(wrap_angle(z.bearing - (std::atan2(dy, dx) - T.theta)));
    out.measured_range.push_back(z.range);
    out.measured_bearing.push_back(z.bearing);
  }
  return out;
}

struct OdoNoise {
  double odo_path_m = 0.0, vicon_path_m = 0.0, duration_s = 0.0;
  long windows = 0;
  double mean_window_m = 0.0;
  double along_mean = 0.0, along_var_per_m = 0.0, along_ms_per_m = 0.0;
  double across_mean = 0.0, across_var_per_m = 0.0, across_ms_per_m = 0.0;
  double heading_mean = 0.0, heading_var_per_m = 0.0, heading_ms_per_m = 0.0;
  // heading error^2 ~ rot_per_rad |turned| + rot_per_m |driven| (least squares, >= 0).
  double fit_rot_per_rad = 0.0, fit_rot_per_m = 0.0;
};

void moments(const std::vector<double>& e, double len, double* mean, double* var_per_m, double* ms_per_m) {
  double s = 0.0, s2 = 0.0;
  for (double x : e) {
    s += x;
    s2 += x * x;
  }
  const double n = static_cast<double>(e.size());
  if (e.size() < 2) return;
  *mean = s / n;
  *var_per_m = (s2 - s * *mean) / (n - 1.0) / len;
  *ms_per_m = s2 / n / len;
}

/// Least squares y ~ a x1 + b x2 with a, b >= 0.
void fit_nonneg(const std::vector<double>& x1, const std::vector<double>& x2, const std::vector<double>& y, double* a,
                double* b) {
  double s11 = 0, s12 = 0, s22 = 0, s1y = 0, s2y = 0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    s11 += x1[i] * x1[i];
    s12 += x1[i] * x2[i];
    s22 += x2[i] * x2[i];
    s1y += x1[i] * y[i];
    s2y += x2[i] * y[i];
  }
  const double det = s11 * s22 - s12 * s12;
  *a = det > 0 ? (s1y * s22 - s2y * s12) / det : -1.0;
  *b = det > 0 ? (s2y * s11 - s1y * s12) / det : -1.0;
  if (*a < 0.0 || *b < 0.0) {  // one term alone, the better of the two
    const double a1 = s11 > 0 ? std::max(0.0, s1y / s11) : 0.0, b1 = s22 > 0 ? std::max(0.0, s2y / s22) : 0.0;
    double r1 = 0, r2 = 0;
    for (std::size_t i = 0; i < y.size(); ++i) {
      r1 += std::pow(y[i] - a1 * x1[i], 2);
      r2 += std::pow(y[i] - b1 * x2[i], 2);
    }
    *a = r1 <= r2 ? a1 : 0.0;
    *b = r1 <= r2 ? 0.0 : b1;
  }
}

OdoNoise odometry_noise(const mrclam::Dataset& d, int id, double rate_hz) {
  mrclam::Options o;
  o.robots = {id};
  o.rate_hz = rate_hz;
  const mrclam::FrameSource src(d, o);
  OdoNoise r;
  const int n = src.num_frames();
  r.duration_s = static_cast<double>(n - 1) / rate_hz;
  std::vector<double> along, across, heading, turned, driven;
  int a = 0;
  double win = 0.0;
  for (int k = 1; k < n; ++k) {
    const Pose2 &o0 = src.odometer(0, k - 1), &o1 = src.odometer(0, k);
    const Pose2 &g0 = src.true_pose(0, k - 1), &g1 = src.true_pose(0, k);
    const double step = std::hypot(g1.x - g0.x, g1.y - g0.y);
    r.odo_path_m += std::hypot(o1.x - o0.x, o1.y - o0.y);
    r.vicon_path_m += step;
    win += step;
    if (win >= 1.0) {
      const Pose2 dodo = between(src.odometer(0, a), o1), dgt = between(src.true_pose(0, a), g1);
      along.push_back(dodo.x - dgt.x);
      across.push_back(dodo.y - dgt.y);
      heading.push_back(wrap_angle(dodo.theta - dgt.theta));
      // Heading turned (Vicon), summed over the frames of the window.
      double t = 0.0;
      for (int j = a + 1; j <= k; ++j)
        t += std::fabs(wrap_angle(src.true_pose(0, j).theta - src.true_pose(0, j - 1).theta));
      turned.push_back(t);
      driven.push_back(win);
      a = k;
      win = 0.0;
    }
  }
  r.windows = static_cast<long>(along.size());
  if (r.windows < 2) return r;
  double len = 0.0;
  for (double x : driven) len += x;
  r.mean_window_m = len / static_cast<double>(r.windows);
  moments(along, r.mean_window_m, &r.along_mean, &r.along_var_per_m, &r.along_ms_per_m);
  moments(across, r.mean_window_m, &r.across_mean, &r.across_var_per_m, &r.across_ms_per_m);
  moments(heading, r.mean_window_m, &r.heading_mean, &r.heading_var_per_m, &r.heading_ms_per_m);
  std::vector<double> h2(heading.size());
  for (std::size_t i = 0; i < heading.size(); ++i) h2[i] = heading[i] * heading[i];
  fit_nonneg(turned, driven, h2, &r.fit_rot_per_rad, &r.fit_rot_per_m);
  return r;
}

json to_json(const OdoNoise& r) {
  return {{"odometer_path_m", r.odo_path_m},
          {"vicon_path_m", r.vicon_path_m},
          {"scale", r.vicon_path_m > 0 ? r.odo_path_m / r.vicon_path_m : 0.0},
          {"duration_s", r.duration_s},
          {"windows", r.windows},
          {"mean_window_m", r.mean_window_m},
          {"along", {{"mean_m", r.along_mean}, {"var_per_m", r.along_var_per_m}, {"ms_per_m", r.along_ms_per_m}}},
          {"across", {{"mean_m", r.across_mean}, {"var_per_m", r.across_var_per_m}, {"ms_per_m", r.across_ms_per_m}}},
          {"heading",
           {{"mean_rad", r.heading_mean}, {"var_per_m", r.heading_var_per_m}, {"ms_per_m", r.heading_ms_per_m}}},
          {"fit_heading_ms", {{"rot_per_rad", r.fit_rot_per_rad}, {"rot_per_m", r.fit_rot_per_m}}}};
}

void print_sensor_row(const char* who, const Robust& rg, const Robust& br) {
  std::printf("%-8s %7ld %9.4f %9.4f %9.4f %7.2f%% | %9.5f %9.5f %9.5f %7.2f%%\n", who, rg.count, rg.median,
              rg.robust_sigma, rg.std_inliers, 100.0 * rg.outlier_fraction, br.median, br.robust_sigma,
              br.std_inliers, 100.0 * br.outlier_fraction);
}

struct Args {
  std::string dataset_dir, robots = "1,2,3,4,5", json_path, config_path;
  double rate = 10.0;
  double calibration_window_s = 5.0;
  double detect_range = 3.5, detect_half_deg = 17.0;
  std::vector<int> ids;
  bool check = false;
  mrclam::Options frame_options;  // --config's dataset section, read before any data
};

/// -1 to go on, else the exit code.
int parse_args(int argc, char** argv, Args* a) {
  CLI::App app{"elaslam mrclam_stats: sensor and odometry noise of an MRCLAM recording against Vicon"};
  cli::add_version_flag(app, "mrclam_stats");
  app.add_option("--dataset", a->dataset_dir, "dataset directory")->required()->check(CLI::ExistingDirectory);
  app.add_option("--robots", a->robots, "robots, e.g. 1,2,3,4,5")->capture_default_str();
  app.add_option("--rate", a->rate, "frame rate for the odometry analysis [Hz]")
      ->capture_default_str()
      ->check(cli::range(mrclam::limits::kRateMinHz, mrclam::limits::kRateMaxHz));
  app.add_option("--json", a->json_path, "also write the numbers as JSON");
  app.add_option("--calibration-window", a->calibration_window_s,
                 "odometer calibration: fit over windows of this many seconds [s] (mrclam::fit_odometry)")
      ->capture_default_str()
      ->check(cli::range(0.0, 600.0));
  app.add_option("--detect-range", a->detect_range, "detection statistics: in view within this range [m]")
      ->capture_default_str()->check(cli::range(0.1, 100.0));
  app.add_option("--detect-half-angle", a->detect_half_deg, "... and this half-angle of the heading [deg]")
      ->capture_default_str()->check(cli::range(1.0, 180.0));
  app.add_option("--config", a->config_path,
                 "also measure the residuals of the frames as the filter receives them, imported with this "
                 "config's dataset section (calibration, motion compensation, odometry delay)");
  app.add_flag("--check", a->check, "check the command line and --config and exit (0: valid); reads no data");
  if (const int rc = cli::parse(app, argc, argv); rc >= 0) return rc;
  std::string why;
  if (!mrclam::parse_robot_list(a->robots, &a->ids, &why)) {
    std::fprintf(stderr, "mrclam_stats: --robots: %s\n", why.c_str());
    return cli::kExitBadInput;
  }
  return -1;
}

/// Per robot and overall: sensor residuals, odometry noise and lag.
struct PerRobot {
  Robust range, bearing;  // overall
  Residuals all;
  std::vector<OdoNoise> odo;
  std::vector<double> lags;
};

PerRobot per_robot(const mrclam::Dataset& d, const Args& a, json* out) {
  PerRobot p;
  std::printf("Range / bearing residuals (measured - predicted from Vicon), static landmarks 6-20\n");
  std::printf("%-8s %7s %9s %9s %9s %8s | %9s %9s %9s %8s\n", "robot", "count", "rng_med", "rng_rsig",
              "rng_std5", "rng_out", "brg_med", "brg_rsig", "brg_std5", "brg_out");
  for (int id : a.ids) {
    const Residuals r = sensor_residuals(d, d.robot(id));
    const Robust rg = robust(r.range), br = robust(r.bearing);
    print_sensor_row(("R" + std::to_string(id)).c_str(), rg, br);
    json& jr = (*out)["robots"][std::to_string(id)];
    jr["range_m"] = to_json(rg);
    jr["bearing_rad"] = to_json(br);
    p.all.range.insert(p.all.range.end(), r.range.begin(), r.range.end());
    p.all.bearing.insert(p.all.bearing.end(), r.bearing.begin(), r.bearing.end());
    p.all.measured_range.insert(p.all.measured_range.end(), r.measured_range.begin(), r.measured_range.end());
    p.all.measured_bearing.insert(p.all.measured_bearing.end(), r.measured_bearing.begin(), r.measured_bearing.end());
    p.odo.push_back(odometry_noise(d, id, a.rate));
    p.lags.push_back(odometry_lag(d.robot(id)));
    jr["odometry_lag_s"] = p.lags.back();
    jr["odometry"] = to_json(p.odo.back());
  }
  p.range = robust(p.all.range);
  p.bearing = robust(p.all.bearing);
  print_sensor_row("all", p.range, p.bearing);
  (*out)["overall"]["range_m"] = to_json(p.range);
  (*out)["overall"]["bearing_rad"] = to_json(p.bearing);
  return p;
}

void report_range_scale_and_lag(const PerRobot& p, json* out) {
  const RangeScale scale = fit_range_scale(p.all);
  std::printf("\nRange scale (the camera's range depends on where the barcode is in the image): fit over %ld\n"
              "measurements, residual = r (k0 + k1 b^2): k0 %.5f, k1 %.5f; range residual std %.4f m before,\n"
              "%.4f m after dividing each range by 1 + k0 + k1 b^2 (dataset.range_scale)\n",
              scale.used, scale.k0, scale.k1, scale.std_before, scale.std_after);
  double lag_mean = 0.0;
  for (double l : p.lags) lag_mean += l / static_cast<double>(p.lags.size());
  std::printf("\nOdometry lag (commands lead the motion): the command in force at t - d fits Vicon's turn rate at t\n"
              "best for d =");
  for (double l : p.lags) std::printf(" %.2f", l);
  std::printf(" s (robots in order); mean %.3f s (dataset.odometry_delay_s)\n", lag_mean);
  (*out)["odometry_lag_s"] = lag_mean;
  (*out)["range_scale"] = {{"k0", scale.k0}, {"k1", scale.k1}, {"used", scale.used},
                           {"std_before", scale.std_before}, {"std_after", scale.std_after}};
}

// The frames as the robots get them (imported with the config's dataset section):
// observations against the Vicon pose at the frame time and the landmarks' positions.
void report_frame_residuals(const mrclam::Dataset& d, const Args& a, json* out) {
  mrclam::Options fo = a.frame_options;
  fo.robots = a.ids;
  fo.with_robot_barcodes = false;
  const mrclam::FrameSource src(d, fo);
  Residuals fr;
  std::vector<sensor_frame_t> sensors;
  for (std::size_t i = 0; i < a.ids.size(); ++i) {
    for (int k = 0; k < src.num_frames(); ++k) {
      src.frame(k, nullptr, &sensors);
      const Pose2& T = src.true_pose(static_cast<int>(i), k);
      const sensor_frame_t& f = sensors[i];
      for (int o = 0; o < f.num_obs; ++o) {
        const auto lm = std::find_if(d.landmarks().begin(), d.landmarks().end(),
                                     [&](const mrclam::LandmarkTruth& l) { return l.subject == f.obs[o].landmark_id; });
        if (lm == d.landmarks().end()) continue;
        const double dx = lm->x - T.x, dy = lm->y - T.y;
        fr.range.push_back(f.obs[o].range - std::hypot(dx, dy));
        fr.bearing.push_back(wrap_angle(f.obs[o].bearing - (std::atan2(dy, dx) - T.theta)));
      }
    }
  }
  const Robust frg = robust(fr.range), fbr = robust(fr.bearing);
  std::printf("\nResiduals of the frames as imported with %s (against Vicon at the frame time):\n", a.config_path.c_str());
  print_sensor_row("frames", frg, fbr);
  (*out)["frame_residuals"] = {{"config", a.config_path}, {"range_m", to_json(frg)}, {"bearing_rad", to_json(fbr)}};
}

void report_detection(const mrclam::Dataset& d, const Args& a, json* out) {
  const Detection det = detection(d, a.ids, a.rate, a.detect_range, deg2rad(a.detect_half_deg));
  const double p_frame = det.in_view > 0 ? static_cast<double>(det.reported) / static_cast<double>(det.in_view) : 0.0;
  const double p99 = quantile(det.miss_streaks, 0.99), p999 = quantile(det.miss_streaks, 0.999);
  // The rule sees thousands of miss runs in a run: it should wait longer than all
  // but 0.1 % of them. The per-frame detection probability for which the rule
  // (waiting until (1 - p)^n <= 0.01) waits p99.9 frames: (1 - p)^p999 = 0.01.
  const double p_eff = p999 > 0 ? 1.0 - std::pow(0.01, 1.0 / p999) : 1.0;
  std::printf("\nDetection (static landmarks within %.1f m and +-%.0f deg of the Vicon pose, %.3g Hz frames):\n"
              "reported in %.3f of %ld landmark-frames; %zu runs of misses: p50 %.0f, p90 %.0f, p99 %.0f,\n"
              "p99.9 %.0f, max %.0f frames. Misses come in bursts; the missing rule waits p99.9 frames with a\n"
              "per-frame detection probability of %.3f (robot.ela.detection_probability)\n",
              a.detect_range, a.detect_half_deg, a.rate, p_frame, det.in_view, det.miss_streaks.size(),
              quantile(det.miss_streaks, 0.5), quantile(det.miss_streaks, 0.9), p99, p999,
              det.miss_streaks.empty() ? 0.0 : *std::max_element(det.miss_streaks.begin(), det.miss_streaks.end()), p_eff);
  (*out)["detection"] = {{"range_m", a.detect_range}, {"half_angle_deg", a.detect_half_deg},
                         {"reported_fraction", p_frame}, {"landmark_frames", det.in_view},
                         {"miss_run_p99_frames", p99}, {"miss_run_p999_frames", p999},
                         {"detection_probability_for_missing_rule", p_eff}};
}

// The odometry table, and the noise values suggested for the config (window-weighted).
void report_odometry(const PerRobot& p, const Args& a, json* out) {
  std::printf("\nOdometry (each robot over its own window, frames at %.3g Hz; windows of >= 1 m driven)\n", a.rate);
  std::printf("%-6s %8s %9s %9s %6s %7s | %9s %9s %9s | %9s %9s | %9s %9s %9s | %9s %9s\n", "robot", "time_s",
              "odo_m", "vicon_m", "scale", "windows", "along_mu", "along_var", "along_ms", "cross_var",
              "cross_ms", "head_mu", "head_var", "head_ms", "fit_rad", "fit_m");
  double w_sum = 0, trans_ms = 0, trans_var = 0, head_ms = 0, head_var = 0, fit_rad = 0, fit_m = 0;
  for (std::size_t i = 0; i < a.ids.size(); ++i) {
    const OdoNoise& r = p.odo[i];
    std::printf("R%-5d %8.1f %9.2f %9.2f %6.3f %7ld | %9.4f %9.5f %9.5f | %9.5f %9.5f | %9.4f %9.5f %9.5f | %9.5f %9.5f\n",
                a.ids[i], r.duration_s, r.odo_path_m, r.vicon_path_m, r.odo_path_m / r.vicon_path_m, r.windows,
                r.along_mean, r.along_var_per_m, r.along_ms_per_m, r.across_var_per_m, r.across_ms_per_m,
                r.heading_mean, r.heading_var_per_m, r.heading_ms_per_m, r.fit_rot_per_rad, r.fit_rot_per_m);
    const double w = static_cast<double>(r.windows);
    w_sum += w;
    trans_ms += w * 0.5 * (r.along_ms_per_m + r.across_ms_per_m);
    trans_var += w * 0.5 * (r.along_var_per_m + r.across_var_per_m);
    head_ms += w * r.heading_ms_per_m;
    head_var += w * r.heading_var_per_m;
    fit_rad += w * r.fit_rot_per_rad;
    fit_m += w * r.fit_rot_per_m;
  }
  if (w_sum > 0) {
    trans_ms /= w_sum, trans_var /= w_sum, head_ms /= w_sum, head_var /= w_sum, fit_rad /= w_sum, fit_m /= w_sum;
  }
  std::printf("\nSuggested (window-weighted over robots):\n");
  std::printf("  range_sigma_m     %.4f  (std within 5 robust sigmas; robust sigma %.4f)\n", p.range.std_inliers,
              p.range.robust_sigma);
  std::printf("  bearing_sigma_rad %.5f (%.3f deg; robust sigma %.5f)\n", p.bearing.std_inliers,
              p.bearing.std_inliers * 180.0 / kPi, p.bearing.robust_sigma);
  std::printf("  odom_var_trans_per_m %.5f  (mean square, along+across / 2; about the mean: %.5f)\n", trans_ms,
              trans_var);
  std::printf("  odom_var_rot_per_m   %.5f  (heading mean square per m; about the mean: %.5f)\n", head_ms, head_var);
  std::printf("  fit heading^2 = %.5f |turned rad| + %.5f |driven m|  (odom_var_rot_per_rad, odom_var_rot_per_m)\n",
              fit_rad, fit_m);
  (*out)["suggested"] = {{"range_sigma_m", p.range.std_inliers},
                         {"bearing_sigma_rad", p.bearing.std_inliers},
                         {"odom_var_trans_per_m", trans_ms},
                         {"odom_var_trans_per_m_about_mean", trans_var},
                         {"odom_var_rot_per_m", head_ms},
                         {"odom_var_rot_per_m_about_mean", head_var},
                         {"fit_odom_var_rot_per_rad", fit_rad},
                         {"fit_odom_var_rot_per_m", fit_m}};
}

json to_json(const mrclam::OdometryFit& f) {
  return {{"steps", f.steps},
          {"speed_scale", f.speed_scale},
          {"turn_scale", f.turn_scale},
          {"turn_bias_rad_s", f.turn_bias_rad_s},
          {"turn_scale_without_bias", f.turn_scale_without_bias},
          {"reported_m", f.reported_m},
          {"reported_rad", f.reported_rad}};
}

// The odometer's systematic error per robot (true = scale x reported, turn + bias dt),
// over the run and its two halves, to set or check robot.odometry_calibration.
void report_calibration(const mrclam::Dataset& d, const Args& a, json* out) {
  mrclam::Options fo = a.frame_options;
  fo.robots = a.ids;
  fo.rate_hz = a.rate;
  const mrclam::FrameSource src(d, fo);
  const int n = src.num_frames(), half = n / 2;
  const int window = std::max(1, static_cast<int>(std::lround(a.calibration_window_s * a.rate)));
  std::printf("\nOdometer calibration (true increment = speed scale x reported translation, turn scale x\n"
              "reported turn + bias x dt), least squares of Vicon's increments on the odometer's over windows of\n"
              "%d frames (%.3g s) at %.3g Hz, frames imported %s; whole run and each half (%d frames):\n",
              window, window / a.rate, a.rate,
              a.config_path.empty() ? "without a config (no odometry delay)" : ("with " + a.config_path).c_str(), n);
  std::printf("%-6s %6s %9s %9s %11s %9s | %9s %9s %11s | %9s %9s %11s\n", "robot", "windows", "speed", "turn",
              "bias_rad_s", "turn_only", "speed_1st", "turn_1st", "bias_1st", "speed_2nd", "turn_2nd", "bias_2nd");
  for (std::size_t i = 0; i < a.ids.size(); ++i) {
    const int r = static_cast<int>(i);
    const mrclam::OdometryFit all = mrclam::fit_odometry(src, r, 0, -1, window),
                              h1 = mrclam::fit_odometry(src, r, 0, half, window),
                              h2 = mrclam::fit_odometry(src, r, half, -1, window);
    std::printf("R%-5d %6d %9.4f %9.4f %11.5f %9.4f | %9.4f %9.4f %11.5f | %9.4f %9.4f %11.5f\n", a.ids[i], all.steps,
                all.speed_scale, all.turn_scale, all.turn_bias_rad_s, all.turn_scale_without_bias, h1.speed_scale,
                h1.turn_scale, h1.turn_bias_rad_s, h2.speed_scale, h2.turn_scale, h2.turn_bias_rad_s);
    (*out)["robots"][std::to_string(a.ids[i])]["odometry_calibration"] = {
        {"window_s", window / a.rate}, {"run", to_json(all)}, {"first_half", to_json(h1)}, {"second_half", to_json(h2)}};
  }
}

int stats_main(int argc, char** argv) {
  Args a;
  if (const int rc = parse_args(argc, argv, &a); rc >= 0) return rc;
  // --config before the data: a bad one is refused (ConfigError: exit 2 through
  // guarded_main) before minutes of analysis.
  if (!a.config_path.empty()) a.frame_options = mrclam::load_options(a.config_path);
  if (a.check) {
    std::printf("mrclam_stats: valid%s%s\n", a.config_path.empty() ? "" : ", --config ", a.config_path.c_str());
    return 0;
  }
  json out;
  out["dataset"] = a.dataset_dir;
  out["rate_hz"] = a.rate;
  try {
    const mrclam::Dataset d = mrclam::Dataset::load(a.dataset_dir, a.ids);
    const PerRobot p = per_robot(d, a, &out);
    report_range_scale_and_lag(p, &out);
    if (!a.config_path.empty()) report_frame_residuals(d, a, &out);
    report_detection(d, a, &out);
    report_odometry(p, a, &out);
    report_calibration(d, a, &out);
  } catch (const mrclam::DatasetError& e) {
    std::fprintf(stderr, "mrclam_stats: %s\n", e.what());
    return cli::kExitFailure;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "mrclam_stats: %s\n", e.what());
    return cli::kExitBadInput;
  }
  if (!a.json_path.empty()) {
    std::ofstream f(a.json_path);
    f << out.dump(2) << "\n";
    if (!f) {
      std::fprintf(stderr, "mrclam_stats: cannot write %s\n", a.json_path.c_str());
      return cli::kExitFailure;
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return cli::guarded_main("mrclam_stats", [&] { return stats_main(argc, argv); });
}

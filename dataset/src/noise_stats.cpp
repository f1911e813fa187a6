// SPDX-License-Identifier: Apache-2.0
#include "elaslam/dataset/noise_stats.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace elaslam::mrclam {

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

void Residuals::append(const Residuals& o) {
  range.insert(range.end(), o.range.begin(), o.range.end());
  bearing.insert(bearing.end(), o.bearing.begin(), o.bearing.end());
  measured_range.insert(measured_range.end(), o.measured_range.begin(), o.measured_range.end());
  measured_bearing.insert(measured_bearing.end(), o.measured_bearing.begin(), o.measured_bearing.end());
}

namespace {

const LandmarkTruth* landmark(const Dataset& d, int subject) {
  const auto lm = std::find_if(d.landmarks().begin(), d.landmarks().end(),
                               [subject](const LandmarkTruth& l) { return l.subject == subject; });
  return lm == d.landmarks().end() ? nullptr : &*lm;
}

}  // namespace

Residuals sensor_residuals(const Dataset& d, const RobotSeries& s) {
  Residuals out;
  std::size_t hint = 0;
  for (const Measurement& z : s.measurements) {
    const int subject = d.subject_of_barcode(z.barcode);
    if (subject < kFirstLandmarkSubject) continue;
    const LandmarkTruth* lm = landmark(d, subject);
    Pose2 T;
    if (lm == nullptr || !interpolate(s.ground_truth, z.utime, &T, &hint)) continue;
    const double dx = lm->x - T.x, dy = lm->y - T.y;
    out.range.push_back(z.range - std::hypot(dx, dy));
    out.bearing.push_back(wrap_angle(z.bearing - (std::atan2(dy, dx) - T.theta)));
    out.measured_range.push_back(z.range);
    out.measured_bearing.push_back(z.bearing);
  }
  return out;
}

Residuals frame_residuals(const Dataset& d, const Options& o) {
  Options fo = o;
  fo.with_robot_barcodes = false;
  const FrameSource src(d, fo);
  Residuals fr;
  std::vector<sensor_frame_t> sensors;
  for (std::size_t i = 0; i < fo.robots.size(); ++i) {
    for (int k = 0; k < src.num_frames(); ++k) {
      src.frame(k, nullptr, &sensors);
      const Pose2& T = src.true_pose(static_cast<int>(i), k);
      const sensor_frame_t& f = sensors[i];
      for (int j = 0; j < f.num_obs; ++j) {
        const LandmarkTruth* lm = landmark(d, f.obs[j].landmark_id);
        if (lm == nullptr) continue;
        const double dx = lm->x - T.x, dy = lm->y - T.y;
        fr.range.push_back(f.obs[j].range - std::hypot(dx, dy));
        fr.bearing.push_back(wrap_angle(f.obs[j].bearing - (std::atan2(dy, dx) - T.theta)));
      }
    }
  }
  return fr;
}

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

double odometry_lag(const RobotSeries& s) {
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
    if (!interpolate(gt, u, &p, &hint)) continue;
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
    if (err < best_err) best_err = err, best_lag = static_cast<double>(lag) * 1e-6;
  }
  return best_lag;
}

Detection detection(const Dataset& d, const std::vector<int>& ids, double rate, double range, double half_angle) {
  Options o;
  o.robots = ids;
  o.rate_hz = rate;
  const FrameSource src(d, o);
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
        for (int j = 0; j < f.num_obs; ++j) seen = seen || f.obs[j].landmark_id == lm.subject;
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

OdoNoise odometry_noise(const Dataset& d, int id, double rate_hz) {
  Options o;
  o.robots = {id};
  o.rate_hz = rate_hz;
  const FrameSource src(d, o);
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

SuggestedOdometry suggest_odometry(const std::vector<OdoNoise>& robots) {
  SuggestedOdometry s;
  double w_sum = 0;
  for (const OdoNoise& r : robots) {
    const double w = static_cast<double>(r.windows);
    w_sum += w;
    s.trans_ms += w * 0.5 * (r.along_ms_per_m + r.across_ms_per_m);
    s.trans_var += w * 0.5 * (r.along_var_per_m + r.across_var_per_m);
    s.rot_ms += w * r.heading_ms_per_m;
    s.rot_var += w * r.heading_var_per_m;
    s.fit_rot_per_rad += w * r.fit_rot_per_rad;
    s.fit_rot_per_m += w * r.fit_rot_per_m;
  }
  if (w_sum > 0) {
    s.trans_ms /= w_sum, s.trans_var /= w_sum, s.rot_ms /= w_sum, s.rot_var /= w_sum, s.fit_rot_per_rad /= w_sum,
        s.fit_rot_per_m /= w_sum;
  }
  return s;
}

}  // namespace elaslam::mrclam

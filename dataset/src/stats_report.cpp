// SPDX-License-Identifier: Apache-2.0
#include "elaslam/dataset/stats_report.hpp"

#include <algorithm>
#include <cmath>

#include "elaslam/common/quantile.hpp"
#include "elaslam/dataset/noise_stats.hpp"

namespace elaslam::mrclam {
namespace {

using nlohmann::json;

json to_json(const Robust& s) {
  return {{"count", s.count},          {"median", s.median},           {"robust_sigma", s.robust_sigma},
          {"std_inliers", s.std_inliers}, {"mean_inliers", s.mean_inliers}, {"outlier_fraction", s.outlier_fraction}};
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

json to_json(const OdometryFit& f) {
  return {{"steps", f.steps},
          {"speed_scale", f.speed_scale},
          {"turn_scale", f.turn_scale},
          {"turn_bias_rad_s", f.turn_bias_rad_s},
          {"turn_scale_without_bias", f.turn_scale_without_bias},
          {"reported_m", f.reported_m},
          {"reported_rad", f.reported_rad}};
}

void print_sensor_row(std::FILE* out, const char* who, const Robust& rg, const Robust& br) {
  std::fprintf(out, "%-8s %7ld %9.4f %9.4f %9.4f %7.2f%% | %9.5f %9.5f %9.5f %7.2f%%\n", who, rg.count, rg.median,
               rg.robust_sigma, rg.std_inliers, 100.0 * rg.outlier_fraction, br.median, br.robust_sigma,
               br.std_inliers, 100.0 * br.outlier_fraction);
}

/// Per robot and overall: sensor residuals, odometry noise and lag.
struct PerRobot {
  Robust range, bearing;  // overall
  Residuals all;
  std::vector<OdoNoise> odo;
  std::vector<double> lags;
};

PerRobot per_robot(const Dataset& d, const StatsOptions& a, std::FILE* f, json* out) {
  PerRobot p;
  std::fprintf(f, "Range / bearing residuals (measured - predicted from Vicon), static landmarks 6-20\n");
  std::fprintf(f, "%-8s %7s %9s %9s %9s %8s | %9s %9s %9s %8s\n", "robot", "count", "rng_med", "rng_rsig",
               "rng_std5", "rng_out", "brg_med", "brg_rsig", "brg_std5", "brg_out");
  for (int id : a.ids) {
    const Residuals r = sensor_residuals(d, d.robot(id));
    const Robust rg = robust(r.range), br = robust(r.bearing);
    print_sensor_row(f, ("R" + std::to_string(id)).c_str(), rg, br);
    json& jr = (*out)["robots"][std::to_string(id)];
    jr["range_m"] = to_json(rg);
    jr["bearing_rad"] = to_json(br);
    p.all.append(r);
    p.odo.push_back(odometry_noise(d, id, a.rate));
    p.lags.push_back(odometry_lag(d.robot(id)));
    jr["odometry_lag_s"] = p.lags.back();
    jr["odometry"] = to_json(p.odo.back());
  }
  p.range = robust(p.all.range);
  p.bearing = robust(p.all.bearing);
  print_sensor_row(f, "all", p.range, p.bearing);
  (*out)["overall"]["range_m"] = to_json(p.range);
  (*out)["overall"]["bearing_rad"] = to_json(p.bearing);
  return p;
}

void report_range_scale_and_lag(const PerRobot& p, std::FILE* f, json* out) {
  const RangeScale scale = fit_range_scale(p.all);
  std::fprintf(f,
               "\nRange scale (the camera's range depends on where the barcode is in the image): fit over %ld\n"
               "measurements, residual = r (k0 + k1 b^2): k0 %.5f, k1 %.5f; range residual std %.4f m before,\n"
               "%.4f m after dividing each range by 1 + k0 + k1 b^2 (dataset.range_scale)\n",
               scale.used, scale.k0, scale.k1, scale.std_before, scale.std_after);
  double lag_mean = 0.0;
  for (double l : p.lags) lag_mean += l / static_cast<double>(p.lags.size());
  std::fprintf(f,
               "\nOdometry lag (commands lead the motion): the command in force at t - d fits Vicon's turn rate at t\n"
               "best for d =");
  for (double l : p.lags) std::fprintf(f, " %.2f", l);
  std::fprintf(f, " s (robots in order); mean %.3f s (dataset.odometry_delay_s)\n", lag_mean);
  (*out)["odometry_lag_s"] = lag_mean;
  (*out)["range_scale"] = {{"k0", scale.k0}, {"k1", scale.k1}, {"used", scale.used},
                           {"std_before", scale.std_before}, {"std_after", scale.std_after}};
}

// The frames as the robots get them (imported with the config's dataset section).
void report_frame_residuals(const Dataset& d, const StatsOptions& a, std::FILE* f, json* out) {
  Options fo = a.frame_options;
  fo.robots = a.ids;
  const Residuals fr = frame_residuals(d, fo);
  const Robust frg = robust(fr.range), fbr = robust(fr.bearing);
  std::fprintf(f, "\nResiduals of the frames as imported with %s (against Vicon at the frame time):\n",
               a.config_path.c_str());
  print_sensor_row(f, "frames", frg, fbr);
  (*out)["frame_residuals"] = {{"config", a.config_path}, {"range_m", to_json(frg)}, {"bearing_rad", to_json(fbr)}};
}

void report_detection(const Dataset& d, const StatsOptions& a, std::FILE* f, json* out) {
  const Detection det = detection(d, a.ids, a.rate, a.detect_range, deg2rad(a.detect_half_deg));
  const double p_frame = det.in_view > 0 ? static_cast<double>(det.reported) / static_cast<double>(det.in_view) : 0.0;
  const double p99 = quantile(det.miss_streaks, 0.99), p999 = quantile(det.miss_streaks, 0.999);
  // The rule sees thousands of miss runs in a run: it should wait longer than all
  // but 0.1 % of them. The per-frame detection probability for which the rule
  // (waiting until (1 - p)^n <= 0.01) waits p99.9 frames: (1 - p)^p999 = 0.01.
  const double p_eff = p999 > 0 ? 1.0 - std::pow(0.01, 1.0 / p999) : 1.0;
  std::fprintf(f,
               "\nDetection (static landmarks within %.1f m and +-%.0f deg of the Vicon pose, %.3g Hz frames):\n"
               "reported in %.3f of %ld landmark-frames; %zu runs of misses: p50 %.0f, p90 %.0f, p99 %.0f,\n"
               "p99.9 %.0f, max %.0f frames. Misses come in bursts; the missing rule waits p99.9 frames with a\n"
               "per-frame detection probability of %.3f (robot.ela.detection_probability)\n",
               a.detect_range, a.detect_half_deg, a.rate, p_frame, det.in_view, det.miss_streaks.size(),
               quantile(det.miss_streaks, 0.5), quantile(det.miss_streaks, 0.9), p99, p999,
               det.miss_streaks.empty() ? 0.0 : *std::max_element(det.miss_streaks.begin(), det.miss_streaks.end()),
               p_eff);
  (*out)["detection"] = {{"range_m", a.detect_range}, {"half_angle_deg", a.detect_half_deg},
                         {"reported_fraction", p_frame}, {"landmark_frames", det.in_view},
                         {"miss_run_p99_frames", p99}, {"miss_run_p999_frames", p999},
                         {"detection_probability_for_missing_rule", p_eff}};
}

// The odometry table, and the noise values suggested for the config (window-weighted).
void report_odometry(const PerRobot& p, const StatsOptions& a, std::FILE* f, json* out) {
  std::fprintf(f, "\nOdometry (each robot over its own window, frames at %.3g Hz; windows of >= 1 m driven)\n", a.rate);
  std::fprintf(f, "%-6s %8s %9s %9s %6s %7s | %9s %9s %9s | %9s %9s | %9s %9s %9s | %9s %9s\n", "robot", "time_s",
               "odo_m", "vicon_m", "scale", "windows", "along_mu", "along_var", "along_ms", "cross_var",
               "cross_ms", "head_mu", "head_var", "head_ms", "fit_rad", "fit_m");
  for (std::size_t i = 0; i < a.ids.size(); ++i) {
    const OdoNoise& r = p.odo[i];
    std::fprintf(f,
                 "R%-5d %8.1f %9.2f %9.2f %6.3f %7ld | %9.4f %9.5f %9.5f | %9.5f %9.5f | %9.4f %9.5f %9.5f | %9.5f "
                 "%9.5f\n",
                 a.ids[i], r.duration_s, r.odo_path_m, r.vicon_path_m, r.odo_path_m / r.vicon_path_m, r.windows,
                 r.along_mean, r.along_var_per_m, r.along_ms_per_m, r.across_var_per_m, r.across_ms_per_m,
                 r.heading_mean, r.heading_var_per_m, r.heading_ms_per_m, r.fit_rot_per_rad, r.fit_rot_per_m);
  }
  const SuggestedOdometry s = suggest_odometry(p.odo);
  std::fprintf(f, "\nSuggested (window-weighted over robots):\n");
  std::fprintf(f, "  range_sigma_m     %.4f  (std within 5 robust sigmas; robust sigma %.4f)\n", p.range.std_inliers,
               p.range.robust_sigma);
  std::fprintf(f, "  bearing_sigma_rad %.5f (%.3f deg; robust sigma %.5f)\n", p.bearing.std_inliers,
               p.bearing.std_inliers * 180.0 / kPi, p.bearing.robust_sigma);
  std::fprintf(f, "  odom_var_trans_per_m %.5f  (mean square, along+across / 2; about the mean: %.5f)\n", s.trans_ms,
               s.trans_var);
  std::fprintf(f, "  odom_var_rot_per_m   %.5f  (heading mean square per m; about the mean: %.5f)\n", s.rot_ms,
               s.rot_var);
  std::fprintf(f,
               "  fit heading^2 = %.5f |turned rad| + %.5f |driven m|  (odom_var_rot_per_rad, odom_var_rot_per_m)\n",
               s.fit_rot_per_rad, s.fit_rot_per_m);
  (*out)["suggested"] = {{"range_sigma_m", p.range.std_inliers},
                         {"bearing_sigma_rad", p.bearing.std_inliers},
                         {"odom_var_trans_per_m", s.trans_ms},
                         {"odom_var_trans_per_m_about_mean", s.trans_var},
                         {"odom_var_rot_per_m", s.rot_ms},
                         {"odom_var_rot_per_m_about_mean", s.rot_var},
                         {"fit_odom_var_rot_per_rad", s.fit_rot_per_rad},
                         {"fit_odom_var_rot_per_m", s.fit_rot_per_m}};
}

// The odometer's systematic error per robot (true = scale x reported, turn + bias dt),
// over the run and its two halves, to set or check robot.odometry_calibration.
void report_calibration(const Dataset& d, const StatsOptions& a, std::FILE* f, json* out) {
  Options fo = a.frame_options;
  fo.robots = a.ids;
  fo.rate_hz = a.rate;
  const FrameSource src(d, fo);
  const int n = src.num_frames(), half = n / 2;
  const int window = std::max(1, static_cast<int>(std::lround(a.calibration_window_s * a.rate)));
  std::fprintf(f,
               "\nOdometer calibration (true increment = speed scale x reported translation, turn scale x\n"
               "reported turn + bias x dt), least squares of Vicon's increments on the odometer's over windows of\n"
               "%d frames (%.3g s) at %.3g Hz, frames imported %s; whole run and each half (%d frames):\n",
               window, window / a.rate, a.rate,
               a.config_path.empty() ? "without a config (no odometry delay)" : ("with " + a.config_path).c_str(), n);
  std::fprintf(f, "%-6s %6s %9s %9s %11s %9s | %9s %9s %11s | %9s %9s %11s\n", "robot", "windows", "speed", "turn",
               "bias_rad_s", "turn_only", "speed_1st", "turn_1st", "bias_1st", "speed_2nd", "turn_2nd", "bias_2nd");
  for (std::size_t i = 0; i < a.ids.size(); ++i) {
    const int r = static_cast<int>(i);
    const OdometryFit all = fit_odometry(src, r, 0, -1, window), h1 = fit_odometry(src, r, 0, half, window),
                      h2 = fit_odometry(src, r, half, -1, window);
    std::fprintf(f, "R%-5d %6d %9.4f %9.4f %11.5f %9.4f | %9.4f %9.4f %11.5f | %9.4f %9.4f %11.5f\n", a.ids[i],
                 all.steps, all.speed_scale, all.turn_scale, all.turn_bias_rad_s, all.turn_scale_without_bias,
                 h1.speed_scale, h1.turn_scale, h1.turn_bias_rad_s, h2.speed_scale, h2.turn_scale, h2.turn_bias_rad_s);
    (*out)["robots"][std::to_string(a.ids[i])]["odometry_calibration"] = {
        {"window_s", window / a.rate}, {"run", to_json(all)}, {"first_half", to_json(h1)}, {"second_half", to_json(h2)}};
  }
}

}  // namespace

nlohmann::json noise_report(const Dataset& d, const StatsOptions& o, std::FILE* out) {
  json j;
  j["dataset"] = o.dataset_dir;
  j["rate_hz"] = o.rate;
  const PerRobot p = per_robot(d, o, out, &j);
  report_range_scale_and_lag(p, out, &j);
  if (!o.config_path.empty()) report_frame_residuals(d, o, out, &j);
  report_detection(d, o, out, &j);
  report_odometry(p, o, out, &j);
  report_calibration(d, o, out, &j);
  return j;
}

}  // namespace elaslam::mrclam

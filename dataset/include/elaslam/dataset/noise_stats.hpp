// SPDX-License-Identifier: Apache-2.0
// The noise of a UTIAS MRCLAM recording measured against its Vicon ground truth
// (mrclam_stats prints them; stats_report.hpp): residuals of the static landmarks'
// range and bearing, their robust statistics, the camera's range scale, the
// odometry's lag, noise per metre driven and the camera's detection rate.
#pragma once

#include <vector>

#include "elaslam/dataset/mrclam.hpp"

namespace elaslam::mrclam {

/// Robust statistics of residuals: median, robust sigma (1.4826 MAD), the plain mean
/// and std of the residuals within 5 robust sigmas of the median (inliers), and the
/// fraction outside (outliers: misreads, occlusions).
struct Robust {
  long count = 0;
  double median = 0.0, robust_sigma = 0.0, std_inliers = 0.0, mean_inliers = 0.0, outlier_fraction = 0.0;
};
/// The median (the mean of the two middle values of an even count); 0 when empty.
double median_of(std::vector<double> v);
Robust robust(const std::vector<double>& r);

/// Range and bearing residuals (measured - predicted from Vicon, bearing wrapped)
/// and the measured range and bearing they belong to.
struct Residuals {
  std::vector<double> range, bearing;
  std::vector<double> measured_range, measured_bearing;
  void append(const Residuals& other);
};

/// Every measurement of a static landmark (subjects 6-20) whose time lies inside the
/// robot's ground truth, against the range and bearing predicted from the Vicon pose
/// interpolated at that time.
Residuals sensor_residuals(const Dataset& d, const RobotSeries& s);

/// The frames as the robots get them (imported with `o`, robot barcodes dropped):
/// each observation against the Vicon pose at the frame time. Range and bearing only.
Residuals frame_residuals(const Dataset& d, const Options& o);

/// Range scale calibration: fit range residual = r (k0 + k1 b^2) by least squares
/// over the measurements with |range residual| < 1 m and |bearing residual| < 0.1
/// rad (r, b as measured); the importer divides each range by 1 + k0 + k1 b^2.
/// std_before / std_after: the range residuals' std before and after that division.
struct RangeScale {
  double k0 = 0.0, k1 = 0.0, std_before = 0.0, std_after = 0.0;
  long used = 0;
};
RangeScale fit_range_scale(const Residuals& r);

/// How far the velocity commands lead the motion: the delay d [s] for which the
/// command in force at t - d best matches Vicon's angular rate at t (least squares
/// over a 50 Hz grid, d in [-0.5, 0.8] s by 0.02 s, 5 s trimmed at both ends).
double odometry_lag(const RobotSeries& s);

/// How reliably the camera reports a landmark that is in view: over the frames at
/// `rate` Hz, every static landmark inside `range` m and +-`half_angle` rad of a
/// robot's Vicon pose is either reported in the frame or missed.
struct Detection {
  long in_view = 0, reported = 0;
  std::vector<double> miss_streaks;  // lengths of the runs of consecutive misses [frames]
};
Detection detection(const Dataset& d, const std::vector<int>& ids, double rate, double range, double half_angle);

/// Odometry noise of one robot over its own full window, frames at a rate. Scale =
/// path length of the dead-reckoned odometer / of Vicon. Noise: consecutive windows
/// of >= 1 m driven (Vicon); in each, the odometer increment minus the Vicon
/// increment (both in the frame of the robot at the window start): along track,
/// across track, heading. var per m = variance / mean window length (about the mean:
/// the scale bias excluded); ms per m = mean square / mean window length (bias
/// included: what a filter that models no bias should use).
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
OdoNoise odometry_noise(const Dataset& d, int id, double rate_hz);

/// Mean, variance per `len` and mean square per `len` of e; left as they are when
/// e has fewer than 2 values.
void moments(const std::vector<double>& e, double len, double* mean, double* var_per_m, double* ms_per_m);

/// Least squares y ~ a x1 + b x2 with a, b >= 0 (else the better one-term fit).
void fit_nonneg(const std::vector<double>& x1, const std::vector<double>& x2, const std::vector<double>& y, double* a,
                double* b);

/// The odometry noise values for the config: every robot's, weighted by its windows.
/// trans: (along + across) / 2.
struct SuggestedOdometry {
  double trans_ms = 0.0, trans_var = 0.0, rot_ms = 0.0, rot_var = 0.0, fit_rot_per_rad = 0.0, fit_rot_per_m = 0.0;
};
SuggestedOdometry suggest_odometry(const std::vector<OdoNoise>& robots);

}  // namespace elaslam::mrclam

// SPDX-License-Identifier: Apache-2.0
// Importer for the UTIAS Multi-Robot Cooperative Localization and Mapping dataset
// (Leung et al., IJRR 2011; data/mrclam/dataset6/README.md, tools/get_mrclam.sh): the text files of
// one recording become, frame by frame, the messages the simulator would publish
// (sensor_frame_t per robot, ground_truth_t), so the robots and main run unchanged.
//
// Conventions (what the messages carry):
// - Ids: robot id = landmark_id = the dataset's SUBJECT number (Barcodes.dat maps
//   subject -> barcode). Subjects 1-5 are the robots, 6-20 the static landmarks.
// - Time: frame k is taken at t_k = T0 + start_s + k / rate_hz, where T0 (the common
//   start) is the LATEST of the selected robots' first odometry time and first
//   ground-truth time. Frames run while t_k <= common end, the EARLIEST of the
//   selected robots' last odometry and last ground-truth times, and while
//   k / rate_hz < duration_s when duration_s > 0 (so 60 s at 10 Hz = 600 frames).
//   Robot1's ground truth ends about 128 s before its other files: selecting robot 1
//   shortens the run to ~758 s (from ~884 s without it).
//   utime = round(t_k * 1e6); every file time is held as exact integer microseconds
//   (the files have millisecond resolution), so binning is free of rounding ties.
// - Odometer (sensor_frame_t.odom_*): the odometry frame is the world (Vicon) frame.
//   The reading at frame 0 is the ground-truth pose at t_0; later readings are that
//   pose integrated with the commanded velocities. A command holds from its own time
//   to the next command's time (piecewise constant, also across gaps in the file; the
//   last command holds to the end) and is integrated exactly (a circular arc when
//   w != 0). theta in [-pi, pi).
// - Observations of frame k: the measurement lines with time in (t_{k-1}, t_k]
//   (frame 0: (t_0 - 1/rate_hz, t_0]). Barcode -> subject via Barcodes.dat. Dropped
//   and counted as misreads: a barcode not in Barcodes.dat, the robot's own barcode,
//   a non-positive range. Another robot's barcode is counted in robot_barcodes and
//   kept (landmark_id = that robot's subject) only with with_robot_barcodes, also
//   when that robot is not selected (it then has no ground-truth entry, see below).
//   The same subject twice in one frame: the later line is kept (at its place in
//   time order), the earlier is counted as a duplicate. Bearing wrapped to [-pi, pi).
//   At most 19 distinct subjects can be seen, below the 64 of sensor_frame_t.
//   dataset6 has no duplicate at 10 Hz (a subject is seen at most every ~0.2 s);
//   at 2 Hz about 20 % of the lines are duplicates.
// - Ground truth of frame k: each selected robot's Vicon pose linearly interpolated
//   at t_k (heading along the short way); the landmarks of Landmark_Groundtruth.dat
//   (id = subject, moving = false); with with_robot_barcodes also every SELECTED
//   robot's position as a landmark (id = its subject, moving = true). Only selected
//   robots are loaded, so the robots that are not selected appear nowhere in it.
// - Odometry noise fields (odom_var_*) are copied from Options into every frame.
//
// File parsing (Dataset::load): whitespace-separated columns; blank lines and lines
// whose first non-blank character is '#' are skipped. A wrong column count, a value
// that is not a number or not finite, a non-integer subject/barcode, or a time that
// goes backwards (odometry, ground truth and measurements alike: in dataset6 all
// three are non-decreasing, so nothing is sorted) throws DatasetError
// "PATH:LINE: what is wrong"; a missing file throws "PATH: cannot open ...".
#pragma once

#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include <elaslam/ground_truth_t.hpp>
#include <elaslam/sensor_frame_t.hpp>

#include "elaslam/common/config.hpp"
#include "elaslam/common/geometry.hpp"

namespace elaslam::mrclam {

/// A problem in the dataset files: "FILE:LINE: what is wrong" (or "FILE: ...").
struct DatasetError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Runs `step` of a dataset program and returns its exit code; when it throws, "program:
/// message" on stderr and the code the error earns: cli::kExitFailure for a
/// DatasetError (the data), cli::kExitBadInput for std::invalid_argument (a value the
/// user gave). Anything else propagates (to cli::guarded_main).
int run_step(const char* program, const std::function<int()>& step);

constexpr int kMaxRobotSubject = 5;    // subjects 1..5 are the robots
constexpr int kFirstLandmarkSubject = 6;  // subjects 6..20 the static landmarks

/// The ranges of the dataset keys that command lines override too (mrclam_import,
/// run_dataset, mrclam_stats --rate): the config reader checks the same bounds.
namespace limits {
inline constexpr double kRateMinHz = 0.1, kRateMaxHz = 1000.0;  // rate_hz
inline constexpr double kStartMaxS = 1e5;                       // start_s (from 0)
inline constexpr double kDurationMaxS = 1e5;                    // duration_s (from 0; 0: to the end)
}  // namespace limits

/// The `dataset:` section of config/mrclam.yaml (every key required).
struct Options {
  double rate_hz = 10.0;                 // [frames/s]
  std::vector<int> robots{1, 2, 3, 4, 5};  // YAML: a string "1,2,3,4,5" (subjects 1..5)
  bool with_robot_barcodes = false;      // keep other robots' barcodes as (moving) landmarks
  double start_s = 0.0;                  // [s] offset of frame 0 from the common start time T0
  double duration_s = 0.0;               // [s] 0: to the common end
  // Odometry noise written into every frame (sensor_frame_t's model). Defaults:
  // measured on dataset6 with mrclam_stats (see config/mrclam.yaml for the numbers).
  double odom_var_trans_per_m = 0.0085;  // [m^2/m]
  double odom_var_rot_per_rad = 0.0094;  // [rad^2/rad]
  double odom_var_rot_per_m = 0.0079;    // [rad^2/m]
  // Motion compensation: a measurement taken at t_m < t_k is re-expressed in the
  // robot frame at the frame's time t_k through the odometry motion between the two
  // (the frame's odometer reading is at t_k; without this the robot's turn during
  // up to one frame period shows up as bearing error).
  bool motion_compensation = false;
  // The velocity commands lead the robot's motion (the data README: ~0.2 s): each
  // command is applied this much after its time stamp. [s], >= 0.
  double odometry_delay_s = 0.0;
  // Range calibration: the camera's range depends on where the barcode is in the
  // image; measured range = true range * (1 + k0 + k1 bearing^2), so each range is
  // divided by that factor (mrclam_stats fits k0, k1 against Vicon). 0, 0: off.
  double range_scale_k0 = 0.0;
  double range_scale_k1 = 0.0;
};

/// Read the `dataset:` section; problems are collected by the reader (ConfigError at
/// Document::finish), like robot_options.
void parse(config::Reader& r, Options* o);
/// Load the `dataset:` section of a config file; the other sections (robot, main,
/// scenario, lcm, team) are allowed. Throws config::ConfigError listing every problem.
Options load_options(const std::string& yaml_path, std::string* effective_yaml = nullptr);
/// "1,2,5" -> {1, 2, 5}: robot subjects 1..5, no repeats, at least one. On failure
/// returns false and says why in *why.
bool parse_robot_list(const std::string& text, std::vector<int>* out, std::string* why);

struct RobotStats {
  int id = 0;
  long measurements = 0;     // measurement lines read in the time window (t_0 - 1/rate, t_last]
  long used = 0;             // put into frames
  long misreads = 0;         // barcode not in Barcodes.dat, own barcode, or range <= 0: dropped
  long robot_barcodes = 0;   // observations of another robot's barcode (kept only with with_robot_barcodes)
  long duplicates = 0;       // same subject twice in one frame: the later one is kept, earlier dropped
  long odometry_gaps = 0;    // odometry intervals longer than 0.5 s that overlap [t_0, t_last]
  double max_odometry_gap_s = 0.0;  // [s] longest of those intervals
};
/// measurements = used + misreads + duplicates + (robot_barcodes when they are dropped).
struct Stats {
  std::vector<RobotStats> robots;  // robot_ids() order
  int frames = 0;
  double start_time = 0.0;  // [s, Unix] time of frame 0
  double end_time = 0.0;    // [s, Unix] time of the last frame
};

// ---- the parsed files ----------------------------------------------------------
struct PoseSample {  // one Vicon line
  std::int64_t utime;  // [us]
  Pose2 pose;          // world frame W
};
struct Command {  // one odometry line
  std::int64_t utime;  // [us]
  double v;            // [m/s] forward
  double w;            // [rad/s] counter-clockwise
};
struct Measurement {  // one measurement line
  std::int64_t utime;  // [us]
  int barcode;         // as in the file (NOT the subject)
  double range;        // [m]
  double bearing;      // [rad] robot frame, as in the file (not wrapped)
};
struct LandmarkTruth {
  int subject;
  double x, y;          // [m] world frame W
  double sigma_x, sigma_y;  // [m]
};
struct RobotSeries {
  int id = 0;  // subject number
  std::vector<Command> odometry;
  std::vector<PoseSample> ground_truth;
  std::vector<Measurement> measurements;
};

/// The parsed files of the selected robots (RobotN_Odometry, _Measurement,
/// _Groundtruth) and the shared Barcodes.dat and Landmark_Groundtruth.dat.
class Dataset {
 public:
  /// Throws DatasetError (a missing or malformed file, robot id not in 1..5).
  static Dataset load(const std::string& dir, const std::vector<int>& robots);

  const std::string& dir() const { return dir_; }
  /// Subject of a barcode, 0 when the barcode is not in Barcodes.dat (a misread).
  int subject_of_barcode(int barcode) const;
  /// Barcode of a subject, 0 when none.
  int barcode_of_subject(int subject) const;
  const std::vector<LandmarkTruth>& landmarks() const { return landmarks_; }
  /// Robots in the order given to load().
  const std::vector<RobotSeries>& robots() const { return robots_; }
  bool has_robot(int id) const;
  /// Throws std::out_of_range when the robot was not loaded.
  const RobotSeries& robot(int id) const;

 private:
  std::string dir_;
  std::vector<std::pair<int, int>> barcodes_;  // (subject, barcode), as in the file
  std::vector<LandmarkTruth> landmarks_;
  std::vector<RobotSeries> robots_;
};

// ---- motion helpers (also used by mrclam_stats) ----------------------------------
/// Pose after driving at v [m/s], w [rad/s] for dt [s] from p: exact (arc when w != 0).
Pose2 integrate(const Pose2& p, double v, double w, double dt);
/// Vicon pose at utime, linearly interpolated (heading the short way). False when
/// utime is outside the series. *hint (optional) is a search start index that makes
/// calls with increasing times O(1); it is updated.
bool interpolate(const std::vector<PoseSample>& gt, std::int64_t utime, Pose2* out, std::size_t* hint = nullptr);

/// Dead reckoning over one odometry series, from a start pose at a start time, for
/// non-decreasing query times. Commands hold until the next command's time.
class OdometryIntegrator {
 public:
  OdometryIntegrator(const std::vector<Command>& cmds, std::int64_t start_utime, const Pose2& start);
  /// Advance to utime (>= the last one) and return the pose (theta wrapped).
  Pose2 advance_to(std::int64_t utime);
  /// [m] distance driven so far (sum of |v| dt).
  double distance() const { return distance_; }

 private:
  const std::vector<Command>* cmds_;
  std::size_t next_ = 0;        // index of the first command later than now_
  std::int64_t now_;
  Pose2 pose_;
  double distance_ = 0.0;
};

// ---- frames --------------------------------------------------------------------
/// Frames at rate_hz from the common start time (see the conventions at the top).
/// Everything is computed in the constructor (odometer readings, ground-truth poses,
/// observation lists, stats; all of dataset6 takes well under 0.1 s once loaded, and
/// loading its 5 robots ~0.3 s); the Dataset is not kept (it may be destroyed).
class FrameSource {
 public:
  /// Throws std::invalid_argument naming the option: rate_hz not > 0, robots empty,
  /// repeated, more than 8 or not loaded in d, start_s or duration_s negative, noise
  /// variances negative, or start_s past the common end.
  FrameSource(const Dataset& d, const Options& o);

  int num_frames() const { return num_frames_; }
  double dt_s() const { return 1.0 / options_.rate_hz; }
  const std::vector<int>& robot_ids() const { return options_.robots; }
  /// Unix time of frame k [us].
  std::int64_t frame_utime(int k) const;
  /// Frame k: ground truth and one sensor frame per robot (robot_ids() order).
  /// O(robots + observations + landmarks): any order of k is cheap.
  void frame(int k, ground_truth_t* gt, std::vector<sensor_frame_t>* sensors) const;
  const Stats& stats() const { return stats_; }
  /// Common start time T0 [us] (before start_s is added) and common end [us].
  std::int64_t common_start_utime() const { return t0_utime_; }
  std::int64_t common_end_utime() const { return end_utime_; }
  /// Odometer reading and true pose of robot index i (robot_ids() order) at frame k.
  const Pose2& odometer(int i, int k) const;
  const Pose2& true_pose(int i, int k) const;

 private:
  struct Obs {
    int subject;
    double range, bearing;
  };
  struct PerRobot {
    std::vector<Pose2> odometer, truth;  // per frame
    std::vector<int> obs_begin;          // frame k: obs[obs_begin[k], obs_begin[k+1])
    std::vector<Obs> obs;
  };
  void compute_frame_times(const Dataset& d);
  void compute_robot(const Dataset& d, const RobotSeries& s, PerRobot* out, RobotStats* st);
  void count_odometry_gaps(const RobotSeries& s, RobotStats* st) const;
  void bin_observations(const Dataset& d, const RobotSeries& s, const std::vector<Command>& commands, PerRobot* out,
                        RobotStats* st) const;

  Options options_;
  std::int64_t t0_utime_ = 0, end_utime_ = 0;
  int num_frames_ = 0;
  std::vector<std::int64_t> frame_utimes_;
  std::vector<PerRobot> per_robot_;
  std::vector<LandmarkTruth> landmarks_;
  Stats stats_;
};

/// The odometer's systematic error against Vicon, in OdometryCalibration's convention (the
/// filter's odometry calibration, robot_node/models.hpp): the true increment of a
/// frame step of dt seconds is (s_v dx_r, s_v dy_r, s_w dtheta_r + b dt) for the
/// reported one, both in the robot frame at the step start. Fitted by least squares
/// over consecutive windows of `window` frame steps of robot index i from frame
/// `first` to `last` (-1: the last frame) of the frames as the filter gets them (the
/// source's odometer readings against its Vicon poses), each window's increments
/// taken as one step (dt = window / rate): s_v = sum(t . r) / sum(|r|^2) over the
/// translations; (s_w, b) from the headings; and s_w alone (b = 0). Windows of a
/// few seconds: the odometer's timing against Vicon is known to about 0.02 s
/// (odometry_delay_s), and over one 0.1 s step that misalignment is as large as the
/// turn itself and pulls the fitted scales towards 0 (errors in the regressor);
/// over 5 s it is a few per cent of it.
struct OdometryFit {
  int steps = 0;  // windows fitted
  double speed_scale = 1.0;             // s_v: true distance / reported
  double turn_scale = 1.0;              // s_w, fitted with the bias
  double turn_bias_rad_s = 0.0;         // b [rad/s]
  double turn_scale_without_bias = 1.0; // s_w, fitted alone
  double reported_m = 0.0, reported_rad = 0.0;  // sum of |reported| translation [m] and turn [rad]
};
OdometryFit fit_odometry(const FrameSource& src, int i, int first = 0, int last = -1, int window = 1);

}  // namespace elaslam::mrclam

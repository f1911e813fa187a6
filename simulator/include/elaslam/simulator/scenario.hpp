// SPDX-License-Identifier: Apache-2.0
// The simulated experiment of the paper (section 4, docs/design.md section 6): world,
// landmark layout, moving landmarks, robots on semicircular paths, sensor and
// odometry noise. SI units inside; angles in radians unless the name says _deg.
// config/paper.yaml documents every key and the reasoning behind the values.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "elaslam/common/config.hpp"
#include "elaslam/common/contract.hpp"

namespace elaslam::sim {

/// Axis-aligned world rectangle, world frame W [m].
struct WorldBounds {
  double x_min_m = -10.0;
  double x_max_m = 10.0;
  double y_min_m = -10.0;
  double y_max_m = 10.0;
};

/// Range-bearing sensor with a circular field of view of diameter D around the
/// robot centre (paper Fig. 1), full 360 degrees.
struct SensorOptions {
  double fov_diameter_m = 8.0;          // D [m]; landmarks within D/2 are observable
  double min_range_m = 0.1;             // [m] closer landmarks are not reported (bearing ill-defined)
  double range_sigma_m = 0.05;          // [m] standard deviation of the range noise
  double bearing_sigma_deg = 1.0;       // [deg] standard deviation of the bearing noise
  double detection_probability = 1.0;   // probability that a landmark in view is reported

  /// Observations a frame carries at most (the nearest are kept; the rest counted).
  int max_observations = contract::kMaxObsPerFrame;
  double max_range_m() const { return 0.5 * fov_diameter_m; }
};

/// Odometry noise, same meaning as the fields of sensor_frame_t.
struct OdometryOptions {
  double var_trans_per_m = 4e-4;   // [m^2/m] along and across the motion
  double var_rot_per_rad = 1e-3;   // [rad^2/rad]
  double var_rot_per_m = 3e-4;     // [rad^2/m]
};

/// A robot odometer's systematic error, the convention the filter estimates too
/// (docs/simulator.md "Odometer"): over one frame of dt [s], with the reported
/// increment (dx_r, dy_r, dtheta_r) in the body frame B at the step's start, the
/// true increment is
///   dx = speed_scale * dx_r,  dy = speed_scale * dy_r,
///   dtheta = turn_scale * dtheta_r + turn_bias_rad_s * dt.
/// On MRCLAM the true turn is 0.87-0.95 of the reported one (docs/mrclam.md). The
/// defaults are no error. sensor_frame_t says nothing of it: the noise model it
/// carries stays the configured one.
struct OdometerError {
  double turn_scale = 1.0;        // s_w: true turn / reported turn
  double speed_scale = 1.0;       // s_v: true translation / reported translation
  double turn_bias_rad_s = 0.0;   // b [rad/s]: true turn rate the odometer does not report
  bool none() const { return turn_scale == 1.0 && speed_scale == 1.0 && turn_bias_rad_s == 0.0; }
};

/// An axis-aligned rectangle of the world W [m] with no landmark in it: the layout
/// leaves out the landmarks it would place inside, and moving landmarks bounce
/// off its sides as off the world's border. A robot farther than D/2 inside it
/// sees nothing (docs/simulator.md "Landmark-free stretches").
struct EmptyRegion {
  bool enabled = false;           // off by default: no landmark is left out
  double x_min_m = 0.0;
  double x_max_m = 0.0;
  double y_min_m = 0.0;
  double y_max_m = 0.0;
  /// Strictly inside (a point on a side is outside: landmarks may sit there).
  bool contains(double x_m, double y_m) const {
    return enabled && x_m > x_min_m && x_m < x_max_m && y_m > y_min_m && y_m < y_max_m;
  }
};

enum class Layout { kGrid, kCloister, kRandom };

/// Initial landmark positions. Only the keys of the chosen layout are required.
struct LandmarkOptions {
  Layout layout = Layout::kGrid;
  int count = 72;
  // grid: landmarks at the centres of a columns x rows division of the world.
  int grid_columns = 9;
  int grid_rows = 8;
  // cloister: landmarks evenly spaced on `rings` concentric squares centred in the
  // world, half-widths from inner to outer (Sola's toolbox "cloister").
  int cloister_rings = 2;
  double cloister_inner_half_width_m = 5.0;
  double cloister_outer_half_width_m = 8.0;
  // random: uniform in the world, at least min_spacing_m apart (layout stream).
  double min_spacing_m = 1.0;
  // Any layout: the landmarks it places in here are left out (ids stay consecutive).
  EmptyRegion empty_region;
};

/// A turn in place on a robot's path: at start_s the robot stops, turns by
/// turn_deg at a constant rate for duration_s, then drives on at the same speed
/// and curvature, so the rest of its path is the rest of the semicircle rotated
/// by turn_deg about the point where it turned (motion.hpp, path_pose).
struct SpinOptions {
  double start_s = 0.0;           // [s] after the run's start
  double duration_s = 0.0;        // [s]; 0: no spin (the default)
  double turn_deg = 0.0;          // [deg] counter-clockwise positive
};

/// One robot: a semicircle (180 degrees of arc) driven at constant speed (it stops
/// at the end of the semicircle if it gets there before the run ends), optionally
/// with a turn in place on the way, and its odometer's systematic error.
struct RobotPathOptions {
  int id = 1;                     // 1..contract::kMaxRobots
  double center_x_m = 0.0;        // circle centre, world frame W [m]
  double center_y_m = 0.0;
  double radius_m = 6.0;          // [m]
  double start_angle_deg = 0.0;   // [deg] polar angle of the start point about the centre
  bool ccw = true;                // direction of travel along the circle
  double speed_mps = 1.0;         // [m/s] along the path
  SpinOptions spin;               // scenario.robots[i].spin (none by default)
  OdometerError odometer;         // scenario.odometry's, or scenario.robots[i].odometry's
};

/// How a landmark moves (docs/simulator.md "Mover kinds"). kStatic is a landmark
/// outside the moving set (World::kind); the moving ones take the other three.
enum class MotionKind {
  kStatic,
  kOscillating,        // along its direction, turning round every reversal_period_frames (the paper's)
  kConstantVelocity,   // along its direction, never turned round: it crosses the world
  kStopAndGo,          // as kConstantVelocity for move_s, standing still for stop_s, repeating
};

/// A stop-and-go mover's stretches. Each is a whole number of frames,
/// round(duration x rate_hz), at least one; each mover starts at its own random
/// point of the cycle (stream::kMoverPhase).
struct StopAndGoOptions {
  double move_s = 3.0;   // [s] moving (bouncing off borders as a constant-velocity mover)
  double stop_s = 3.0;   // [s] standing still
};

/// The kinds the moving landmarks take: the j-th moving landmark in ascending id
/// order takes kinds[j % kinds.size()], so a list mixes them in its proportions.
struct MoverOptions {
  std::vector<MotionKind> kinds{MotionKind::kOscillating};  // the paper's movers alone
  StopAndGoOptions stop_and_go;                              // used when kinds lists kStopAndGo
  bool uses(MotionKind k) const;
};

struct ScenarioOptions {
  WorldBounds world;
  int frames = 150;                 // frames per run, 0..frames-1
  double rate_hz = 10.0;            // F [frames/s]
  int seed = 1;                     // master seed of every random stream
  SensorOptions sensor;
  OdometryOptions odometry;
  LandmarkOptions landmarks;
  double dynamism_percent = 0.0;    // share of the landmarks that move [%]
  double landmark_speed_mps = 0.1;  // [m/s] speed of the moving landmarks
  int reversal_period_frames = 20;  // oscillating movers turn around every this many frames
  MoverOptions movers;              // how the moving landmarks move (scenario.movers)
  std::vector<RobotPathOptions> robots;

  double dt_s() const { return 1.0 / rate_hz; }
  /// round(dynamism x N): the number of moving landmarks among the N the world has
  /// (landmarks.count, less those the empty region leaves out: generate_layout).
  int moving_count(int num_landmarks) const;
  /// A stop-and-go mover's stretches in frames: round(move_s x rate_hz) and
  /// round(stop_s x rate_hz) (check_scenario keeps each in [1, limits::kFramesMax]).
  int stop_and_go_move_frames() const;
  int stop_and_go_stop_frames() const;
};

/// The ranges of the scenario keys that command lines override too (simulator,
/// scenario_dump, run_scenario, sweep, evaluate, apply_overrides): the config
/// reader checks the same bounds, so an override is refused where the key would be.
namespace limits {
inline constexpr double kRateMinHz = 1e-3, kRateMaxHz = 100000.0;           // rate_hz
inline constexpr int kFramesMax = 100000000;                                 // frames (from 1)
inline constexpr int kSeedMax = 2147483647;                                  // seed (from 0)
inline constexpr double kDynamismMaxPercent = 100.0;                         // dynamism_percent (from 0)
inline constexpr double kLandmarkSpeedMaxMps = 1000.0;                       // landmark_speed_mps (from 0)
inline constexpr std::size_t kMaxMoverKinds = 64;                            // movers.kinds (from 1 item)
}  // namespace limits

/// One problem found by check_scenario: key path relative to the scenario section.
struct Problem {
  std::string key;
  std::string what;
};

/// Read the `scenario` section's keys (ranges checked), then run check_scenario.
void parse(config::Reader& r, ScenarioOptions* o);

/// Cross-field checks (also the ones a command-line override can break): world
/// non-empty, robot motion per frame below D (paper eq 14 and after), robot paths
/// inside the world, unique robot ids, landmark speed per frame below D, mover kinds
/// listed and stop-and-go stretches of at least a frame, layout feasible and inside
/// the world, capacities of the message contract.
std::vector<Problem> check_scenario(const ScenarioOptions& o);

/// Load the `scenario` section of a YAML file; the sections of the other
/// components (robot, main, lcm, team) are allowed and left alone.
/// Throws config::ConfigError listing every problem with its key path.
/// `effective_yaml`, when given, receives the scenario section as read (YAML).
ScenarioOptions load_scenario(const std::string& path, std::string* effective_yaml = nullptr);
/// The same from YAML text (tests). `source` names the text in errors.
ScenarioOptions load_scenario_text(const std::string& text, const std::string& source = "<string>");

/// A few lines describing the effective scenario, for start-up logs.
std::string describe(const ScenarioOptions& o);

const char* layout_name(Layout l);
/// The configuration's spelling of a kind: static, oscillating, constant_velocity, stop_and_go.
const char* motion_kind_name(MotionKind k);

}  // namespace elaslam::sim

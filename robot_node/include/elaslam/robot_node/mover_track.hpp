// SPDX-License-Identifier: Apache-2.0
// One moving landmark's track: its position and velocity in W, estimated by an
// interacting multiple model (IMM) filter over three motion models, from the robot's
// range-bearing sightings of it. The robot's pose is a consider parameter: its
// covariance widens every sighting's innovation, the track never corrects the pose
// (docs/tracking.md).
//
// State x = (p_x, p_y, v_x, v_y) in W [m, m/s], the same in every model, so that the
// models mix (Blom and Bar-Shalom 1988; Bar-Shalom, Li, Kirubarajan, "Estimation with
// Applications to Tracking and Navigation", 2001, section 11.6.6). The models:
//   static             p' = p, v' = 0 (a landmark at rest; a slow random walk of p)
//   bounded            a damped spring about an anchor a: dp = v dt,
//                      dv = (-w^2 (p - a) - 2 zeta w v) dt + white acceleration
//                      (a second-order Gauss-Markov offset: a parked object that
//                      shifts, a door that swings, a mover that turns back)
//   constant_velocity  dp = v dt, dv = white acceleration (a walking person, a robot)
// The bounded model's white acceleration is set by its stationary offset: the
// position offset of the spring driven by it has standard deviation bounded_sigma_m.
// The anchor is where the track started (the landmark's last static position), and
// moves to the static model's estimate whenever the static model holds most of the
// probability: an object that came to rest anchors its next excursion there.
//
// Fixed size: every matrix is a fixed-size Eigen type; nothing allocates.
#pragma once

#include <array>
#include <cstdint>

#include <Eigen/Core>

#include "elaslam/common/geometry.hpp"
#include "elaslam/common/track_motion.hpp"
#include "elaslam/robot_node/models.hpp"

namespace elaslam {

enum class MotionModel : std::uint8_t { kStatic = 0, kBounded = 1, kConstantVelocity = 2 };
inline constexpr int kMotionModels = 3;
const char* motion_model_name(MotionModel m);

using TrackVector = Eigen::Matrix<double, 4, 1>;
using TrackMatrix = Eigen::Matrix<double, 4, 4>;

/// The track filter's parameters. None is fitted to a speed or a recording: each
/// is a physical scale of the motion it models (docs/tracking.md says why each
/// default).
struct MoverTrackOptions {
  /// Mean time a landmark keeps one motion model [s]: the IMM's switching matrix
  /// has pi_jj = exp(-dt / model_sojourn_s), the rest shared equally.
  double model_sojourn_s = 4.0;
  /// Static: random walk of the position [m / sqrt(s)] (a resting object nudged).
  double static_walk_m_per_sqrt_s = 0.002;
  /// Bounded: the stationary standard deviation of the offset from the anchor [m],
  /// the spring's natural angular frequency [rad/s] and its damping ratio [-].
  double bounded_sigma_m = 0.3;
  double bounded_omega_rad_s = 1.0;
  double bounded_damping = 0.7;
  /// Constant velocity: standard deviation of the white acceleration's spectral
  /// density [m / s^1.5]: the velocity's random walk per sqrt(s).
  double cv_accel_sigma = kDefaultCvAccelSigma;
  /// A new track's velocity: zero with this standard deviation per axis [m/s].
  double initial_speed_sigma_mps = 0.5;
  /// A new track's model probabilities (static, bounded, constant velocity): it
  /// starts because the landmark was found not static (normalised on use).
  std::array<double, kMotionModels> initial_probabilities{0.1, 0.45, 0.45};
  /// Longest prediction step [s]: a longer interval is integrated in equal steps no
  /// longer than this (the spring's discretisation stays accurate).
  double max_step_s = 0.1;
  /// A sighting whose innovation fits no model (d2 above the chi-square quantile of
  /// this probability, 2 dof, in every model) restarts the track at the sighting.
  double restart_probability = 0.999999;
  /// Validation: the sum of the last validation_sightings innovations' d2 (2 dof
  /// each) at most the chi-square quantile of validation_probability (a model
  /// whose noise is too large is conservative, not wrong: no lower bound).
  int validation_sightings = 10;
  double validation_probability = 0.95;
  /// The track's own noise scale, from its innovations: each sighting's noise (the
  /// pose's included) is multiplied by lambda = mean NIS / 2 of the unscaled
  /// innovations, averaged with weight 1 / noise_memory_sightings, held within
  /// [1, max_noise_scale]. A consistent track keeps lambda near 1; one whose
  /// sightings are noisier than stated (a pose error correlated over frames, a
  /// detector's offset) widens its own noise. Off: lambda 1.
  bool adapt_noise = true;
  double noise_memory_sightings = 10.0;
  double max_noise_scale = 100.0;
};

/// One range-bearing sighting of the tracked landmark and what it was taken from.
struct TrackSighting {
  RangeBearing z;                       // measured range [m], bearing [rad]
  Eigen::Matrix2d R = Eigen::Matrix2d::Zero();  // its noise covariance
  Pose2 pose;                           // the robot's estimated pose R_WB
  Eigen::Matrix3d pose_cov = Eigen::Matrix3d::Zero();  // its covariance (consider)
};

/// What one sighting did to the track.
struct TrackUpdate {
  double d2 = 0.0;          // combined innovation's nu' S^-1 nu (2 dof)
  bool outlier = false;     // no model explained it: held back, the track unchanged
  bool restarted = false;   // the second such sighting in a row, agreeing with the first: the track started again from them
};

class MoverTrack {
 public:
  static constexpr int kMaxValidationSightings = 64;

  /// Inactive until start(). Throws std::invalid_argument naming a bad option.
  explicit MoverTrack(const MoverTrackOptions& options = {});

  /// Starts at position p with covariance P (velocity zero, initial_speed_sigma_mps),
  /// anchored at `anchor`, at time t [s].
  void start(const Eigen::Vector2d& p, const Eigen::Matrix2d& P, const Eigen::Vector2d& anchor, double t);
  /// Starts at a sighting (its world position and covariance, pose included).
  void start(const TrackSighting& s, const Eigen::Vector2d& anchor, double t);

  /// Mixes the models and predicts each to time t [s]; t before the track's time is
  /// ignored (0 s). Several sightings at one time: predict once, update each.
  void predict(double t);
  /// Corrects every model with the sighting and updates the model probabilities. A
  /// sighting no model explains (d2 above the chi-square quantile of
  /// restart_probability in every model) is held back; a second in a row that
  /// agrees with it restarts the track from the two.
  TrackUpdate update(const TrackSighting& s);

  bool active() const { return active_; }
  void stop() { active_ = false; }
  double time() const { return t_; }
  /// The combined (moment-matched) estimate.
  TrackVector mean() const;
  TrackMatrix covariance() const;
  const std::array<double, kMotionModels>& probabilities() const { return mu_; }
  const TrackVector& model_mean(MotionModel m) const { return x_[index(m)]; }
  const TrackMatrix& model_covariance(MotionModel m) const { return P_[index(m)]; }
  MotionModel likeliest() const;
  /// At rest: the static model holds at least half of the probability.
  bool stopped() const { return mu_[0] >= 0.5; }
  const Eigen::Vector2d& anchor() const { return anchor_; }
  /// The last validation_sightings innovations are consistent (chi-square band).
  bool validated() const;
  /// Sightings taken since the track (re)started, the one it started at included.
  std::int64_t sightings() const { return sightings_; }
  std::int64_t restarts() const { return restarts_; }
  /// The noise scale lambda now (MoverTrackOptions::adapt_noise).
  double noise_scale() const { return noise_scale_; }
  /// Sightings no model explained (TrackUpdate::outlier).
  std::int64_t outliers() const { return outliers_; }
  /// A second sighting has fitted the track since it (re)started: a single
  /// sighting (a misread, a wrong association) is not a track yet.
  static constexpr std::int64_t kConfirmingSightings = 2;
  bool confirmed() const { return sightings_ >= kConfirmingSightings; }

  /// The model's transition over dt [s] (dt <= max_step_s): x' = F x + c, noise Q.
  /// Public for the tests (the discretisation against the continuous model).
  void transition(MotionModel m, double dt, TrackMatrix* F, TrackVector* c, TrackMatrix* Q) const;
  /// The IMM's switching matrix over dt: pi(i, j) = P(model j after | model i before).
  Eigen::Matrix3d switching(double dt) const;

 private:
  static int index(MotionModel m) { return static_cast<int>(m); }
  void predict_model(int j, double dt);
  TrackUpdate unexplained(const TrackSighting& s, TrackUpdate out);

  MoverTrackOptions options_;
  double restart_d2_ = 0.0;
  double valid_d2_ = 0.0;    // the validation window's bound on the sum of d2
  double bounded_q_ = 0.0;  // the bounded model's acceleration spectral density [m^2/s^3]

  bool active_ = false;
  double t_ = 0.0;
  Eigen::Vector2d anchor_ = Eigen::Vector2d::Zero();
  std::array<TrackVector, kMotionModels> x_{};
  std::array<TrackMatrix, kMotionModels> P_{};
  std::array<double, kMotionModels> mu_{};
  std::array<double, kMaxValidationSightings> window_{};
  int window_count_ = 0, window_next_ = 0;
  std::int64_t sightings_ = 0, restarts_ = 0, outliers_ = 0;
  // The last sighting no model explained, held back (unexplained()): its world
  // position, covariance and time.
  // Each model's F and Q for the last step length predicted (predict_model).
  double step_cached_ = -1.0;
  std::array<TrackMatrix, kMotionModels> F_step_{}, Q_step_{};
  // The switching matrix for the last interval predicted over (predict).
  double switching_cached_ = -1.0;
  Eigen::Matrix3d switching_step_ = Eigen::Matrix3d::Identity();
  double mean_nis_ = 2.0;     // running mean of the unscaled combined innovations' d2
  double noise_scale_ = 1.0;  // lambda
  bool pending_ = false;
  Eigen::Vector2d pending_p_ = Eigen::Vector2d::Zero();
  Eigen::Matrix2d pending_P_ = Eigen::Matrix2d::Zero();
  double pending_t_ = 0.0;
};

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// Fixed-memory planar EKF-SLAM (docs/design.md section 3). Paper equations held here:
// the state X = [R; M] (eqs 1-2, here with the odometer's calibration states), prediction (eqs 3-6, with the models of
// models.hpp), correction (eqs 7-13), augmentation by the inverse observation
// (eq 15) and the uncertainty mean(diag(P)) (eq 19). Not here: eq 14 (landmark
// speed, the simulator), eq 16 (the ELA, ela_gate), eqs 17-18 (team/'s metrics).
//
// State X = [R; C; M]: R = (x, y, theta) of the robot in W, C = (s_w, s_v, b) the
// odometer's calibration (turn scale, speed scale, turn-rate bias; models.hpp,
// OdometryCalibration), M = landmark positions in W, one 2-vector per
// occupied slot. R and C are the vehicle block V. With the calibration frozen
// (CalibrationOptions all zero, the default) C holds the prior's constants and its
// rows of P stay zero: the filter is then the paper's on X = [R; M], bit for bit.
// Mean, covariance and the id-to-slot tables are allocated once, at construction,
// from the configured capacity; predict, update, add_landmark and remove_landmark
// allocate nothing (tests/robot_node/test_ekf_no_alloc.cpp).
// Only this class changes the mean and covariance. Every operation returns a
// status; none throws or exits on bad data.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "elaslam/common/geometry.hpp"
#include "elaslam/robot_node/models.hpp"

namespace elaslam {

/// Named state layout: no bare indices into X or P outside these.
struct StateLayout {
  static constexpr int kPoseDim = 3;         // x, y, theta
  static constexpr int kCalibrationDim = 3;  // s_w, s_v, b (OdometryCalibration)
  static constexpr int kVehicleDim = kPoseDim + kCalibrationDim;
  static constexpr int kLandmarkDim = 2;     // x, y
  static constexpr int kX = 0, kY = 1, kTheta = 2;
  static constexpr int kTurnScale = 3, kSpeedScale = 4, kTurnBias = 5;
  static constexpr int kCalibration = kTurnScale;  // first calibration state
  /// Offset in X and P of the landmark stored in `slot`.
  static constexpr int landmark_offset(int slot) { return kVehicleDim + kLandmarkDim * slot; }
  static constexpr int dim(int num_landmarks) { return kVehicleDim + kLandmarkDim * num_landmarks; }
};

/// The odometer's calibration states C: their prior and random walk.
/// All sigmas and walks zero (the default): frozen at the prior's means, which the
/// prediction applies as known constants (1, 1, 0: the odometer as reported).
struct CalibrationOptions {
  OdometryCalibration prior;       // prior means
  double turn_scale_sigma = 0.0;   // prior std dev of s_w
  double speed_scale_sigma = 0.0;  // prior std dev of s_v
  double turn_bias_sigma = 0.0;    // [rad/s] prior std dev of b
  // Random walk: the std dev a state gains over one second (variance grows with
  // the time a prediction spans, its dt).
  double turn_scale_walk = 0.0;    // [1/sqrt(s)]
  double speed_scale_walk = 0.0;   // [1/sqrt(s)]
  double turn_bias_walk = 0.0;     // [rad/s/sqrt(s)]
  bool estimated() const {
    return turn_scale_sigma > 0.0 || speed_scale_sigma > 0.0 || turn_bias_sigma > 0.0 || turn_scale_walk > 0.0 ||
           speed_scale_walk > 0.0 || turn_bias_walk > 0.0;
  }
};

struct EkfOptions {
  int capacity = 128;          // maximum landmarks held at once (slots)
  int max_landmark_id = 1024;  // ids accepted: 0 <= id < max_landmark_id
  double range_sigma = 0.1;    // [m]   std dev of range measurements
  double bearing_sigma = 0.01; // [rad] std dev of bearing measurements
  double gate_probability = 0.99;  // chi-square gate probability (mode "gated")
  /// Covariance step of update(): the symmetric form P - M M^T, M = P H^T L^-T
  /// (false: rank 2 per update, rank 2k per frame of k) or the Joseph form
  /// (true: rank 4 per update, twice the arithmetic). Every gain is the optimal one
  /// for P with the earlier steps in, so the two agree to rounding (tests
  /// EkfKnownAnswer, EkfBatch); docs/adr/0033-symmetric-covariance-form.md. update_landmark_only, whose gain
  /// is deliberately not optimal, always uses the Joseph form.
  bool joseph = false;
  CalibrationOptions calibration;  // the odometer's calibration states (frozen by default)
};

enum class EkfStatus : std::uint8_t {
  kOk = 0,
  kGated,              // innovation outside the chi-square gate: not applied
  kUnknownLandmark,    // id not in the filter
  kAlreadyMapped,      // add_landmark of an id already in the filter
  kFull,               // no free slot
  kBadInput,           // non-finite input, id out of range, range <= 0
  kSingular,           // innovation covariance not positive definite
  kCovarianceFault,    // result would be non-finite or have a negative diagonal: refused
};
const char* to_string(EkfStatus s);

/// The numbers behind one update (or gate check): kept for every observation.
struct UpdateReport {
  EkfStatus status = EkfStatus::kOk;
  double d2 = 0.0;         // innovation Mahalanobis distance squared, z^T Z^-1 z
  double threshold = 0.0;  // chi-square quantile used (0 when no gate was applied)
  Eigen::Vector2d innovation = Eigen::Vector2d::Zero();  // z = y - h(X), bearing wrapped
  Eigen::Vector2d whitened = Eigen::Vector2d::Zero();    // L^-1 z with Z = L L^T: d2 = |whitened|^2
};

class EkfSlam {
 public:
  using Layout = StateLayout;

  /// Allocates everything the filter will ever use. Throws std::invalid_argument
  /// on invalid options (start-up only; no other member throws).
  explicit EkfSlam(const EkfOptions& options);

  /// Forget every landmark and set the robot prior; the calibration states start
  /// at their prior (options.calibration), uncorrelated with the pose.
  void reset(const Pose2& pose, const Eigen::Matrix3d& pose_cov);

  /// Prediction (eqs 4-5) from the odometer's reported increment (in B at the step
  /// start), the covariance U of its error, and the time the step spans, dt [s].
  /// The robot moves by the calibrated increment u(c) (calibrated_increment, the
  /// current estimate of C); U is the reported increment's noise, so the motion's
  /// is F_u J_r U J_r^T F_u^T (J_r = du/du_r). With the calibration estimated the
  /// vehicle block V = [R; C] moves with F_V = [[F_x, F_c], [0, I]], F_c = F_u du/dc,
  /// and C gains its random walk over dt; the landmarks' cross terms become
  /// P_LR F_x^T + P_LC F_c^T (P_LC is unchanged). O(n): touches the vehicle block
  /// and the landmarks' cross terms with R only.
  EkfStatus predict(const Pose2& increment, const Eigen::Matrix3d& U, double dt = 0.0);

  /// Innovation and its Mahalanobis distance for landmark `id` without changing
  /// the filter (eqs 8-9). status kUnknownLandmark / kBadInput / kSingular on failure.
  UpdateReport check(int id, const RangeBearing& z) const;

  /// Correction with one observation (eqs 8-13), using the sparsity of H.
  /// With `gate` true, an innovation beyond the chi-square quantile of
  /// options.gate_probability is refused with kGated (filter unchanged).
  /// The mean is corrected at once; the covariance step is held with the other
  /// pending ones (up to kMaxBatch updates) and applied with them in one pass over
  /// P when anything next reads P or changes its shape. Each update's gain is
  /// computed against P with all the earlier steps in, so the result is that of
  /// sequential updates (up to rounding): a batch is invisible to callers.
  UpdateReport update(int id, const RangeBearing& z, bool gate = false);

  /// Correction of landmark `id` alone (a Schmidt-Kalman "consider" update): the
  /// gain is the optimal one for the landmark's two rows and zero for every other
  /// state, so the robot and the other landmarks keep their means and their
  /// covariance block, while the landmark's mean, covariance and cross-covariances
  /// are corrected: P_l. <- P_l. - K_l (H P), P_ll <- P_ll - K_l Z K_l^T. It is the
  /// Joseph form with that gain, so P stays consistent (never more confident than
  /// the measurements justify). Used for candidates that must not yet steer the
  /// robot. O(n).
  UpdateReport update_landmark_only(int id, const RangeBearing& z);

  /// Correction with a direct measurement of landmark `id`'s position: z = l + v,
  /// v ~ N(0, R) (H selects the landmark; the team map's information, team_aid.hpp).
  /// R must be symmetric positive definite. d2 = (z - l)^T (P_ll + R)^-1 (z - l).
  /// Same gain, health check and Joseph / standard covariance step as update(),
  /// batched like it.
  UpdateReport update_position(int id, const Eigen::Vector2d& z, const Eigen::Matrix2d& R);
  /// The same measurement's innovation and d2 without changing the filter.
  UpdateReport check_position(int id, const Eigen::Vector2d& z, const Eigen::Matrix2d& R) const;

  /// Prediction of landmark `id` alone, for a mover the filter follows
  /// (docs/tracking.md "Followed movers"): l <- l + delta, P_ll <- P_ll
  /// + Q, its cross-covariances unchanged (the motion is independent of the rest
  /// of the state). Q symmetric positive semi-definite; kBadInput otherwise, filter
  /// unchanged. O(1) after the pending steps.
  EkfStatus move_landmark(int id, const Eigen::Vector2d& delta, const Eigen::Matrix2d& Q);

  /// Add landmark `id` by inverse observation (eq 15) with Jacobian augmentation.
  EkfStatus add_landmark(int id, const RangeBearing& z);

  /// Remove landmark `id` by marginalisation: the last slot moves into the hole. O(n).
  EkfStatus remove_landmark(int id);

  // ---- accessors --------------------------------------------------------------
  bool has_landmark(int id) const;
  int num_landmarks() const { return num_landmarks_; }
  int capacity() const { return options_.capacity; }
  int state_dim() const { return Layout::dim(num_landmarks_); }
  const EkfOptions& options() const { return options_; }
  /// Slot of a landmark id, or -1.
  int slot_of(int id) const;
  /// Landmark id stored at a slot (0 <= slot < num_landmarks()).
  int id_at(int slot) const { return slot_to_id_[static_cast<std::size_t>(slot)]; }

  Pose2 pose() const;
  Eigen::Matrix3d pose_cov() const;
  /// The calibration estimate (the prior's constants while frozen) and its
  /// covariance (columns s_w, s_v, b; zero while frozen).
  OdometryCalibration calibration() const;
  Eigen::Matrix3d calibration_cov() const;
  /// Whether the calibration states are estimated (options.calibration).
  bool calibration_estimated() const { return calibration_estimated_; }
  /// Landmark mean / covariance / cross-covariances. The id must be mapped.
  Eigen::Vector2d landmark(int id) const;
  Eigen::Matrix2d landmark_cov(int id) const;
  Eigen::Matrix2d landmark_cross_cov(int id_i, int id_j) const;  // P_ij = E[(l_i)(l_j)^T]
  Eigen::Matrix<double, 3, 2> pose_landmark_cov(int id) const;   // P_Rl

  /// The active part of the mean and covariance (views, no copies; valid until the
  /// next non-const call). The filter keeps only the lower triangle of P current
  /// (half the memory traffic per update); covariance() completes the upper one
  /// first when it is stale, O(n^2). The block accessors above never need that.
  /// Not thread-safe, not even for concurrent const calls.
  Eigen::Ref<const Eigen::VectorXd> mean() const { return x_.head(state_dim()); }
  Eigen::Ref<const Eigen::MatrixXd> covariance() const {
    settle();
    if (upper_stale_) complete_upper_triangle();
    return P_.topLeftCorner(state_dim(), state_dim());
  }
  /// mean(diag(P)) over the pose and the landmarks (paper eq 19): the calibration
  /// states are not the map's uncertainty and are left out.
  double mean_diag() const;
  /// Measurement noise covariance W = diag(range_sigma^2, bearing_sigma^2).
  const Eigen::Matrix2d& measurement_cov() const { return W_; }
  /// The chi-square threshold used by the gate (2 dof, options.gate_probability).
  double gate_threshold() const { return gate_threshold_; }

  /// Become a copy of `other` (same capacity and id range; kBadInput otherwise,
  /// filter unchanged): its mean, covariance and landmarks. O(n^2) in the active
  /// state of both, never the capacity's; allocates nothing (FilterHistory).
  EkfStatus assign(const EkfSlam& other);

  /// Move the whole state by the rigid motion p -> R(rotation) p + translation of
  /// the world frame: the robot's position and every landmark's carried, its
  /// heading turned by `rotation`, P <- A P A^T (A rotates each position block).
  /// Every range and bearing the filter predicts is unchanged (the motion is a
  /// change of gauge), and so is every relative uncertainty: it re-anchors a map
  /// that is right in itself but wrong as a whole (Robot::apply_team_map). O(n^2);
  /// allocates nothing. kBadInput (filter unchanged) for a non-finite motion.
  EkfStatus apply_rigid_motion(double rotation, const Eigen::Vector2d& translation);

  // ---- state file (robot_state.cpp) -------------------------------------------
  /// Replace the whole state by a saved one: mean x (dim(n)), covariance P (dim(n)
  /// square, symmetric; the caller has checked it), slot_ids[slot] = landmark id in
  /// slot order. kBadInput, filter unchanged, when sizes or ids are inconsistent.
  /// Start-up only (not the frame path).
  EkfStatus restore(const Eigen::VectorXd& x, const Eigen::MatrixXd& P, const std::vector<int>& slot_ids);

 /// Most updates whose covariance steps are applied in one pass.
  static constexpr int kMaxBatch = 16;

 private:
  using Matrix5 = Eigen::Matrix<double, 5, 5>;
  using Matrix25 = Eigen::Matrix<double, 2, 5>;
  /// Columns of fa_ one update uses: K, B (Joseph) or M (standard).
  int factor_cols() const { return options_.joseph ? 4 : 2; }
  static constexpr int kMaxFactorCols = 4 * kMaxBatch;
  bool valid_id(int id) const { return id >= 0 && id < options_.max_landmark_id; }
  /// check_position / update_position: input checks, the innovation and d2 into
  /// `report`, the Cholesky factor of Z = P_ll + R into L; false (status set) on failure.
  bool position_innovation(int id, const Eigen::Vector2d& z, const Eigen::Matrix2d& R, int* slot,
                           Eigen::Matrix2d* L, UpdateReport* report) const;
  /// Input checks shared by check() and update(): kBadInput / kUnknownLandmark.
  EkfStatus locate(int id, const RangeBearing& z, int* slot) const;
  /// The two columns of P of the landmark at offset `off`, into lm_cols_ (O(n)).
  void load_landmark_columns(Eigen::Index off) const;
  /// P's block on the robot and the landmark at `off`, pending steps included.
  Matrix5 block5(Eigen::Index off) const;
  /// P H^T into PHt_, pending steps included (O(n k), k pending columns).
  void compute_pht(Eigen::Index off, const Matrix25& H) const;
  /// The gain factors of one correction from PHt_ and the factor L of Z, into the
  /// next free columns of fa_, and the O(n) preview: would the correction leave X
  /// and P finite with diag(P) >= 0? (O(n).)
  bool compute_gain(const Eigen::Matrix2d& L, const Eigen::Vector2d& nu, const Eigen::Vector2d& w);
  /// The mean step now; the rank-2 (standard) or rank-4 (Joseph) covariance step
  /// joins the pending ones.
  void apply_correction(const Eigen::Vector2d& nu, const Eigen::Vector2d& w);
  /// Apply the pending covariance steps: P_ -= fa_ fb_^T (fb_ = fa_ for the
  /// standard form) on the lower triangle, one pass, O(n^2 k).
  void settle() const;
  /// Copy the lower triangle of the active block into the upper one (symmetrise).
  void complete_upper_triangle() const;

  EkfOptions options_;
  Eigen::Matrix2d W_;
  double gate_threshold_ = 0.0;
  int num_landmarks_ = 0;
  Eigen::VectorXd x_;          // capacity-sized mean
  // Capacity-sized covariance. Current: the lower triangle (i >= j) of the active
  // block, and the 3x3 robot block R in full (so columns 0..2 are complete; the
  // calibration rows of those columns, P_CR, are in the lower triangle). The
  // strict upper triangle is a cache, refreshed by covariance() when stale.
  mutable Eigen::MatrixXd P_;
  mutable bool upper_stale_ = false;
  std::vector<int> id_to_slot_;  // max_landmark_id entries, -1 when absent
  std::vector<int> slot_to_id_;  // capacity entries
  // Scratch allocated once, used by predict/update/add/remove.
  // Scratch (mutable: const readers use it too, e.g. check_position).
  mutable Eigen::MatrixXd PHt_;  // n x 2: P H^T
  // The pending covariance steps: P = P_ - fa_ fb_^T on the lower triangle, over
  // the first pending_cols_ columns; per update [K B] and [B K] (Joseph) or M in
  // fa_ alone (standard, fb_ unused). diag_: diag(P) while steps are pending.
  mutable Eigen::MatrixXd fa_, fb_;
  mutable int pending_cols_ = 0;
  Eigen::VectorXd diag_;
  mutable std::array<double, kMaxFactorCols> erow0_{}, erow1_{};  // H fb_^T, by rows
  Eigen::MatrixXd tmp_rows_;   // n x 3: the new P_LR in predict
  bool calibration_estimated_ = false;  // options_.calibration.estimated()
  Eigen::Vector3d calibration_walk_var_ = Eigen::Vector3d::Zero();  // per second: Q_c = diag(this) dt
  mutable Eigen::MatrixXd lm_cols_;  // n x 2: the observed landmark's two columns of P
};

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// The mover track's IMM (robot_node/mover_track.hpp): its motion models against the
// continuous models they discretise, the switching and mixing against hand-worked
// numbers, and tracks of simulated movers of each shape (at rest, constant velocity,
// stop-and-go, turning back) against their truth, with the consistency of the
// combined estimate over Monte Carlo runs.
#include "elaslam/robot_node/mover_track.hpp"

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/LU>
#include <gtest/gtest.h>

#include "elaslam/common/stats.hpp"

namespace elaslam {
namespace {

using Vec2 = Eigen::Vector2d;

constexpr double kDt = 0.1;                       // [s] 10 Hz, the paper's rate
constexpr double kRangeSigma = 0.05;              // [m]  config/paper.yaml's sensor
constexpr double kBearingSigma = kPi / 180.0;     // [rad] 1 degree

/// A robot standing near the origin whose pose estimate is off by a draw from its
/// covariance at every sighting; sightings with the sensor's noise.
struct Observer {
  explicit Observer(std::uint64_t seed) : rng(seed) {}
  std::mt19937_64 rng;
  std::normal_distribution<double> normal{0.0, 1.0};
  Pose2 truth{0.0, 0.0, 0.3};
  Eigen::Vector3d pose_sigma{0.02, 0.02, 0.005};
  double range_sigma = kRangeSigma;  // the sensor's true noise (the model's stays kRangeSigma)

  TrackSighting see(const Vec2& p) {
    TrackSighting s;
    s.pose = {truth.x + pose_sigma(0) * normal(rng), truth.y + pose_sigma(1) * normal(rng),
              truth.theta + pose_sigma(2) * normal(rng)};
    s.pose_cov = pose_sigma.cwiseAbs2().asDiagonal();
    const RangeBearing h = observe(truth, p);
    s.z = {h.range + range_sigma * normal(rng), wrap_angle(h.bearing + kBearingSigma * normal(rng))};
    s.R = Eigen::Vector2d(kRangeSigma * kRangeSigma, kBearingSigma * kBearingSigma).asDiagonal();
    return s;
  }
};

/// A mover's true path: position and velocity at time t.
struct Truth {
  Vec2 p;
  Vec2 v;
};

/// Runs a track over `frames` frames of `path`, started at its first sighting with the
/// true start as the anchor; `each(k, track, truth)` after every update.
template <class Path, class Each>
void run_track(MoverTrack* track, Observer* obs, const Path& path, int frames, const Each& each) {
  const Truth t0 = path(0.0);
  track->start(obs->see(t0.p), t0.p, 0.0);
  for (int k = 1; k < frames; ++k) {
    const double t = k * kDt;
    const Truth truth = path(t);
    track->predict(t);
    track->update(obs->see(truth.p));
    each(k, *track, truth);
  }
}

Truth constant_velocity(double t, const Vec2& p0, const Vec2& v) { return {p0 + v * t, v}; }

TEST(MoverTrack, OptionsOutOfRangeAreRefusedByName) {
  const auto refused = [](MoverTrackOptions o, const std::string& key) {
    try {
      MoverTrack track(o);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what()).find(key) != std::string::npos;
    }
    return false;
  };
  MoverTrackOptions o;
  o.model_sojourn_s = 0.0;
  EXPECT_TRUE(refused(o, "model_sojourn_s"));
  o = {};
  o.bounded_sigma_m = std::nan("");
  EXPECT_TRUE(refused(o, "bounded_sigma_m"));
  o = {};
  o.initial_probabilities = {0.0, 0.0, 0.0};
  EXPECT_TRUE(refused(o, "initial_probabilities"));
  o = {};
  o.validation_sightings = 65;
  EXPECT_TRUE(refused(o, "validation_sightings"));
  o = {};
  o.restart_probability = 1.0;
  EXPECT_TRUE(refused(o, "restart_probability"));
  EXPECT_NO_THROW(MoverTrack{MoverTrackOptions{}});
}

TEST(MoverTrack, SwitchingKeepsAModelForItsSojournTime) {
  MoverTrackOptions o;
  o.model_sojourn_s = 4.0;
  const MoverTrack track(o);
  const Eigen::Matrix3d pi = track.switching(1.0);
  EXPECT_NEAR(pi(0, 0), 0.778801, 1e-6);  // exp(-1/4)
  EXPECT_NEAR(pi(0, 1), 0.110600, 1e-6);  // (1 - exp(-1/4)) / 2
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(pi.row(i).sum(), 1.0, 1e-12);
}

TEST(MoverTrack, PredictionMixesTheModelProbabilities) {
  MoverTrackOptions o;
  o.model_sojourn_s = 4.0;
  o.initial_probabilities = {0.2, 0.3, 0.5};
  MoverTrack track(o);
  track.start(Vec2(1.0, 2.0), Eigen::Matrix2d::Identity() * 0.01, Vec2(1.0, 2.0), 0.0);
  track.predict(1.0);
  // c_j = sum_i pi_ij mu_i: 0.2 x 0.778801 + 0.8 x 0.110600, and so on.
  EXPECT_NEAR(track.probabilities()[0], 0.244240, 1e-6);
  EXPECT_NEAR(track.probabilities()[1], 0.311060, 1e-6);  // 0.3 x 0.778801 + 0.7 x 0.110600
  EXPECT_NEAR(track.probabilities()[2], 0.444700, 1e-6);  // 0.5 x 0.778801 + 0.5 x 0.110600
  // Every model started at rest at the anchor: each predicts it stays there.
  for (int j = 0; j < kMotionModels; ++j) {
    EXPECT_NEAR((track.model_mean(static_cast<MotionModel>(j)).head<2>() - Vec2(1.0, 2.0)).norm(), 0.0, 1e-12);
  }
}

TEST(MoverTrack, MixingMomentMatchesTheModelsBeforePrediction) {
  // Two models that disagree: after mixing, each model's mean is the mu_{i|j}-weighted
  // mean and its covariance holds the spread (IMM step 1), checked by hand on the
  // velocity of a track whose constant-velocity model alone has learnt a velocity.
  MoverTrackOptions o;
  o.model_sojourn_s = 1.0;
  MoverTrack track(o);
  Observer obs(7);
  obs.pose_sigma.setConstant(1e-6);
  const auto path = [](double t) { return constant_velocity(t, Vec2(3.0, 1.0), Vec2(0.5, 0.0)); };
  run_track(&track, &obs, path, 30, [](int, const MoverTrack&, const Truth&) {});
  const auto mu = track.probabilities();
  const std::array<TrackVector, 3> x{track.model_mean(MotionModel::kStatic), track.model_mean(MotionModel::kBounded),
                                     track.model_mean(MotionModel::kConstantVelocity)};
  const Eigen::Matrix3d pi = track.switching(kDt);
  MoverTrack mixed = track;
  mixed.predict(track.time() + kDt);
  // Predicting the static model zeroes its velocity, so check the constant-velocity
  // model: x0_cv = sum_i pi_i2 mu_i x_i / c_2, then F: v unchanged.
  double c2 = 0.0;
  Vec2 v0 = Vec2::Zero();
  for (int i = 0; i < 3; ++i) c2 += pi(i, 2) * mu[i];
  for (int i = 0; i < 3; ++i) v0 += pi(i, 2) * mu[i] / c2 * x[static_cast<std::size_t>(i)].tail<2>();
  EXPECT_NEAR((mixed.model_mean(MotionModel::kConstantVelocity).tail<2>() - v0).norm(), 0.0, 1e-12);
  EXPECT_NEAR(mixed.probabilities()[2], c2, 1e-12);
}

// Each model's prediction (done on 2 x 2 blocks, every model moving both axes
// alike) is its transition's F x + c and F P F' + Q, on models that hold different
// velocities and a position away from the bounded model's anchor. The switching
// matrix is the identity here (an endless sojourn), so mixing changes nothing.
TEST(MoverTrack, EachModelsPredictionIsItsTransition) {
  MoverTrackOptions o;
  o.model_sojourn_s = 1e300;
  MoverTrack track(o);
  Observer obs(11);
  const auto path = [](double t) { return constant_velocity(t, Vec2(3.0, 1.0), Vec2(0.4, -0.3)); };
  run_track(&track, &obs, path, 30, [](int, const MoverTrack&, const Truth&) {});
  ASSERT_GT((track.model_mean(MotionModel::kBounded).head<2>() - track.anchor()).norm(), 0.3);
  MoverTrack next = track;
  next.predict(track.time() + kDt);
  for (int j = 0; j < kMotionModels; ++j) {
    const auto m = static_cast<MotionModel>(j);
    TrackMatrix F, Q;
    TrackVector c;
    track.transition(m, kDt, &F, &c, &Q);
    const TrackVector x = F * track.model_mean(m) + c;
    const TrackMatrix P = F * track.model_covariance(m) * F.transpose() + Q;
    EXPECT_LT((next.model_mean(m) - x).norm(), 1e-12) << "model " << j;
    EXPECT_LT((next.model_covariance(m) - P).norm(), 1e-12 * P.norm()) << "model " << j;
  }
}

TEST(MoverTrack, BoundedModelIsTheDampedSpringItDiscretises) {
  MoverTrackOptions o;
  o.bounded_omega_rad_s = 1.0;
  o.bounded_damping = 0.7;
  o.bounded_sigma_m = 0.3;
  MoverTrack track(o);
  track.start(Vec2::Zero(), Eigen::Matrix2d::Identity(), Vec2::Zero(), 0.0);
  TrackMatrix F, Q;
  TrackVector c;
  track.transition(MotionModel::kBounded, kDt, &F, &c, &Q);
  // The free response from an offset of 1 m at rest, against the analytic one:
  // x(t) = e^{-zeta w t} (cos(w_d t) + zeta w / w_d sin(w_d t)), w_d = w sqrt(1 - zeta^2).
  TrackVector x = TrackVector::Zero();
  x(0) = 1.0;
  const double w = 1.0, z = 0.7, wd = w * std::sqrt(1.0 - z * z);
  for (int k = 1; k <= 50; ++k) {
    x = F * x + c;
    const double t = k * kDt;
    const double analytic = std::exp(-z * w * t) * (std::cos(wd * t) + z * w / wd * std::sin(wd * t));
    ASSERT_NEAR(x(0), analytic, 2e-3) << "t " << t;
    EXPECT_EQ(x(1), 0.0);  // the axes do not couple
  }
  // Driven by its noise, the offset's variance settles at bounded_sigma_m^2.
  TrackMatrix P = TrackMatrix::Zero();
  for (int k = 0; k < 2000; ++k) P = F * P * F.transpose() + Q;
  EXPECT_NEAR(std::sqrt(P(0, 0)), 0.3, 0.3 * 0.05);
  EXPECT_NEAR(std::sqrt(P(1, 1)), 0.3, 0.3 * 0.05);
}

TEST(MoverTrack, ConstantVelocityAndStaticTransitionsAreExact) {
  MoverTrackOptions o;
  o.cv_accel_sigma = 0.5;
  MoverTrack track(o);
  track.start(Vec2::Zero(), Eigen::Matrix2d::Identity(), Vec2::Zero(), 0.0);
  TrackMatrix F, Q;
  TrackVector c;
  const TrackVector x(1.0, 2.0, 0.5, -0.25);
  track.transition(MotionModel::kConstantVelocity, 0.1, &F, &c, &Q);
  EXPECT_NEAR(((F * x + c) - TrackVector(1.05, 1.975, 0.5, -0.25)).norm(), 0.0, 1e-15);
  // White acceleration of spectral density q = 0.25: Q = q [dt^3/3, dt^2/2; dt^2/2, dt].
  EXPECT_NEAR(Q(0, 0), 0.25 * 1e-3 / 3, 1e-15);
  EXPECT_NEAR(Q(0, 2), 0.25 * 1e-2 / 2, 1e-15);
  EXPECT_NEAR(Q(2, 2), 0.25 * 0.1, 1e-15);
  EXPECT_EQ(Q(0, 1), 0.0);
  track.transition(MotionModel::kStatic, 0.1, &F, &c, &Q);
  EXPECT_NEAR(((F * x + c) - TrackVector(1.0, 2.0, 0.0, 0.0)).norm(), 0.0, 1e-15);
}

TEST(MoverTrack, StartsAtTheSightingWithThePoseAndSensorCovariance) {
  MoverTrack track;
  Observer obs(3);
  const TrackSighting s = obs.see(Vec2(4.0, 1.0));
  track.start(s, Vec2(4.0, 1.0), 2.0);
  Eigen::Matrix<double, 2, 3> G_x;
  Eigen::Matrix2d G_z;
  const Vec2 p = inverse_observe(s.pose, s.z, &G_x, &G_z);
  EXPECT_NEAR((track.mean().head<2>() - p).norm(), 0.0, 1e-12);
  const Eigen::Matrix2d P = G_x * s.pose_cov * G_x.transpose() + G_z * s.R * G_z.transpose();
  EXPECT_NEAR((track.covariance().topLeftCorner<2, 2>() - P).norm(), 0.0, 1e-12);
  EXPECT_NEAR(track.covariance()(2, 2), 0.25, 1e-12);  // initial_speed_sigma_mps^2
  EXPECT_DOUBLE_EQ(track.time(), 2.0);
  EXPECT_TRUE(track.active());
}

TEST(MoverTrack, ALandmarkAtRestIsFoundStoppedWithoutVelocity) {
  // Over the last 5 s of 10 s, on five seeds: found stopped in most frames, with the
  // static model most of the probability and the estimate near the landmark at rest.
  const auto path = [](double) { return Truth{Vec2(3.0, 2.0), Vec2::Zero()}; };
  for (std::uint64_t seed : {11u, 12u, 13u, 14u, 15u}) {
    MoverTrack track;
    Observer obs(seed);
    int frames = 0, stopped = 0;
    double mu_static = 0.0, speed = 0.0, pos2 = 0.0;
    run_track(&track, &obs, path, 100, [&](int k, const MoverTrack& tr, const Truth& truth) {
      if (k < 50) return;
      ++frames;
      stopped += tr.stopped() ? 1 : 0;
      mu_static += tr.probabilities()[0];
      speed += tr.mean().tail<2>().norm();
      pos2 += (tr.mean().head<2>() - truth.p).squaredNorm();
    });
    EXPECT_GE(stopped, frames * 9 / 10) << "seed " << seed;
    EXPECT_GT(mu_static / frames, 0.75) << "seed " << seed;
    EXPECT_LT(speed / frames, 0.03) << "seed " << seed;
    EXPECT_LT(std::sqrt(pos2 / frames), 0.04) << "seed " << seed;
    EXPECT_EQ(track.restarts(), 0);
  }
}

TEST(MoverTrack, AConstantVelocityMoverIsTrackedWithItsVelocity) {
  // Movers that pass the robot 2 m abeam over 8 s, so that they stay in the sensor's
  // 4 m range: scored over the last 5 s. The sighting's noise (5 cm, 1 degree, the
  // pose's 2 cm and 0.3 degree drawn anew each frame) bounds the velocity at 10 Hz:
  // 0.05-0.12 m/s measured.
  for (const double speed : {0.1, 0.5, 1.0}) {
    MoverTrack track;
    Observer obs(100 + static_cast<std::uint64_t>(speed * 10));
    const Vec2 dir(0.6, 0.8);
    const auto path = [&](double t) { return constant_velocity(t - 4.0, Vec2(1.6, -1.2), speed * dir); };
    double pos2 = 0.0, vel2 = 0.0;
    int n = 0, moving = 0;
    run_track(&track, &obs, path, 80, [&](int k, const MoverTrack& tr, const Truth& truth) {
      if (k < 30) return;
      pos2 += (tr.mean().head<2>() - truth.p).squaredNorm();
      vel2 += (tr.mean().tail<2>() - truth.v).squaredNorm();
      moving += tr.stopped() ? 0 : 1;
      ++n;
    });
    EXPECT_LT(std::sqrt(pos2 / n), 0.05) << "speed " << speed;
    EXPECT_LT(std::sqrt(vel2 / n), 0.15) << "speed " << speed;
    EXPECT_GE(moving, n * 9 / 10) << "speed " << speed;
    EXPECT_EQ(track.likeliest(), MotionModel::kConstantVelocity) << "speed " << speed;
    EXPECT_EQ(track.restarts(), 0);
  }
}

/// Stop-and-go: 0.3 m/s for 5 s, standing for 5 s, again and again.
Truth stop_and_go(double t) {
  constexpr double kSpeed = 0.3, kLeg = 5.0;
  const int leg = static_cast<int>(t / kLeg);
  const double moved = kSpeed * (kLeg * ((leg + 1) / 2) + ((leg % 2 == 0) ? t - kLeg * leg : 0.0));
  const Vec2 dir(0.6, 0.8);
  return {Vec2(1.0, 1.0) + moved * dir, (leg % 2 == 0) ? Vec2(kSpeed * dir) : Vec2::Zero()};
}

TEST(MoverTrack, StopsAndStartsAreFoundWithinTwoSeconds) {
  ASSERT_NEAR((stop_and_go(5.0).p - stop_and_go(9.9).p).norm(), 0.0, 1e-12);  // the path stands
  ASSERT_NEAR((stop_and_go(12.0).p - stop_and_go(10.0).p).norm(), 0.6, 1e-12);
  for (std::uint64_t seed : {21u, 22u, 23u, 24u, 25u}) {
    MoverTrack track;
    Observer obs(seed);
    // First frame from each leg's start at which the track's verdict matches the leg.
    std::vector<double> latency;
    int leg = -1;
    bool found = false;
    run_track(&track, &obs, stop_and_go, 300, [&](int k, const MoverTrack& tr, const Truth& truth) {
      const double t = k * kDt;
      const int now = static_cast<int>(t / 5.0 + 1e-9);
      if (now != leg) {
        if (leg >= 1 && !found) latency.push_back(1e9);
        leg = now;
        found = false;
      }
      const bool standing = truth.v.norm() == 0.0;
      if (leg >= 1 && !found && tr.stopped() == standing) {
        latency.push_back(t - 5.0 * leg);
        found = true;
      }
    });
    ASSERT_GE(latency.size(), 4u);
    for (std::size_t i = 0; i < latency.size(); ++i) {
      EXPECT_LE(latency[i], 2.0) << "seed " << seed << ", leg " << i + 1 << (i % 2 == 0 ? " (stop)" : " (go)");
    }
  }
}

TEST(MoverTrack, AMoverThatTurnsBackIsFollowed) {
  // The simulator's oscillating mover: 0.3 m/s, turning back every 2 s.
  const auto path = [](double t) {
    const int leg = static_cast<int>(t / 2.0);
    const double s = (leg % 2 == 0) ? t - 2.0 * leg : 2.0 - (t - 2.0 * leg);
    const double sign = (leg % 2 == 0) ? 1.0 : -1.0;
    return Truth{Vec2(4.0, 0.0) + 0.3 * s * Vec2(0.0, 1.0), sign * 0.3 * Vec2(0.0, 1.0)};
  };
  MoverTrack track;
  Observer obs(31);
  double pos2 = 0.0;
  int n = 0;
  run_track(&track, &obs, path, 200, [&](int k, const MoverTrack& tr, const Truth& truth) {
    if (k < 20) return;
    pos2 += (tr.mean().head<2>() - truth.p).squaredNorm();
    ++n;
  });
  EXPECT_LT(std::sqrt(pos2 / n), 0.08);
  EXPECT_EQ(track.restarts(), 0);
}

TEST(MoverTrack, TheCombinedEstimateIsConsistentOverMonteCarloRuns) {
  // Movers whose velocity does a random walk of the constant-velocity model's own
  // spectral density: at 5 s the average NEES over (p, v) of 100 runs is below the
  // upper end of the 95 % band of chi-square with 400 dof / 100 (the track is not
  // overconfident). The mixture's covariance holds the other models' spread too, so
  // it is somewhat conservative (3.39 of 4 measured); the lower bound, 3, says no
  // more than that.
  const MoverTrackOptions o;
  constexpr int kRuns = 100;
  double nees = 0.0;
  for (int r = 0; r < kRuns; ++r) {
    std::mt19937_64 rng(5000 + static_cast<std::uint64_t>(r));
    std::normal_distribution<double> normal(0.0, 1.0);
    std::vector<Truth> truth(51);
    truth[0] = {Vec2(3.0, 1.0), Vec2::Zero()};
    const double q = o.cv_accel_sigma * o.cv_accel_sigma;
    for (std::size_t k = 1; k < truth.size(); ++k) {
      // Exact sampling of the integrated random walk over one step.
      const double a = normal(rng), b = normal(rng), c = normal(rng), d = normal(rng);
      const double sp = std::sqrt(q * kDt * kDt * kDt / 12), sv = std::sqrt(q * kDt);
      const Vec2 dv(sv * a, sv * b);
      truth[k].v = truth[k - 1].v + dv;
      truth[k].p = truth[k - 1].p + kDt * truth[k - 1].v + 0.5 * kDt * dv + sp * Vec2(c, d);
    }
    MoverTrack track(o);
    Observer obs(9000 + static_cast<std::uint64_t>(r));
    TrackVector err = TrackVector::Zero();
    run_track(&track, &obs, [&](double t) { return truth[static_cast<std::size_t>(std::lround(t / kDt))]; }, 51,
              [&](int k, const MoverTrack& tr, const Truth& t) {
                if (k != 50) return;
                err.head<2>() = tr.mean().head<2>() - t.p;
                err.tail<2>() = tr.mean().tail<2>() - t.v;
                nees += err.dot(tr.covariance().inverse() * err);
              });
  }
  const double mean_nees = nees / kRuns;
  EXPECT_GT(mean_nees, 3.0);
  EXPECT_LT(mean_nees, chi2_quantile(0.975, 4 * kRuns) / kRuns);
}

// A sensor 4 times noisier in range than its stated noise: the track's noise scale
// grows from its innovations until its estimate is consistent again, where the
// track with the stated noise stays overconfident; an honest sensor keeps the
// scale near 1. NEES of (p, v) at frame 150 over 60 Monte Carlo runs of a
// landmark at rest (measured: 11.8 without the scale, 2.2 with it at a scale of
// 4.1; the honest sensor 0.7 at 1.04).
TEST(MoverTrack, ItsNoiseScaleFromItsInnovationsMakesANoisierSensorConsistent) {
  const auto mean_nees = [](bool adapt, double range_sigma, double* mean_scale) {
    MoverTrackOptions o;
    o.adapt_noise = adapt;
    constexpr int kRuns = 60;
    double nees = 0.0;
    *mean_scale = 0.0;
    for (int r = 0; r < kRuns; ++r) {
      MoverTrack track(o);
      Observer obs(7000 + static_cast<std::uint64_t>(r));
      obs.range_sigma = range_sigma;
      const auto path = [](double) { return Truth{Vec2(3.0, 1.0), Vec2::Zero()}; };
      run_track(&track, &obs, path, 151, [&](int k, const MoverTrack& tr, const Truth& t) {
        if (k != 150) return;
        TrackVector err;
        err << tr.mean().head<2>() - t.p, tr.mean().tail<2>() - t.v;
        nees += err.dot(tr.covariance().inverse() * err);
        *mean_scale += tr.noise_scale() / kRuns;
      });
    }
    return nees / kRuns;
  };
  double scale_off = 0.0, scale_on = 0.0, scale_honest = 0.0;
  const double off = mean_nees(false, 4 * kRangeSigma, &scale_off);
  const double on = mean_nees(true, 4 * kRangeSigma, &scale_on);
  const double honest = mean_nees(true, kRangeSigma, &scale_honest);
  EXPECT_NEAR(scale_off, 1.0, 1e-12);
  EXPECT_GT(off, 8.0);  // overconfident
  EXPECT_GT(scale_on, 3.0);
  EXPECT_LT(on, chi2_quantile(0.975, 4 * 60) / 60);
  EXPECT_LT(on, off / 2);
  EXPECT_LT(scale_honest, 1.5);
  EXPECT_LT(honest, chi2_quantile(0.975, 4 * 60) / 60);
}

// One sighting no model explains (a misread) is held back and leaves the track as
// it was; a second in a row that agrees with it restarts the track from the two;
// one that does not agree is held back in its turn.
TEST(MoverTrack, AnUnexplainedSightingIsHeldBackAndASecondThatAgreesRestartsTheTrack) {
  MoverTrack track;
  Observer obs(41);
  const auto path = [](double) { return Truth{Vec2(3.0, 0.0), Vec2::Zero()}; };
  run_track(&track, &obs, path, 20, [](int, const MoverTrack&, const Truth&) {});
  ASSERT_TRUE(track.confirmed());
  const std::int64_t sightings = track.sightings();
  track.predict(track.time() + kDt);
  const MoverTrack predicted = track;
  TrackUpdate u = track.update(obs.see(Vec2(6.0, 4.0)));
  EXPECT_TRUE(u.outlier);
  EXPECT_FALSE(u.restarted);
  EXPECT_EQ(track.outliers(), 1);
  EXPECT_EQ(track.restarts(), 0);
  EXPECT_EQ(track.sightings(), sightings);
  EXPECT_EQ(track.mean(), predicted.mean());  // the prediction alone
  EXPECT_EQ(track.covariance(), predicted.covariance());
  // A second misread elsewhere: held back too, nothing restarted.
  track.predict(track.time() + kDt);
  u = track.update(obs.see(Vec2(-2.0, 5.0)));
  EXPECT_TRUE(u.outlier);
  EXPECT_EQ(track.outliers(), 2);
  EXPECT_LT((track.mean().head<2>() - Vec2(3.0, 0.0)).norm(), 0.1);
  // Then two sightings near (6, 4): the second restarts the track from both.
  track.predict(track.time() + kDt);
  EXPECT_TRUE(track.update(obs.see(Vec2(6.0, 4.0))).outlier);
  track.predict(track.time() + kDt);
  u = track.update(obs.see(Vec2(6.02, 4.0)));
  EXPECT_TRUE(u.restarted);
  EXPECT_FALSE(u.outlier);
  EXPECT_EQ(track.restarts(), 1);
  EXPECT_EQ(track.sightings(), 2);
  EXPECT_TRUE(track.confirmed());
  EXPECT_LT((track.mean().head<2>() - Vec2(6.01, 4.0)).norm(), 0.2);
  EXPECT_LT((track.anchor() - Vec2(6.0, 4.0)).norm(), 0.2);
  // A track started at a sighting holds one: not confirmed until a second fits.
  MoverTrack fresh;
  fresh.start(obs.see(Vec2(1.0, 1.0)), Vec2(1.0, 1.0), 0.0);
  EXPECT_EQ(fresh.sightings(), 1);
  EXPECT_FALSE(fresh.confirmed());
}

TEST(MoverTrack, ValidatedOnlyWhenItsInnovationsFitTheirCovariance) {
  const auto path = [](double t) { return constant_velocity(t, Vec2(2.0, 2.0), Vec2(0.3, 0.0)); };
  MoverTrack good;
  Observer honest(51);
  bool early = false;
  run_track(&good, &honest, path, 60, [&](int k, const MoverTrack& tr, const Truth&) {
    if (k < 9) early = early || tr.validated();  // fewer than validation_sightings
  });
  EXPECT_FALSE(early);
  EXPECT_TRUE(good.validated());
  // A sensor six times noisier in range than its model says: the window's NIS is
  // far above its bound.
  MoverTrack bad;
  Observer noisy(52);
  noisy.range_sigma = 6 * kRangeSigma;
  run_track(&bad, &noisy, path, 60, [](int, const MoverTrack&, const Truth&) {});
  EXPECT_FALSE(bad.validated());
}

}  // namespace
}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// The moving landmarks' tracks (robot.tracking): the pool of MoverTracks on its own
// (slots, order, expiry, a full pool counted), and the Robot that starts a track
// at a MOVING verdict, feeds it the sightings its map keeps out, ends it at the
// landmark's RETURN, and is not moved by it (tracks are consider estimates).
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <string>
#include <random>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "elaslam/robot_node/mover_tracks.hpp"
#include "elaslam/robot_node/robot.hpp"
#include "elaslam/robot_node/robot_options.hpp"
#include "scene.hpp"

namespace elaslam {
namespace {

using Vec2 = Eigen::Vector2d;

TrackSighting sighting_of(const Vec2& p) {
  TrackSighting s;
  s.z = observe(Pose2{}, p);
  s.R = Eigen::Vector2d(0.0025, 1e-4).asDiagonal();
  s.pose_cov = Eigen::Matrix3d::Identity() * 1e-6;
  return s;
}

TEST(MoverTracks, SlotsAreTakenAndGivenBackInOrder) {
  TrackingOptions o;
  o.max_tracks = 2;
  o.lost_after_s = 1.0;
  MoverTracks tracks(o, 16);
  EXPECT_TRUE(tracks.begin(5, sighting_of(Vec2(2, 0)), Vec2(2, 0), 0.0));
  EXPECT_TRUE(tracks.begin(3, sighting_of(Vec2(0, 2)), Vec2(0, 2), 0.0));
  EXPECT_FALSE(tracks.begin(7, sighting_of(Vec2(1, 1)), Vec2(1, 1), 0.0));  // full
  EXPECT_EQ(tracks.counters().full, 1);
  EXPECT_EQ(tracks.ids(), (std::vector<int>{5, 3}));
  EXPECT_FALSE(tracks.begin(16, sighting_of(Vec2(1, 1)), Vec2(1, 1), 0.0));  // id out of range
  EXPECT_FALSE(tracks.see(7, sighting_of(Vec2(1, 1)), 0.1));                  // no track
  // Seen at 0.5 s; 3 is not: at 1.2 s only 3 is lost (unseen for more than 1 s).
  EXPECT_TRUE(tracks.see(5, sighting_of(Vec2(2, 0)), 0.5));
  tracks.expire(1.2);
  EXPECT_EQ(tracks.ids(), (std::vector<int>{5}));
  EXPECT_EQ(tracks.counters().lost, 1);
  EXPECT_FALSE(tracks.has(3));
  EXPECT_NEAR(tracks.track(5).time(), 0.5, 1e-12);
  // The freed slot takes 7; ending 5 as returned frees the other.
  EXPECT_TRUE(tracks.begin(7, sighting_of(Vec2(1, 1)), Vec2(1, 1), 1.2));
  tracks.end(5, /*returned=*/true);
  EXPECT_EQ(tracks.counters().returned, 1);
  EXPECT_EQ(tracks.ids(), (std::vector<int>{7}));
  tracks.clear();
  EXPECT_TRUE(tracks.ids().empty());
  EXPECT_EQ(tracks.counters().ended, 1);
  EXPECT_EQ(tracks.counters().started, 3);
  EXPECT_EQ(tracks.counters().updates, 1);
}

TEST(MoverTracks, DisabledHoldsNoSlotAndBadOptionsAreRefused) {
  TrackingOptions o;
  o.enabled = false;
  MoverTracks off(o, 16);
  EXPECT_FALSE(off.begin(1, sighting_of(Vec2(2, 0)), Vec2(2, 0), 0.0));
  EXPECT_EQ(off.counters().full, 0);
  o = {};
  o.max_tracks = -1;
  EXPECT_THROW(MoverTracks(o, 16), std::invalid_argument);
  o = {};
  o.lost_after_s = 0.0;
  EXPECT_THROW(MoverTracks(o, 16), std::invalid_argument);
  o = {};
  o.track.cv_accel_sigma = -1.0;
  EXPECT_THROW(MoverTracks(o, 16), std::invalid_argument);
}

/// A robot standing among six landmarks 3 m away, at 10 Hz with stamps; landmark 2
/// is still for 2 s, moves at 0.8 m/s for 3 s, then stands still again.
class RobotTracks : public ::testing::Test {
 protected:
  static constexpr int kMover = 2;
  static constexpr double kSpeed = 0.8;
  static constexpr int kStart = 20, kStop = 50, kFrames = 120;

  static Vec2 mover_at(int frame, const Vec2& start) {
    const int moving = std::clamp(frame, kStart, kStop) - kStart;
    return start + kSpeed * 0.1 * moving * Vec2(0.0, 1.0);
  }
  /// Runs the scene; `each(frame, robot, truth of the mover)` after every frame.
  template <class Each>
  static void run(Robot* r, std::uint64_t seed, const Each& each) {
    std::vector<Vec2> lms = test::ring(6, 3.0);
    const Vec2 start = lms[kMover];
    std::mt19937_64 rng(seed);
    for (int f = 0; f < kFrames; ++f) {
      lms[kMover] = mover_at(f, start);
      FrameInput in = test::frame_from(f, Pose2{}, Pose2{}, lms, test::all_ids(6), &rng);
      in.utime = 1'700'000'000'000'000 + std::int64_t{100000} * f;
      r->process(in);
      each(f, *r, lms[kMover]);
    }
  }
};

TEST_F(RobotTracks, AMoverIsTrackedFromItsMovingVerdictUntilItReturns) {
  Robot r(test::robot_options(Mode::kEla), 1);
  int moving_frame = -1, returned_frame = -1, tracked_frames = 0;
  double pos2 = 0.0, vel2 = 0.0;
  int scored = 0;
  run(&r, 7, [&](int f, const Robot& robot, const Vec2& truth) {
    for (const MapEvent& e : robot.events()) {
      if (e.landmark_id != kMover) continue;
      if (e.kind == EventKind::kMoving && moving_frame < 0) moving_frame = f;
      if (e.kind == EventKind::kReturn) returned_frame = f;
    }
    if (!robot.tracks().has(kMover)) return;
    ++tracked_frames;
    const MoverTrack& t = robot.tracks().track(kMover);
    // Scored from 1 s after the verdict while the mover moves.
    if (moving_frame >= 0 && f >= moving_frame + 10 && f < kStop) {
      pos2 += (t.mean().head<2>() - truth).squaredNorm();
      vel2 += (t.mean().tail<2>() - Vec2(0.0, kSpeed)).squaredNorm();
      ++scored;
    }
  });
  ASSERT_GE(moving_frame, kStart);
  ASSERT_LT(moving_frame, kStart + 10);  // found within 1 s
  ASSERT_GT(scored, 10);
  EXPECT_LT(std::sqrt(pos2 / scored), 0.05);
  EXPECT_LT(std::sqrt(vel2 / scored), 0.1);
  // It stopped at frame 50: it returns to the map, and the track ends there.
  ASSERT_GT(returned_frame, kStop);
  EXPECT_FALSE(r.tracks().has(kMover));
  EXPECT_EQ(r.tracks().counters().returned, 1);
  EXPECT_EQ(tracked_frames, returned_frame - moving_frame);
  EXPECT_GT(r.tracks().counters().updates, 20);
  EXPECT_EQ(r.tracks().counters().full, 0);
}

// A mover at 0.3 m/s agrees with its candidate's anchor for return_frames sightings
// and comes back to the map while it still moves; with return_when_stopped its
// RETURN waits until its track finds it stopped (it stops at frame 50).
TEST(RobotTracksReturn, ASlowMoverReturnsOnlyOnceItsTrackFindsItStopped) {
  const auto returns_while_moving = [](bool when_stopped, int* first_return) {
    RobotOptions o = test::robot_options(Mode::kEla);
    o.tracking.return_when_stopped = when_stopped;
    Robot r(o, 1);
    std::vector<Vec2> lms = test::ring(6, 3.0);
    const Vec2 start = lms[2];
    std::mt19937_64 rng(7);
    int during = 0;
    *first_return = -1;
    for (int f = 0; f < 120; ++f) {
      lms[2] = start + 0.03 * (std::clamp(f, 20, 50) - 20) * Vec2(0.0, 1.0);
      FrameInput in = test::frame_from(f, Pose2{}, Pose2{}, lms, test::all_ids(6), &rng);
      in.utime = 1'700'000'000'000'000 + std::int64_t{100000} * f;
      r.process(in);
      for (const MapEvent& e : r.events()) {
        if (e.landmark_id != 2 || e.kind != EventKind::kReturn) continue;
        if (f < 50) ++during;
        if (*first_return < 0 && f >= 50) *first_return = f;
      }
    }
    return during;
  };
  int after_off = -1, after_on = -1;
  EXPECT_GT(returns_while_moving(false, &after_off), 0);
  EXPECT_EQ(returns_while_moving(true, &after_on), 0);
  EXPECT_GT(after_on, 50);  // it does come back once it rests
  EXPECT_LT(after_on, 80);
}

// tracking.correct_pose: from frame 20 a mover sways about its place as the
// bounded model's process does (a damped spring driven by white acceleration,
// the track's default scales: 0.3 m, 1 rad/s, damping 0.7) among three static
// landmarks, seen by a robot that turns in place on a noisy odometer (its heading
// drifts unless the landmarks correct it). Once the mover's track is validated
// and likeliest static or bounded, the filter follows it: its state moves as the
// track predicts, consistently with the truth, and its sightings correct the
// robot without making its pose inconsistent. Off, the mover corrects nothing. (What following buys is measured
// on the grid: docs/experiments/mover-tracks.md.)
struct FollowRun {
  std::int64_t followed = 0, corrections = 0;
  double landmark_nees = 0.0, landmark_worst_m = 0.0;
  int landmark_samples = 0;
  double pose_nees = 0.0;
  int pose_samples = 0;
};

FollowRun run_swaying_mover(bool correct_pose, std::uint64_t seed) {
  RobotOptions o = test::robot_options(Mode::kEla);
  o.tracking.return_when_stopped = true;
  o.tracking.correct_pose = correct_pose;
  Robot r(o, 1);
  std::vector<Vec2> lms = test::ring(4, 3.0);
  const Vec2 start = lms[2];
  std::mt19937_64 rng(seed), sway_rng(seed + 1000), odo_rng(seed + 2000);
  std::normal_distribution<double> n01(0.0, 1.0);
  // The odometer's turn noise as the robot states it: var_rot_per_rad per step.
  constexpr double kTurn = 0.02, kVarRotPerRad = 1e-4;
  double odometer_heading = 0.0;
  const MoverTrackOptions& k = o.tracking.track;
  const double w = k.bounded_omega_rad_s, zeta = k.bounded_damping, dt = 0.1;
  // The spectral density that gives the model its stationary sigma.
  const double q = 4.0 * zeta * w * w * w * k.bounded_sigma_m * k.bounded_sigma_m;
  Vec2 offset = Vec2::Zero(), velocity = Vec2::Zero();
  FollowRun out;
  for (int f = 0; f < 200; ++f) {
    if (f > 20) {
      offset += velocity * dt;
      velocity += (-w * w * offset - 2.0 * zeta * w * velocity) * dt + std::sqrt(q * dt) * Vec2(n01(sway_rng), n01(sway_rng));
    }
    lms[2] = start + offset;
    const Pose2 truth{0.0, 0.0, wrap_angle(kTurn * f)};
    if (f > 0) odometer_heading += kTurn + std::sqrt(kVarRotPerRad * kTurn) * n01(odo_rng);
    FrameInput in = test::frame_from(f, truth, Pose2{0.0, 0.0, wrap_angle(odometer_heading)}, lms, test::all_ids(4), &rng);
    in.noise = {0.0, kVarRotPerRad, 0.0};
    in.utime = 1'700'000'000'000'000 + std::int64_t{100000} * f;
    const FrameSummary s = r.process(in);
    out.followed += s.movers_followed;
    out.corrections += s.mover_corrections;
    if (s.movers_followed > 0 && r.filter().has_landmark(2)) {
      const Vec2 e = r.filter().landmark(2) - lms[2];
      out.landmark_nees += e.dot(r.filter().landmark_cov(2).ldlt().solve(e));
      out.landmark_worst_m = std::max(out.landmark_worst_m, e.norm());
      ++out.landmark_samples;
    }
    if (f >= 100) {
      const Eigen::Vector3d e(r.filter().pose().x, r.filter().pose().y, wrap_angle(r.filter().pose().theta - truth.theta));
      out.pose_nees += e.dot(r.filter().pose_cov().ldlt().solve(e));
      ++out.pose_samples;
    }
  }
  return out;
}

TEST(RobotTracksFollow, AValidatedSwayingMoverIsFollowedConsistently) {
  for (const std::uint64_t seed : {3u, 5u, 11u}) {
    SCOPED_TRACE(seed);
    const FollowRun on = run_swaying_mover(true, seed);
    const FollowRun off = run_swaying_mover(false, seed);
    EXPECT_EQ(off.followed, 0);
    EXPECT_EQ(off.corrections, 0);
    ASSERT_GT(on.followed, 50);
    EXPECT_GT(on.corrections, 50);
    ASSERT_GT(on.landmark_samples, 50);
    // The followed state is where the mover is, within its own covariance (2 dof).
    EXPECT_LT(on.landmark_nees / on.landmark_samples, 4.0);
    EXPECT_LT(on.landmark_worst_m, 0.2);
    // The robot's pose stays consistent with the mover's sightings in (3 dof), as
    // without them.
    EXPECT_LT(off.pose_nees / off.pose_samples, 6.0);
    EXPECT_LT(on.pose_nees / on.pose_samples, 6.0);
  }
}

// config/paper.yaml with `tracking` as its robot.tracking section, in a file.
std::string paper_with_tracking(const std::string& tracking) {
  std::ifstream in(std::string(ELASLAM_SOURCE_DIR) + "/config/paper.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t at = text.find("\nrobot:\n");
  EXPECT_NE(at, std::string::npos);
  text.insert(at + 8, tracking);
  const std::string path = ::testing::TempDir() + "/tracking.yaml";
  std::ofstream(path) << text;
  return path;
}

TEST(RobotTracksConfig, TheFollowKeysAreReadAndABadOneIsNamed) {
  const RobotOptions d = load_robot_options(std::string(ELASLAM_SOURCE_DIR) + "/config/paper.yaml");
  EXPECT_FALSE(d.tracking.correct_pose);
  EXPECT_FALSE(d.tracking.return_when_stopped);
  const RobotOptions o = load_robot_options(
      paper_with_tracking("  tracking:\n    correct_pose: true\n    return_when_stopped: true\n"));
  EXPECT_TRUE(o.tracking.correct_pose);
  EXPECT_TRUE(o.tracking.return_when_stopped);
  try {
    load_robot_options(paper_with_tracking("  tracking:\n    correct_pose: sometimes\n"));
    ADD_FAILURE() << "robot.tracking.correct_pose: sometimes was accepted";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("robot.tracking.correct_pose"), std::string::npos) << e.what();
  }
}

TEST_F(RobotTracks, TracksNeverMoveTheRobotNorItsMap) {
  RobotOptions on = test::robot_options(Mode::kEla);
  RobotOptions off = on;
  off.tracking.enabled = false;
  Robot a(on, 1), b(off, 1);
  run(&a, 9, [](int, const Robot&, const Vec2&) {});
  run(&b, 9, [](int, const Robot&, const Vec2&) {});
  EXPECT_GT(a.tracks().counters().started, 0);
  EXPECT_EQ(b.tracks().counters().started, 0);
  ASSERT_EQ(a.filter().mean().size(), b.filter().mean().size());
  EXPECT_EQ(a.filter().mean(), b.filter().mean());
  EXPECT_EQ(a.filter().covariance(), b.filter().covariance());
}

// The frame's operations (Robot::track_ops) replayed on a pool of one's own with the
// robot's own pose reproduce its tracks bit for bit; with the true pose (the robot
// stands at the origin) they are the tracks of a perfectly localised observer.
TEST_F(RobotTracks, ReplayingTheFramesOperationsReproducesTheTracks) {
  const RobotOptions o = test::robot_options(Mode::kEla);
  Robot r(o, 1);
  MoverTracks same(o.tracking, o.ekf.max_landmark_id), truth(o.tracking, o.ekf.max_landmark_id);
  int compared = 0, ops = 0;
  double true_pose_gap = 0.0;
  run(&r, 13, [&](int, const Robot& robot, const Vec2&) {
    ops += static_cast<int>(robot.track_ops().size());
    TrackSighting base;
    base.R = robot.filter().measurement_cov();
    base.pose = robot.estimate().pose();
    base.pose_cov = robot.estimate().pose_cov();
    same.apply(robot.track_ops(), base, robot.clock_s());
    TrackSighting exact;
    exact.R = base.R;
    truth.apply(robot.track_ops(), exact, robot.clock_s());
    ASSERT_EQ(same.ids(), robot.tracks().ids());
    ASSERT_EQ(truth.ids(), robot.tracks().ids());
    for (const int id : robot.tracks().ids()) {
      EXPECT_EQ(same.track(id).mean(), robot.tracks().track(id).mean());
      EXPECT_EQ(same.track(id).covariance(), robot.tracks().track(id).covariance());
      true_pose_gap = std::max(true_pose_gap, (truth.track(id).mean() - same.track(id).mean()).norm());
      ++compared;
    }
  });
  EXPECT_GT(compared, 20);
  EXPECT_GT(ops, compared);
  // The robot's pose is well known here: the true pose changes the tracks by
  // centimetres at most, and changes them (the pose covariance is no longer considered).
  EXPECT_GT(true_pose_gap, 0.0);
  EXPECT_LT(true_pose_gap, 0.05);
}

TEST_F(RobotTracks, TheClockFollowsTheStampsAndAResetEndsEveryTrack) {
  Robot r(test::robot_options(Mode::kEla), 1);
  bool had_track = false;
  run(&r, 11, [&](int f, const Robot& robot, const Vec2&) {
    if (f == kStop - 1) had_track = robot.tracks().has(kMover);
  });
  EXPECT_TRUE(had_track);
  EXPECT_NEAR(r.clock_s(), 0.1 * (kFrames - 1), 1e-9);
  r.reset();
  EXPECT_TRUE(r.tracks().ids().empty());
  EXPECT_DOUBLE_EQ(r.clock_s(), 0.0);
}

}  // namespace
}  // namespace elaslam

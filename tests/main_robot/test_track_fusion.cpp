// SPDX-License-Identifier: Apache-2.0
// main_robot's fusion of the robots' tracks (track_fusion.hpp): covariance
// intersection against hand-worked numbers, the age bound, and MainNode's checks of
// TRACKS_<r> (every bad message refused, counted by reason, and nothing changed).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "../support/messages.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/main_robot/main_node.hpp"
#include "elaslam/main_robot/track_fusion.hpp"
#include "team_options.hpp"

namespace elaslam {
namespace {

TrackEstimate estimate(const Eigen::Vector4d& x, const Eigen::Vector4d& diag, const std::array<double, 3>& p) {
  TrackEstimate e;
  e.id = 5;
  e.x = x;
  e.P = diag.asDiagonal();
  e.probabilities = p;
  return e;
}

// Pa = diag(1, 4, 1, 4), Pb = diag(4, 1, 4, 1): trace(P(w)) = 2 / (w + (1 - w) / 4) +
// 2 / (w / 4 + 1 - w), symmetric about w = 1/2, where it is smallest: P = 1.6 I
// (1 / (1/2 + 1/8)), trace 6.4 against 10 for either alone. With xa = 0 and
// xb = (1, 1, 1, 1): x = 1.6 * 1/2 * diag(1/4, 1, 1/4, 1) xb = (0.2, 0.8, 0.2, 0.8).
TEST(CovarianceIntersection, TwoTracksAgainstAHandWorkedFusion) {
  const TrackEstimate a = estimate(Eigen::Vector4d::Zero(), Eigen::Vector4d(1, 4, 1, 4), {0.2, 0.2, 0.6});
  const TrackEstimate b = estimate(Eigen::Vector4d::Ones(), Eigen::Vector4d(4, 1, 4, 1), {0.6, 0.2, 0.2});
  TrackEstimate f;
  const double w = covariance_intersection(a, b, &f);
  EXPECT_NEAR(w, 0.5, 1e-6);
  EXPECT_NEAR((f.P - 1.6 * Eigen::Matrix4d::Identity()).norm(), 0.0, 1e-6);
  EXPECT_NEAR((f.x - Eigen::Vector4d(0.2, 0.8, 0.2, 0.8)).norm(), 0.0, 1e-6);
  EXPECT_NEAR(f.probabilities[0], 0.4, 1e-6);
  EXPECT_NEAR(f.probabilities[1], 0.2, 1e-6);
  EXPECT_NEAR(f.probabilities[2], 0.4, 1e-6);
  EXPECT_EQ(f.id, 5);
  // Symmetric in its arguments, with the weight on the other side.
  TrackEstimate g;
  EXPECT_NEAR(covariance_intersection(b, a, &g), 0.5, 1e-6);
  EXPECT_NEAR((g.x - f.x).norm(), 0.0, 1e-6);
}

// Pa = I, Pb = 4 I: trace(P(w)) = 4 / (w + (1 - w) / 4) falls all the way to w = 1,
// a alone: covariance intersection never takes a worse estimate in (unlike a Kalman
// fusion, which would claim P = 0.8 I, as if the two were independent).
TEST(CovarianceIntersection, AWorseTrackAddsNothing) {
  const TrackEstimate a = estimate(Eigen::Vector4d(1, 2, 3, 4), Eigen::Vector4d(1, 1, 1, 1), {0.1, 0.1, 0.8});
  const TrackEstimate b = estimate(Eigen::Vector4d(2, 2, 2, 2), Eigen::Vector4d(4, 4, 4, 4), {0.9, 0.05, 0.05});
  TrackEstimate f;
  EXPECT_EQ(covariance_intersection(a, b, &f), 1.0);
  EXPECT_EQ(f.x, a.x);
  EXPECT_EQ(f.P, a.P);
  EXPECT_EQ(f.probabilities, a.probabilities);
  EXPECT_EQ(covariance_intersection(b, a, &f), 0.0);
  EXPECT_EQ(f.x, a.x);
}

// A robot's newest TRACKS replaces its last; a message more than max_age_frames older
// than the frame fused is left out; several robots' tracks of one landmark are one
// fused track naming them all.
TEST(TrackFusion, NewestTracksPerRobotWithinTheAgeBound) {
  TrackFusion fusion(10);
  fusion.take(test::tracks_msg(1, 0, {test::track_of(3, 0, 0, 1, 0), test::track_of(8, 5, 5, 0, 0)}));
  fusion.take(test::tracks_msg(1, 4, {test::track_of(3, 0.4, 0, 1, 0)}));  // 8 ended
  fusion.take(test::tracks_msg(3, 2, {test::track_of(3, 0.5, 0, 1, 0)}));
  const std::vector<FusedTrack>& f = fusion.fuse(12);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(f[0].estimate.id, 3);
  EXPECT_EQ(f[0].contributors, 0b101);
  EXPECT_NEAR(f[0].estimate.x(0), 0.45, 1e-6);  // equal covariances: the weight is 1/2
  EXPECT_EQ(f[0].likeliest(), track_t::CONSTANT_VELOCITY);
  EXPECT_FALSE(f[0].stopped());
  const std::vector<FusedTrack>& g = fusion.fuse(13);  // robot 3's, of frame 2, is 11 frames old
  ASSERT_EQ(g.size(), 1u);
  EXPECT_EQ(g[0].contributors, 0b1);
  EXPECT_EQ(g[0].estimate.x(0), 0.4);
  fusion.forget(1);
  EXPECT_TRUE(fusion.fuse(13).empty());
  EXPECT_EQ(fusion.robot_frame(1), -1);
}

// Each robot's tracks are predicted to the frame fused at the robot's own frame
// period, measured from its publications' stamps: robot 1's track of a mover at
// 1 m/s sent at frame 11 and robot 2's at frame 10, both at 10 Hz, are fused as two
// estimates of frame 12. Until a robot's period is known its tracks go as sent.
TEST(TrackFusion, TracksArePredictedToTheFrameFusedAtEachRobotsPeriod) {
  TrackFusion fusion(10);
  const auto stamped = [](int robot, int frame, double x) {
    track_list_t m = test::tracks_msg(robot, frame, {test::track_of(3, x, 0, 1, 0)});
    m.utime = 1'000'000 + std::int64_t{100'000} * frame;
    return m;
  };
  fusion.take(stamped(1, 9, 0.9));
  EXPECT_EQ(fusion.robot_period_s(1), 0.0);
  const std::vector<FusedTrack>& alone = fusion.fuse(10);  // period unknown: as sent
  ASSERT_EQ(alone.size(), 1u);
  EXPECT_EQ(alone[0].estimate.x(0), 0.9);
  fusion.take(stamped(1, 8, 0.8));  // older: stale, nothing learnt
  fusion.take(stamped(2, 9, 0.9));
  fusion.take(stamped(2, 10, 1.0));
  EXPECT_NEAR(fusion.robot_period_s(2), 0.1, 1e-12);
  fusion.take(stamped(1, 10, 1.0));
  fusion.take(stamped(1, 11, 1.1));
  EXPECT_NEAR(fusion.robot_period_s(1), 0.1, 1e-12);
  const std::vector<FusedTrack>& f = fusion.fuse(12);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(f[0].contributors, 0b11);
  // Robot 1's of frame 11 predicted 0.1 s, robot 2's of frame 10 0.2 s: both at 1.2 m.
  EXPECT_NEAR(f[0].estimate.x(0), 1.2, 1e-9);
  // The prediction widens the covariance by the constant-velocity model's Q.
  const TrackEstimate one = predict_track(TrackEstimate{3, Eigen::Vector4d(0, 0, 1, 0),
                                                        Eigen::Vector4d(0.01, 0.01, 0.04, 0.04).asDiagonal(), {}},
                                          0.2);
  const double q = kDefaultCvAccelSigma * kDefaultCvAccelSigma;
  EXPECT_NEAR(one.x(0), 0.2, 1e-15);
  EXPECT_NEAR(one.P(0, 0), 0.01 + 0.04 * 0.04 + q * 0.008 / 3.0, 1e-15);
  EXPECT_NEAR(one.P(0, 2), 0.04 * 0.2 + q * 0.04 / 2.0, 1e-15);
  EXPECT_NEAR(one.P(2, 2), 0.04 + q * 0.2, 1e-15);
  EXPECT_EQ(predict_track(one, 0.0).x, one.x);
  EXPECT_EQ(predict_track(one, -0.1).P, one.P);
  fusion.forget(2);
  EXPECT_EQ(fusion.robot_period_s(2), 0.0);
}

using test::team_of_three;

// GIVEN main holding robot 1's track of landmark 7 and robot 2's of landmark 9
// WHEN TRACKS messages arrive each spoilt in one way
// THEN each is refused with its reason named and counted (tracks_refused,
// rejected_inputs, refused[reason]), and the fused tracks are what they were.
TEST(MainNodeTracks, EveryKindOfBadTracksIsRefusedAndCounted) {
  MainNode node(team_of_three());
  ASSERT_TRUE(node.on_tracks(test::tracks_msg(1, 3, {test::track_of(7, 1, 2, 0.5, 0)})));
  ASSERT_TRUE(node.on_tracks(test::tracks_msg(2, 3, {test::track_of(9, -1, 0, 0, 0)})));
  ASSERT_TRUE(node.make_global_tracks(0, 3));
  const global_tracks_t before = node.global_tracks(0);
  ASSERT_EQ(before.num_tracks, 2);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  struct Case {
    const char* name;
    std::function<void(track_list_t&)> spoil;
    Refusal reason;
    const char* expect;
  };
  const std::vector<Case> cases = {
      {"robot outside the team", [](track_list_t& m) { m.robot_id = 4; }, Refusal::kOutsideTeam, "limits.team"},
      {"robot id 0", [](track_list_t& m) { m.robot_id = 0; }, Refusal::kMalformed, "robot_id"},
      {"negative frame", [](track_list_t& m) { m.frame = -1; }, Refusal::kMalformed, "frame"},
      {"count beyond the contract",
       [](track_list_t& m) {
         m.tracks.resize(contract::kMaxTracks + 1, m.tracks[0]);
         m.num_tracks = contract::kMaxTracks + 1;
       },
       Refusal::kMalformed, "num_tracks"},
      {"count beyond the array", [](track_list_t& m) { m.num_tracks = 2; }, Refusal::kMalformed, "num_tracks"},
      {"negative omitted", [](track_list_t& m) { m.num_omitted = -1; }, Refusal::kMalformed, "num_omitted"},
      {"no chunks", [](track_list_t& m) { m.num_chunks = 0; }, Refusal::kMalformed, "num_chunks"},
      {"more chunks than the contract's",
       [](track_list_t& m) { m.num_chunks = contract::kMaxTrackChunks + 1; }, Refusal::kMalformed, "num_chunks"},
      {"chunk beyond num_chunks", [](track_list_t& m) { m.chunk = 1; }, Refusal::kMalformed, "chunk"},
      {"negative chunk", [](track_list_t& m) { m.chunk = -1; }, Refusal::kMalformed, "chunk"},
      {"id beyond max_landmark_id", [](track_list_t& m) { m.tracks[0].id = 32; }, Refusal::kMalformed, "landmark id"},
      {"negative id", [](track_list_t& m) { m.tracks[0].id = -1; }, Refusal::kMalformed, "landmark id"},
      {"id twice",
       [](track_list_t& m) {
         m.tracks.push_back(m.tracks[0]);
         m.num_tracks = 2;
       },
       Refusal::kDuplicateId, "twice"},
      {"NaN position", [nan](track_list_t& m) { m.tracks[0].x = nan; }, Refusal::kImplausible, "not finite"},
      {"NaN velocity", [nan](track_list_t& m) { m.tracks[0].vy = nan; }, Refusal::kMalformed, "not finite"},
      {"infinite covariance", [](track_list_t& m) { m.tracks[0].cov[9] = INFINITY; }, Refusal::kMalformed, "not finite"},
      {"position far away", [](track_list_t& m) { m.tracks[0].x = 1e6; }, Refusal::kImplausible, "world_bound"},
      {"absurd speed", [](track_list_t& m) { m.tracks[0].vx = 1e6; }, Refusal::kImplausible, "speed"},
      {"covariance not positive semi-definite",
       [](track_list_t& m) { m.tracks[0].cov[2] = 1.0f; },  // xvx = 1 with var(x) 0.01, var(vx) 0.04
       Refusal::kImplausible, "semi-definite"},
      {"negative velocity variance", [](track_list_t& m) { m.tracks[0].cov[7] = -0.04f; }, Refusal::kImplausible,
       "semi-definite"},
      {"zero position covariance",
       [](track_list_t& m) { m.tracks[0].cov[0] = m.tracks[0].cov[4] = 0.0f; }, Refusal::kImplausible, "cov_floor"},
      {"variance above the ceiling", [](track_list_t& m) { m.tracks[0].cov[9] = 1e5f; }, Refusal::kImplausible,
       "cov_ceiling"},
      {"probabilities summing to 1.5", [](track_list_t& m) { m.tracks[0].probabilities[0] = 0.6f; },
       Refusal::kMalformed, "sum to 1"},
      {"negative probability",
       [](track_list_t& m) {
         m.tracks[0].probabilities[0] = -0.1f;
         m.tracks[0].probabilities[1] = 0.4f;
       },
       Refusal::kMalformed, "outside [0, 1]"},
      {"likeliest not a model", [](track_list_t& m) { m.tracks[0].likeliest = 3; }, Refusal::kMalformed, "likeliest"},
      {"stopped not a flag", [](track_list_t& m) { m.tracks[0].stopped = 2; }, Refusal::kMalformed, "stopped"},
      {"validated not a flag", [](track_list_t& m) { m.tracks[0].validated = -1; }, Refusal::kMalformed, "validated"},
      {"negative sightings", [](track_list_t& m) { m.tracks[0].sightings = -1; }, Refusal::kMalformed, "sightings"},
  };
  std::int64_t refused = 0;
  for (const Case& c : cases) {
    track_list_t m = test::tracks_msg(1, 4, {test::track_of(7, 5, 5, 0, 0)});
    c.spoil(m);
    const RefusalCounts counts = node.counters().refused;
    std::string why;
    EXPECT_FALSE(node.on_tracks(m, &why)) << c.name;
    EXPECT_NE(why.find(c.expect), std::string::npos) << c.name << ": " << why;
    EXPECT_EQ(node.counters().refused[c.reason], counts[c.reason] + 1) << c.name << ": " << why;
    ++refused;
    EXPECT_EQ(node.track_fusion().robot_frame(1), 3) << c.name;
  }
  EXPECT_EQ(node.counters().tracks_refused, refused);
  EXPECT_EQ(node.counters().rejected_inputs, refused);
  EXPECT_EQ(node.counters().tracks, 2);
  // The fused tracks are unchanged.
  ASSERT_TRUE(node.make_global_tracks(0, 3));
  const global_tracks_t& after = node.global_tracks(0);
  ASSERT_EQ(after.num_tracks, 2);
  EXPECT_EQ(after.tracks[0].id, 7);
  EXPECT_EQ(after.tracks[0].x, before.tracks[0].x);
  EXPECT_EQ(after.tracks[1].id, 9);
  // A late (older) message is ignored, not refused; a good one is taken.
  EXPECT_TRUE(node.on_tracks(test::tracks_msg(1, 2, {test::track_of(7, 5, 5, 0, 0)})));
  EXPECT_EQ(node.counters().stale_tracks, 1);
  EXPECT_EQ(node.track_fusion().robot_frame(1), 3);
  EXPECT_TRUE(node.on_tracks(test::tracks_msg(1, 4, {test::track_of(7, 5, 5, 0, 0)})));
  EXPECT_EQ(node.track_fusion().robot_frame(1), 4);
}

// GIVEN robot 1 followed at incarnation 100 with a track of landmark 7
// WHEN TRACKS of another incarnation arrive, then a POSE of a new incarnation (a
// restart without its state)
// THEN the other incarnation's tracks are refused as stale; the restart drops the
// robot's tracks (those of before are gone) and its new incarnation's are taken.
TEST(MainNodeTracks, TracksFollowTheRobotsIncarnation) {
  MainNode node(team_of_three());
  pose_estimate_t p = test::pose_msg(1, 0);
  p.incarnation = 100;
  ASSERT_EQ(node.on_pose(p), 0);
  track_list_t m = test::tracks_msg(1, 0, {test::track_of(7, 1, 2, 0.5, 0)});
  m.incarnation = 100;
  ASSERT_TRUE(node.on_tracks(m));
  track_list_t other = test::tracks_msg(1, 1, {test::track_of(7, 9, 9, 0, 0)});
  other.incarnation = 99;
  std::string why;
  EXPECT_FALSE(node.on_tracks(other, &why));
  EXPECT_NE(why.find("incarnation"), std::string::npos) << why;
  EXPECT_EQ(node.counters().refused[Refusal::kStale], 1);
  ASSERT_TRUE(node.make_global_tracks(0, 1));
  ASSERT_EQ(node.global_tracks(0).num_tracks, 1);
  EXPECT_EQ(node.global_tracks(0).tracks[0].x, 1.0);
  p.incarnation = 200;  // restarted
  p.frame = 1;
  node.on_pose(p);
  EXPECT_EQ(node.counters().restarts, 1);
  EXPECT_EQ(node.track_fusion().robot_frame(1), -1);
  EXPECT_EQ(node.make_global_tracks(0, 1), 1) << "the last fused track ended: one empty chunk";
  EXPECT_EQ(node.global_tracks(0).num_tracks, 0);
  EXPECT_EQ(node.global_tracks(0).num_chunks, 1);
  m.incarnation = 200;
  m.frame = 1;
  EXPECT_TRUE(node.on_tracks(m));
  EXPECT_EQ(node.track_fusion().robot_frame(1), 1);
}

// More fused tracks than one GLOBAL_TRACKS chunk holds: they go out in chunks of
// kMaxGlobalTracks in ascending id, none omitted; beyond kMaxTrackChunks chunks the
// rest are counted. Robot 1's 72 tracks (6 chunks) and robot 2's 12 others: 84
// fused, 72 go out in 6 chunks, 12 are counted.
TEST(MainNodeTracks, FusedTracksGoOutInChunksAndBeyondTheBoundAreCounted) {
  GlobalMapOptions o = team_of_three();
  o.max_landmark_id = 128;
  MainNode node(o);
  std::vector<track_t> one, two;
  for (int id = 0; id < contract::kMaxTracks; ++id) one.push_back(test::track_of(id, id, 0, 0, 0));
  for (int id = 20; id < 20 + contract::kMaxTracks; ++id) two.push_back(test::track_of(id, id, 0, 0, 0));
  ASSERT_TRUE(node.on_tracks(test::tracks_msg(1, 0, one)));
  ASSERT_TRUE(node.on_tracks(test::tracks_msg(2, 0, two)));
  ASSERT_EQ(node.make_global_tracks(0, 0), 2);
  EXPECT_EQ(node.global_tracks(0).num_tracks, contract::kMaxGlobalTracks);
  EXPECT_EQ(node.global_tracks(0).tracks[0].id, 0);
  EXPECT_EQ(node.global_tracks(1).num_tracks, 2 * contract::kMaxTracks - contract::kMaxGlobalTracks);
  EXPECT_EQ(node.global_tracks(1).tracks[0].id, 20);
  for (int c = 0; c < 2; ++c) {
    EXPECT_EQ(node.global_tracks(c).chunk, c);
    EXPECT_EQ(node.global_tracks(c).num_chunks, 2);
    EXPECT_EQ(node.global_tracks(c).num_omitted, 0);
  }
  EXPECT_EQ(node.counters().global_tracks_omitted, 0);

  const int n = contract::kMaxTrackChunks;
  for (int c = 0; c < n; ++c) {
    std::vector<track_t> chunk;
    for (int k = 0; k < contract::kMaxTracks; ++k) {
      const int id = c * contract::kMaxTracks + k;
      chunk.push_back(test::track_of(id, id, 0, 0, 0));
    }
    ASSERT_TRUE(node.on_tracks(test::tracks_msg(1, 1, chunk, c, n)));
  }
  two.clear();
  for (int id = 100; id < 100 + contract::kMaxTracks; ++id) two.push_back(test::track_of(id, id, 0, 0, 0));
  ASSERT_TRUE(node.on_tracks(test::tracks_msg(2, 1, two)));
  EXPECT_EQ(node.track_fusion().robot_tracks(1), n * contract::kMaxTracks);
  ASSERT_EQ(node.make_global_tracks(0, 1), n);
  int sent = 0, previous = -1;
  for (int c = 0; c < n; ++c) {
    const global_tracks_t& g = node.global_tracks(c);
    EXPECT_EQ(g.num_tracks, contract::kMaxGlobalTracks);
    EXPECT_EQ(g.num_omitted, contract::kMaxTracks);
    for (int k = 0; k < g.num_tracks; ++k) {
      EXPECT_GT(g.tracks[static_cast<std::size_t>(k)].id, previous);
      previous = g.tracks[static_cast<std::size_t>(k)].id;
      ++sent;
    }
  }
  EXPECT_EQ(sent, n * contract::kMaxGlobalTracks);
  EXPECT_EQ(previous, n * contract::kMaxTracks - 1) << "robot 2's ids, the highest, are the ones left out";
  EXPECT_EQ(node.counters().global_tracks_omitted, contract::kMaxTracks);
}

// A robot's publication in chunks: its tracks are fused once every chunk came. A
// publication missing a chunk when the next frame's first chunk comes is taken as
// it came (its tracks are newer than those before); a chunk that comes later is
// stale, as is a copy of a chunk taken.
TEST(TrackFusion, ARobotsChunksAreFusedTogether) {
  TrackFusion fusion(10);
  using Take = TrackFusion::Take;
  EXPECT_EQ(fusion.take(test::tracks_msg(1, 0, {test::track_of(3, 0, 0, 1, 0)}, 0, 2)), Take::kTaken);
  EXPECT_TRUE(fusion.fuse(0).empty()) << "chunk 1 still to come";
  EXPECT_EQ(fusion.robot_frame(1), 0);
  EXPECT_EQ(fusion.take(test::tracks_msg(1, 0, {test::track_of(3, 0, 0, 1, 0)}, 0, 2)), Take::kStale);  // a copy
  EXPECT_EQ(fusion.take(test::tracks_msg(1, 0, {test::track_of(8, 5, 5, 0, 0)}, 1, 2)), Take::kTaken);
  ASSERT_EQ(fusion.fuse(0).size(), 2u);
  EXPECT_EQ(fusion.robot_tracks(1), 2);

  // Frame 1: chunk 1 is lost; frame 0's tracks are fused until frame 2 begins.
  EXPECT_EQ(fusion.take(test::tracks_msg(1, 1, {test::track_of(3, 0.1, 0, 1, 0)}, 0, 2)), Take::kTaken);
  ASSERT_EQ(fusion.fuse(1).size(), 2u);
  EXPECT_EQ(fusion.fuse(1)[0].estimate.x(0), 0.0);
  EXPECT_EQ(fusion.take(test::tracks_msg(1, 2, {test::track_of(3, 0.2, 0, 1, 0)}, 0, 2)), Take::kTaken);
  const std::vector<FusedTrack>& f = fusion.fuse(2);
  ASSERT_EQ(f.size(), 1u) << "frame 1 as it came: landmark 3 alone";
  EXPECT_EQ(f[0].estimate.x(0), 0.1);
  EXPECT_EQ(fusion.take(test::tracks_msg(1, 1, {test::track_of(8, 5, 5, 0, 0)}, 1, 2)), Take::kStale);  // too late
  EXPECT_EQ(fusion.fuse(2).size(), 1u);
}

// GIVEN main holding robot 1's chunk 0 of 2 of frame 5 (landmark 7)
// WHEN chunk 1 comes claiming 3 chunks, or listing landmark 7 again
// THEN each is refused (malformed, duplicate id) and counted, and the publication
// still completes with a good chunk 1.
TEST(MainNodeTracks, AChunkAtOddsWithItsPublicationIsRefused) {
  MainNode node(team_of_three());
  ASSERT_TRUE(node.on_tracks(test::tracks_msg(1, 5, {test::track_of(7, 1, 2, 0.5, 0)}, 0, 2)));
  std::string why;
  EXPECT_FALSE(node.on_tracks(test::tracks_msg(1, 5, {test::track_of(9, 1, 2, 0.5, 0)}, 1, 3), &why));
  EXPECT_NE(why.find("num_chunks"), std::string::npos) << why;
  EXPECT_EQ(node.counters().refused[Refusal::kMalformed], 1);
  EXPECT_FALSE(node.on_tracks(test::tracks_msg(1, 5, {test::track_of(7, 1, 2, 0.5, 0)}, 1, 2), &why));
  EXPECT_NE(why.find("two chunks"), std::string::npos) << why;
  EXPECT_EQ(node.counters().refused[Refusal::kDuplicateId], 1);
  EXPECT_EQ(node.counters().tracks_refused, 2);
  EXPECT_EQ(node.counters().rejected_inputs, 2);
  EXPECT_EQ(node.track_fusion().robot_tracks(1), 0) << "the publication is not complete";
  ASSERT_TRUE(node.on_tracks(test::tracks_msg(1, 5, {test::track_of(9, 1, 2, 0.5, 0)}, 1, 2)));
  EXPECT_EQ(node.track_fusion().robot_tracks(1), 2);
  EXPECT_EQ(node.counters().tracks, 2);
}

}  // namespace
}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// The track scores of metrics.json (eval/track_score.hpp) on hand-made frames: a
// landmark that moves at 0.5 m/s for 1 s and then rests, tracked with known errors,
// against the figures worked out by hand; landmarks without truth are not scored,
// and the JSON says null for a figure over no sample.
#include "elaslam/eval/track_score.hpp"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "elaslam/eval/report.hpp"

namespace elaslam {
namespace {

constexpr double kDt = 0.1;

/// Landmark 1 at (0.05 k, 0) until frame 10, then at rest at (0.5, 0).
Eigen::Vector2d truth_at(int k) { return {0.05 * std::min(k, 10), 0.0}; }

TEST(TrackScorer, ScoresAgainstTheTruthAsWorkedOutByHand) {
  TrackScorer scorer;
  const double angle = 10.0 * 3.14159265358979323846 / 180.0;
  for (int k = 0; k <= 20; ++k) {
    std::vector<Eigen::Vector2d> truth{Eigen::Vector2d(9, 9), truth_at(k), Eigen::Vector2d(5, 5)};
    std::vector<std::uint8_t> present{1, 1, 0};
    TrackSample s;
    s.robot = 0;
    s.landmark_id = 1;
    // 0.1 m off across the motion; while it moves, 0.6 m/s turned by 10 degrees.
    s.x.head<2>() = truth_at(k) + Eigen::Vector2d(0.0, 0.1);
    s.x.tail<2>() = k <= 10 ? Eigen::Vector2d(0.6 * std::cos(angle), 0.6 * std::sin(angle)) : Eigen::Vector2d::Zero();
    s.P = Eigen::Matrix4d::Identity() * 0.01;
    s.stopped = k >= 13;
    TrackSample unknown = s;  // landmark 2 has no truth at this frame: not scored
    unknown.landmark_id = 2;
    scorer.add(kDt * k, truth, present, {s, unknown});
  }
  const TrackMetrics m = scorer.finish();
  EXPECT_EQ(m.samples, 21);
  EXPECT_NEAR(m.position_rms_m, 0.1, 1e-12);
  // Frames 1-10 move at 0.5 m/s (frame 0 has no velocity yet), 11-20 rest.
  EXPECT_EQ(m.moving_samples, 10);
  EXPECT_NEAR(m.speed_rms_mps, 0.1, 1e-9);
  EXPECT_NEAR(m.heading_rms_deg, 10.0, 1e-9);
  EXPECT_EQ(m.at_rest_samples, 10);
  EXPECT_EQ(m.stopped_verdicts, 8);  // frames 13-20
  EXPECT_NEAR(m.stop_precision, 1.0, 1e-12);
  EXPECT_NEAR(m.stop_recall, 0.8, 1e-12);
  // The stop: at rest from frame 11, found stopped at frame 13.
  EXPECT_EQ(m.stops, 1);
  EXPECT_EQ(m.stops_found, 1);
  EXPECT_NEAR(m.stop_latency_s, 0.2, 1e-9);
  // NEES: (0.1^2 + |v error|^2) / 0.01 per sample; moving: |(0.6 cos, 0.6 sin) - (0.5, 0)|^2.
  const double dv2 = std::pow(0.6 * std::cos(angle) - 0.5, 2) + std::pow(0.6 * std::sin(angle), 2);
  EXPECT_EQ(m.nees_samples, 20);
  EXPECT_NEAR(m.nees_mean, (10 * (0.01 + dv2) + 10 * 0.01) / 0.01 / 20, 1e-9);
  // 1 + dv2 / 0.01 = 2.91 and 1 are both inside [0.484, 11.143].
  EXPECT_NEAR(m.nees_in_band, 1.0, 1e-12);
  // One unbroken track over 2 s.
  EXPECT_EQ(m.segments, 1);
  EXPECT_NEAR(m.mean_segment_s, 2.0, 1e-9);
}

// A track seen 8 times (frames 0-7), gone at frame 8, started again at frame 9 and
// seen 5 times: two segments; from the fifth sighting on, frames 4-7 and 13. The
// first four sightings of each are 1 m off, the rest 0.1 m.
TEST(TrackScorer, SegmentsAndTheEstablishedPartOfEachBurst) {
  TrackScorer all, established(TrackScorer::kEstablishedSightings);
  for (int k = 0; k <= 13; ++k) {
    std::vector<TrackSample> tracks;
    const int sightings = k <= 7 ? k + 1 : k - 8;
    if (k != 8) {
      TrackSample s;
      s.landmark_id = 0;
      s.sightings = sightings;
      s.x.head<2>() = Eigen::Vector2d(sightings < 5 ? 1.0 : 0.1, 0.0);
      s.P = Eigen::Matrix4d::Identity();
      tracks.push_back(s);
    }
    all.add(kDt * k, {Eigen::Vector2d::Zero()}, {1}, tracks);
    established.add(kDt * k, {Eigen::Vector2d::Zero()}, {1}, tracks);
  }
  const TrackMetrics a = all.finish(), e = established.finish();
  EXPECT_EQ(a.samples, 13);
  EXPECT_EQ(a.segments, 2);
  EXPECT_NEAR(a.mean_segment_s, (0.7 + 0.4) / 2, 1e-9);
  EXPECT_NEAR(a.position_rms_m, std::sqrt((8 * 1.0 + 5 * 0.01) / 13), 1e-12);
  EXPECT_EQ(e.samples, 5);
  EXPECT_EQ(e.segments, 2);
  EXPECT_NEAR(e.mean_segment_s, (0.3 + 0.0) / 2, 1e-9);
  EXPECT_NEAR(e.position_rms_m, 0.1, 1e-12);
  EXPECT_TRUE(tracks_json(established.finish())["speed_rms_mps"].is_null());
  EXPECT_EQ(tracks_json(e)["segments"], 2);
}

TEST(TrackScorer, AStopNotFoundBeforeTheTrackEndsCountsUnfound) {
  TrackScorer scorer;
  for (int k = 0; k <= 14; ++k) {
    std::vector<Eigen::Vector2d> truth{truth_at(k)};
    std::vector<std::uint8_t> present{1};
    std::vector<TrackSample> tracks;
    if (k <= 12) {  // the track ends at frame 12, never having found the stop
      TrackSample s;
      s.landmark_id = 0;
      s.x.head<2>() = truth_at(k);
      s.P = Eigen::Matrix4d::Identity();
      tracks.push_back(s);
    }
    scorer.add(kDt * k, truth, present, tracks);
  }
  const TrackMetrics m = scorer.finish();
  EXPECT_EQ(m.stops, 1);
  EXPECT_EQ(m.stops_found, 0);
  EXPECT_EQ(m.stop_latency_s, 0.0);
  EXPECT_EQ(m.stopped_verdicts, 0);
  const nlohmann::json j = tracks_json(m);
  EXPECT_TRUE(j["stop_latency_s"].is_null());
  EXPECT_TRUE(j["stop_precision"].is_null());
  EXPECT_FALSE(j["position_rms_m"].is_null());
  EXPECT_EQ(j["stops"], 1);
}

TEST(TrackScorer, NothingTrackedGivesNullFigures) {
  TrackScorer scorer;
  scorer.add(0.0, {Eigen::Vector2d::Zero()}, {1}, {});
  const nlohmann::json j = tracks_json(scorer.finish());
  EXPECT_EQ(j["samples"], 0);
  for (const char* key : {"position_rms_m", "speed_rms_mps", "heading_rms_deg", "stop_latency_s", "nees_mean"})
    EXPECT_TRUE(j[key].is_null()) << key;
}

}  // namespace
}  // namespace elaslam

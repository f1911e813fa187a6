// SPDX-License-Identifier: Apache-2.0
// Mover kinds (scenario.movers): constant-velocity movers keep their direction
// and speed until they bounce, stop-and-go movers alternate stretches of the
// configured lengths, the kinds go in turn over the moving set, the velocity and
// standing-still the world reports are the true ones, and the default is the
// paper's oscillating motion, unchanged.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "elaslam/simulator/scenario.hpp"
#include "elaslam/simulator/world.hpp"
#include "sim_test_util.hpp"

namespace elaslam::sim {
namespace {

using test::run_bytes;

// config/paper.yaml with `dynamism` % of the landmarks moving at `speed`, of `kinds`.
ScenarioOptions with_kinds(std::vector<MotionKind> kinds, double dynamism = 50.0, double speed = 0.5) {
  ScenarioOptions o = test::paper();
  o.dynamism_percent = dynamism;
  o.landmark_speed_mps = speed;
  o.movers.kinds = std::move(kinds);
  return o;
}

// Every landmark's position at every frame, [frame][id].
std::vector<std::vector<Eigen::Vector2d>> trajectories(const ScenarioOptions& o) {
  World w(o);
  std::vector<std::vector<Eigen::Vector2d>> out{w.landmark_positions()};
  for (int k = 1; k < o.frames; ++k) {
    w.step();
    out.push_back(w.landmark_positions());
  }
  return out;
}

// Lengths of the runs of equal values in `v`, in order: {true, true, false} -> {2, 1}.
std::vector<int> run_lengths(const std::vector<bool>& v) {
  std::vector<int> out;
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (i == 0 || v[i] != v[i - 1]) out.push_back(0);
    ++out.back();
  }
  return out;
}

// Steps `w` to frame frames - 1 and calls each(k, i, d) for every landmark i after
// step k, d its displacement in that step.
template <typename Each>
void for_each_displacement(World& w, int frames, Each each) {
  for (int k = 1; k < frames; ++k) {
    const auto before = w.landmark_positions();
    w.step();
    const auto& p = w.landmark_positions();
    for (int i = 0; i < w.num_landmarks(); ++i) {
      const auto u = static_cast<std::size_t>(i);
      each(k, i, Eigen::Vector2d(p[u] - before[u]));
    }
  }
}

TEST(SimMovers, ConstantVelocityMoversKeepDirectionAndSpeedUntilTheyBounce) {
  // GIVEN every mover of constant velocity, fast enough to reach a border in the run
  ScenarioOptions o = with_kinds({MotionKind::kConstantVelocity}, 50.0, 0.9);
  o.frames = 400;
  World w(o);
  const double step = o.landmark_speed_mps / o.rate_hz;
  const auto p0 = w.landmark_positions();
  std::vector<Eigen::Vector2d> dir0;
  for (int i = 0; i < w.num_landmarks(); ++i) dir0.push_back(w.direction(i));
  std::vector<bool> bounced(p0.size(), false);
  int unbounced_steps = 0, bounces = 0, reversal_frames_crossed = 0;
  for (int k = 1; k < o.frames; ++k) {
    std::vector<Eigen::Vector2d> dir_before;
    for (int i = 0; i < w.num_landmarks(); ++i) dir_before.push_back(w.direction(i));
    const auto before = w.landmark_positions();
    w.step();
    const auto& p = w.landmark_positions();
    for (int i = 0; i < w.num_landmarks(); ++i) {
      const auto u = static_cast<std::size_t>(i);
      if (!w.is_moving(i)) continue;
      ASSERT_EQ(w.kind(i), MotionKind::kConstantVelocity);
      if (w.reflected_last_step(i)) {
        bounced[u] = true;
        ++bounces;
        continue;
      }
      // THEN each step is speed / rate along the direction it had, which it keeps,
      // reversal frames included (an oscillating mover would turn round there)
      EXPECT_NEAR((p[u] - before[u] - step * dir_before[u]).norm(), 0.0, 1e-9) << "landmark " << i << " frame " << k;
      EXPECT_EQ(w.direction(i), dir_before[u]) << "landmark " << i << " frame " << k;
      reversal_frames_crossed += (k - 1) > 0 && (k - 1) % o.reversal_period_frames == 0 ? 1 : 0;
      // AND until its first bounce it is k steps from where it started, on a line
      if (!bounced[u]) {
        EXPECT_NEAR((p[u] - (p0[u] + k * step * dir0[u])).norm(), 0.0, 1e-9) << "landmark " << i << " frame " << k;
        ++unbounced_steps;
      }
    }
  }
  EXPECT_GT(unbounced_steps, 1000);
  EXPECT_GT(reversal_frames_crossed, 100);
  // AND they cross the world: every one has bounced off a border by frame 399 (36 m at 0.9 m/s)
  EXPECT_GT(bounces, 0);
  for (int i = 0; i < w.num_landmarks(); ++i)
    EXPECT_TRUE(!w.is_moving(i) || bounced[static_cast<std::size_t>(i)]) << "landmark " << i << " never bounced";
}

TEST(SimMovers, StopAndGoMoversAlternateStretchesOfTheConfiguredLengths) {
  // GIVEN stop-and-go movers that move 1.2 s and stand 0.7 s: 12 and 7 frames at 10 Hz
  ScenarioOptions o = with_kinds({MotionKind::kStopAndGo}, 50.0, 0.5);
  o.movers.stop_and_go = {1.2, 0.7};
  ASSERT_EQ(o.stop_and_go_move_frames(), 12);
  ASSERT_EQ(o.stop_and_go_stop_frames(), 7);
  World w(o);
  const double step = o.landmark_speed_mps / o.rate_hz;
  const auto n = static_cast<std::size_t>(w.num_landmarks());
  std::vector<std::vector<bool>> moved(n);  // per landmark, per step: did it move
  std::vector<bool> first_step_still(n);
  for (std::size_t u = 0; u < n; ++u) first_step_still[u] = w.standing_still(static_cast<int>(u));
  for_each_displacement(w, o.frames, [&](int k, int i, const Eigen::Vector2d& displacement) {
    const double d = displacement.norm();
    if (!w.is_moving(i)) {
      EXPECT_EQ(d, 0.0);
      return;
    }
    // THEN a step is either no displacement at all or speed / rate (bounces aside)
    EXPECT_EQ(w.standing_still(i), d == 0.0) << "landmark " << i << " frame " << k;
    if (d != 0.0 && !w.reflected_last_step(i)) {
      EXPECT_NEAR(d, step, 1e-9) << "landmark " << i << " frame " << k;
    }
    moved[static_cast<std::size_t>(i)].push_back(d != 0.0);
  });
  // AND the stretches between the first and the last are 12 moving, 7 standing, to the frame
  std::set<int> first_stretches;
  int movers = 0, inner_stretches = 0;
  for (std::size_t u = 0; u < n; ++u) {
    if (!w.is_moving(static_cast<int>(u))) continue;
    ++movers;
    const std::vector<int> runs = run_lengths(moved[u]);
    ASSERT_GE(runs.size(), 3u) << "landmark " << u;  // 149 steps span 7 cycles of 19
    bool moving = moved[u][0];
    EXPECT_EQ(first_step_still[u], !moving) << "landmark " << u << ": frame 0 says the first step wrong";
    for (std::size_t r = 0; r < runs.size(); ++r, moving = !moving) {
      const int expected = moving ? 12 : 7;
      if (r == 0 || r + 1 == runs.size())
        EXPECT_LE(runs[r], expected) << "landmark " << u << " stretch " << r;
      else {
        EXPECT_EQ(runs[r], expected) << "landmark " << u << " stretch " << r << (moving ? " (moving)" : " (still)");
        ++inner_stretches;
      }
    }
    first_stretches.insert(moved[u][0] ? runs[0] : 12 + runs[0]);  // where in the cycle it started
  }
  EXPECT_EQ(movers, 36);
  EXPECT_GT(inner_stretches, 36 * 10);
  // AND the movers start at different points of the cycle (their phases are drawn)
  EXPECT_GT(first_stretches.size(), 5u);
}

TEST(SimMovers, KindsAreTakenInTurnOverTheMovingSetInIdOrder) {
  const std::vector<MotionKind> kinds = {MotionKind::kOscillating, MotionKind::kConstantVelocity,
                                         MotionKind::kStopAndGo, MotionKind::kConstantVelocity};
  World mixed(with_kinds(kinds));
  World paper(with_kinds({MotionKind::kOscillating}));
  std::map<MotionKind, int> count;
  int j = 0;
  for (int i = 0; i < mixed.num_landmarks(); ++i) {
    // The moving set is the one the default picks: the kinds do not change it.
    ASSERT_EQ(mixed.is_moving(i), paper.is_moving(i)) << i;
    if (!mixed.is_moving(i)) {
      EXPECT_EQ(mixed.kind(i), MotionKind::kStatic) << i;
      EXPECT_TRUE(mixed.standing_still(i)) << i;
      continue;
    }
    EXPECT_EQ(mixed.kind(i), kinds[static_cast<std::size_t>(j % 4)]) << "landmark " << i << ", mover " << j;
    EXPECT_EQ(paper.kind(i), MotionKind::kOscillating) << i;
    ++count[mixed.kind(i)];
    ++j;
  }
  EXPECT_EQ(j, 36);
  EXPECT_EQ(count[MotionKind::kOscillating], 9);
  EXPECT_EQ(count[MotionKind::kConstantVelocity], 18);
  EXPECT_EQ(count[MotionKind::kStopAndGo], 9);
}

TEST(SimMovers, ReportedVelocityIsThePositionDifferenceOverTheStep) {
  ScenarioOptions o = with_kinds({MotionKind::kOscillating, MotionKind::kConstantVelocity, MotionKind::kStopAndGo},
                                 80.0, 0.9);
  o.movers.stop_and_go = {1.0, 0.5};
  World w(o);
  const double speed = o.landmark_speed_mps;
  // Frame 0: the velocity each starts with.
  for (int i = 0; i < w.num_landmarks(); ++i) {
    if (!w.is_moving(i) || w.standing_still(i)) {
      EXPECT_EQ(w.velocity(i), Eigen::Vector2d::Zero()) << i;
      EXPECT_TRUE(!w.is_moving(i) || w.kind(i) == MotionKind::kStopAndGo) << i;
    } else {
      EXPECT_NEAR((w.velocity(i) - speed * w.direction(i)).norm(), 0.0, 1e-12) << i;
    }
  }
  int still = 0, full_speed = 0, bounced = 0;
  for_each_displacement(w, o.frames, [&](int k, int i, const Eigen::Vector2d& diff) {
    // THEN velocity x dt is the step's displacement, bounces included
    EXPECT_NEAR((w.velocity(i) / o.rate_hz - diff).norm(), 0.0, 1e-12) << "landmark " << i << " frame " << k;
    EXPECT_EQ(w.standing_still(i), w.velocity(i).isZero(0.0)) << "landmark " << i << " frame " << k;
    if (w.standing_still(i)) {
      ++still;
    } else if (w.reflected_last_step(i)) {
      EXPECT_LT(w.velocity(i).norm(), speed + 1e-9);
      ++bounced;
    } else {
      EXPECT_NEAR(w.velocity(i).norm(), speed, 1e-9) << "landmark " << i << " frame " << k;
      EXPECT_NEAR((w.velocity(i) - speed * w.direction(i)).norm(), 0.0, 1e-9) << i;
      ++full_speed;
    }
  });
  EXPECT_GT(still, 0);
  EXPECT_GT(full_speed, 0);
  EXPECT_GT(bounced, 0);
}

TEST(SimMovers, TheDefaultIsTheOscillatingMotionUnchanged) {
  // GIVEN config/paper.yaml as it is (no movers section) and with the oscillating
  // kind given explicitly (and unused stop-and-go stretches)
  const std::string text = test::read_text(test::paper_yaml_path());
  const std::string anchor = "  reversal_period_frames: 20\n";
  ASSERT_NE(text.find(anchor), std::string::npos);
  auto with_movers = [&](const std::string& movers) {
    std::string t = text;
    t.replace(t.find(anchor), anchor.size(), anchor + movers);
    return load_scenario_text(t, "paper.yaml with movers");
  };
  const ScenarioOptions by_default = test::paper();
  const ScenarioOptions given = with_movers("  movers: {kinds: [oscillating]}\n");
  const ScenarioOptions given_with_unused =
      with_movers("  movers: {kinds: [oscillating], stop_and_go: {move_s: 0.4, stop_s: 9.0}}\n");
  ASSERT_EQ(by_default.movers.kinds, std::vector<MotionKind>{MotionKind::kOscillating});
  // THEN every landmark is at the same place at every frame, and every message is the same
  const auto expected = trajectories(given);
  EXPECT_EQ(trajectories(by_default), expected);
  EXPECT_EQ(trajectories(given_with_unused), expected);
  EXPECT_EQ(run_bytes(by_default), run_bytes(given));
  // AND the oscillating movers of a mixed scenario move as they do alone (no
  // random stream the default draws from is shifted), while the others differ
  const ScenarioOptions mixed =
      with_movers("  movers: {kinds: [oscillating, constant_velocity, stop_and_go]}\n");
  const auto mixed_paths = trajectories(mixed);
  World w(mixed);
  int same = 0, different = 0;
  for (int i = 0; i < w.num_landmarks(); ++i) {
    bool equal = true;
    for (std::size_t k = 0; k < expected.size(); ++k)
      equal = equal && mixed_paths[k][static_cast<std::size_t>(i)] == expected[k][static_cast<std::size_t>(i)];
    if (w.kind(i) == MotionKind::kOscillating || w.kind(i) == MotionKind::kStatic) {
      EXPECT_TRUE(equal) << "landmark " << i << " (" << motion_kind_name(w.kind(i)) << ")";
      ++same;
    } else {
      EXPECT_FALSE(equal) << "landmark " << i << " (" << motion_kind_name(w.kind(i)) << ")";
      ++different;
    }
  }
  EXPECT_EQ(same, 36 + 12);
  EXPECT_EQ(different, 24);
}

}  // namespace
}  // namespace elaslam::sim

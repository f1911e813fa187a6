// SPDX-License-Identifier: Apache-2.0
// A robot that misses frames (a restart, a radio outage): the frames after the gap
// carry the odometer's whole motion over the gap in one increment.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "elaslam/common/geometry.hpp"
#include "elaslam/team/team_run.hpp"
#include "edited_frames.hpp"
#include "paper_team.hpp"

namespace elaslam {
namespace {

// Robot index 1's mean position error over the run [m].
double run_gap(int seed, double rate, int gap) {
  TeamConfig c = test::paper();
  c.scenario.seed = seed;
  c.scenario.rate_hz = rate;
  // Robot index 1 misses frames [from, to): it is given frame from - 1 again, which it
  // refuses as a repeat, so it next sees frame `to`.
  const int from = 64, to = from + gap;
  sensor_frame_t last{};
  test::EditedFrames frames(c.scenario, [&](int k, std::vector<sensor_frame_t>* sensors) {
    sensor_frame_t& s = (*sensors)[1];
    if (k == from - 1) last = s;
    if (k >= from && k < to) s = last;
  });
  const RunResult r = run_team(c.robot, c.main, frames);
  double sum = 0.0;
  for (std::size_t k = 0; k < r.estimated[1].size(); ++k)
    sum += std::hypot(r.estimated[1][k].pose.x - r.truth[1][k].pose.x, r.estimated[1][k].pose.y - r.truth[1][k].pose.y);
  return sum / static_cast<double>(r.estimated[1].size());
}

// Robot 2 of the paper's scenario at 20 Hz misses 2-12 frames from frame 64 (as a
// restart does: system_robot_restart misses 4-9): its mean error over the run
// stays within 1.5 times the uninterrupted run's, for six seeds. Before, seed 3
// with 9 or 12 frames missed ended at 3.0 and 2.9 times: the movers had gone
// on during the gap, and in the first frame after it eq 16 set aside the three
// static landmarks in view and kept two movers (ElaGate::judge_eq16).
TEST(FrameGap, AFewFramesMissedCostLittle) {
  for (int seed = 1; seed <= 6; ++seed) {
    const double uninterrupted = run_gap(seed, 20.0, 0);
    for (int gap : {2, 4, 6, 7, 9, 12}) {
      const double error = run_gap(seed, 20.0, gap);
      EXPECT_LT(error, 1.5 * uninterrupted)
          << "seed " << seed << ", " << gap << " frames missed: " << error << " m against " << uninterrupted;
    }
  }
}

}  // namespace
}  // namespace elaslam

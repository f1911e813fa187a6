// SPDX-License-Identifier: Apache-2.0
// The viewer's work per pushed state (docs/benchmarks.md): ViewState::to_json for a
// team of R robots with full trails (500 poses each, and as many ground-truth poses)
// and L landmarks, the JSON the page gets 20 times a second. Run: build/bin/bench_viewer
#include <cmath>
#include <string>

#include <benchmark/benchmark.h>

#include "elaslam/viewer/view_state.hpp"

namespace {

using elaslam::viewer::ViewState;

ViewState team(int robots, int landmarks) {
  ViewState v;
  for (int f = 0; f < 500; ++f) {
    for (int r = 1; r <= robots; ++r) {
      elaslam::pose_estimate_t p{};
      p.robot_id = static_cast<std::int16_t>(r);
      p.frame = f;
      p.x = r + std::cos(0.01 * f), p.y = std::sin(0.01 * f), p.theta = 0.01 * f;
      p.cov[0][0] = p.cov[1][1] = 1e-3;
      v.on_pose(p);
    }
    elaslam::ground_truth_t g{};
    g.frame = f;
    g.num_robots = static_cast<std::int16_t>(robots);
    g.robot_ids.resize(static_cast<std::size_t>(robots));
    g.robots.resize(static_cast<std::size_t>(robots));
    for (int r = 0; r < robots; ++r) g.robot_ids[r] = static_cast<std::int16_t>(r + 1), g.robots[r].x = r;
    g.num_landmarks = static_cast<std::int16_t>(landmarks);
    g.landmarks.resize(static_cast<std::size_t>(landmarks));
    for (int k = 0; k < landmarks; ++k) g.landmarks[k].id = k, g.landmarks[k].x = k;
    v.on_truth(g);
  }
  elaslam::global_map_t m{};
  m.frame = 499, m.num_chunks = 1, m.id_begin = 0, m.id_end = 256;
  for (int k = 0; k < landmarks; ++k) {
    elaslam::global_landmark_t l{};
    l.id = k, l.x = k * 0.5, l.y = -k * 0.5;
    l.cov[0][0] = l.cov[1][1] = 1e-3;
    l.contributors = 3;
    l.status = elaslam::global_landmark_t::STATIC;
    m.landmarks.push_back(l);
  }
  m.num_landmarks = static_cast<std::int16_t>(landmarks);
  v.on_global_map(m);
  return v;
}

void BM_ToJson(benchmark::State& st) {
  const ViewState v = team(static_cast<int>(st.range(0)), static_cast<int>(st.range(1)));
  std::size_t bytes = 0;
  for (auto _ : st) {
    const std::string j = v.to_json(0.0, "{}");
    bytes = j.size();
    benchmark::DoNotOptimize(j.data());
  }
  st.counters["json_bytes"] = static_cast<double>(bytes);
}
BENCHMARK(BM_ToJson)->Args({3, 72})->Args({5, 20})->Args({8, 256})->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();

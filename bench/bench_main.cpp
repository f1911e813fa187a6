// SPDX-License-Identifier: Apache-2.0
// main_robot's cost per team frame against the team's size and the world's:
// every robot's frame brings its LMAP_EVENTs (UPDATEs of landmarks in
// its view) and its POSE; when all R poses of a frame are in, main_robot fills the
// frame's GLOBAL_MAP (every static landmark, in datagram-sized chunks) and encodes
// it as LCM would. The map holds N landmarks, each held by two robots (one when the
// team has one), as a team that has mapped its world.
//   build/bin/bench_main --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// Counters: map_bytes is one GLOBAL_MAP publication (all chunks, LCM payload), what
// goes out every frame. Results: docs/benchmarks.md, "Scale".
#include <cstdint>
#include <vector>

#include <benchmark/benchmark.h>

#include "../tests/support/messages.hpp"
#include "elaslam/main_robot/main_node.hpp"

namespace elaslam {
namespace {

constexpr int kEventsPerRobotFrame = 3;  // UPDATEs: ~12 in view, one per landmark per 5 frames

landmark_event_t event(int robot, std::int64_t seq, int kind, int id, int frame) {
  return test::event_msg(robot, seq, kind, id, frame, 0.5 * id, -0.25 * id);
}

void BM_MainFrame(benchmark::State& state) {
  const int R = static_cast<int>(state.range(0));
  const int N = static_cast<int>(state.range(1));
  GlobalMapOptions o;
  o.max_landmark_id = N;
  MainNode main(o);
  std::vector<std::int64_t> seq(static_cast<std::size_t>(R) + 1, 0);
  for (int id = 0; id < N; ++id)
    for (int h = 0; h < (R > 1 ? 2 : 1); ++h) {
      const int r = (id + h) % R + 1;
      main.on_event(event(r, ++seq[static_cast<std::size_t>(r)], landmark_event_t::ADD, id, 0));
    }
  // Per frame, robot r updates kEventsPerRobotFrame landmarks of its share of the map.
  std::vector<std::uint8_t> buf(64 * 1024);
  int frame = 0;
  std::int64_t bytes = 0;
  for (auto _ : state) {
    ++frame;
    for (int r = 1; r <= R; ++r) {
      for (int k = 0; k < kEventsPerRobotFrame; ++k) {
        const int id = ((r - 1) * N / R + (frame * kEventsPerRobotFrame + k)) % N;
        main.on_event(event(r, ++seq[static_cast<std::size_t>(r)], landmark_event_t::UPDATE, id, frame));
      }
      main.on_pose(test::pose_msg(r, frame));
    }
    const int chunks = main.make_global_map(0, frame);
    bytes = 0;
    for (int c = 0; c < chunks; ++c) {
      const global_map_t& m = main.map_chunk(c);
      const int n = m.encode(buf.data(), 0, static_cast<int>(buf.size()));
      benchmark::DoNotOptimize(n);
      bytes += n;
    }
  }
  state.counters["map_bytes"] = static_cast<double>(bytes);
  state.counters["events_per_frame"] = R * kEventsPerRobotFrame;
}

void team_and_world(benchmark::internal::Benchmark* b) {
  for (const int r : {1, 2, 4, 8, 16}) b->Args({r, 1024});  // robots, at the large world's size
  for (const int n : {72, 256, 4096}) b->Args({16, n});      // global landmarks, 16 robots (and 1,024 above)
  b->ArgNames({"robots", "landmarks"})->Unit(benchmark::kMicrosecond);
}

BENCHMARK(BM_MainFrame)->Apply(team_and_world);

}  // namespace
}  // namespace elaslam

BENCHMARK_MAIN();

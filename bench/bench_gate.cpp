// SPDX-License-Identifier: Apache-2.0
// The ELA gate's cost per frame against the number of mapped landmarks in view
// ElaGate::judge_view, modes ela (eq 16 for every landmark, the
// worst set aside and the rest re-tested) and consensus (pair tests, the cliques
// with their joint prior test, eq 16 re-tests), with every landmark static (one
// pass) and with a quarter of them displaced (set-aside passes).
//   build/bin/bench_gate --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// Results: docs/benchmarks.md.
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <benchmark/benchmark.h>

#include "elaslam/robot_node/ela_gate.hpp"
#include "elaslam/robot_node/lmap.hpp"

namespace elaslam {
namespace {

RobotOptions gate_options(Mode mode, int n) {
  RobotOptions o;
  o.mode = mode;
  o.ekf.capacity = n;
  o.ekf.max_landmark_id = n;
  o.ekf.range_sigma = 0.05;
  o.ekf.bearing_sigma = 0.01;
  return o;
}

// A robot at the origin that has mapped n landmarks on a ring of 4 m under 2 deg of
// heading uncertainty, then observes them (noisy); `moved` of them displaced 0.5 m.
struct Scene {
  Scene(int n, int moved, const RobotOptions& o) : ekf(o.ekf) {
    ekf.reset(Pose2{}, Eigen::Vector3d(1e-4, 1e-4, std::pow(2.0 * kPi / 180.0, 2)).asDiagonal());
    std::mt19937_64 rng(7);
    std::normal_distribution<double> n01;
    for (int i = 0; i < n; ++i) {
      const double a = 2.0 * kPi * i / n + 0.1;
      const Eigen::Vector2d l(4.0 * std::cos(a), 4.0 * std::sin(a));
      ekf.add_landmark(i, observe(Pose2{}, l));
      Eigen::Vector2d seen = l;
      if (i % 4 == 0 && i / 4 < moved) seen += Eigen::Vector2d(0.5, -0.3);
      RangeBearing z = observe(Pose2{}, seen);
      z.range += 0.05 * n01(rng);
      z.bearing += 0.01 * n01(rng);
      view.push_back(z);
    }
    ekf.predict(Pose2{0.1, 0.0, 0.0}, Eigen::Vector3d(1e-3, 1e-3, 1e-4).asDiagonal());
  }
  EkfSlam ekf;
  std::vector<RangeBearing> view;
};

void run_gate(benchmark::State& state, Mode mode, bool movers) {
  const int n = static_cast<int>(state.range(0));
  const RobotOptions o = gate_options(mode, n);
  const Scene scene(n, movers ? n / 4 : 0, o);
  ElaGate gate(o);
  LMap lmap(n);
  for (auto _ : state) {
    gate.clear();
    for (int i = 0; i < n; ++i) gate.add_to_view(i, scene.view[static_cast<std::size_t>(i)]);
    gate.judge_view(scene.ekf, &lmap);
    benchmark::DoNotOptimize(gate.verdict(0));
  }
}

void BM_GateEq16AllStatic(benchmark::State& s) { run_gate(s, Mode::kEla, false); }
void BM_GateEq16QuarterMoved(benchmark::State& s) { run_gate(s, Mode::kEla, true); }
void BM_GateConsensusAllStatic(benchmark::State& s) { run_gate(s, Mode::kConsensus, false); }
void BM_GateConsensusQuarterMoved(benchmark::State& s) { run_gate(s, Mode::kConsensus, true); }

void in_view(benchmark::internal::Benchmark* b) {
  for (const int n : {5, 15, 40, 64}) b->Arg(n);
  b->ArgName("in_view")->Unit(benchmark::kMicrosecond);
}

BENCHMARK(BM_GateEq16AllStatic)->Apply(in_view);
BENCHMARK(BM_GateEq16QuarterMoved)->Apply(in_view);
BENCHMARK(BM_GateConsensusAllStatic)->Apply(in_view);
BENCHMARK(BM_GateConsensusQuarterMoved)->Apply(in_view);

}  // namespace
}  // namespace elaslam

BENCHMARK_MAIN();

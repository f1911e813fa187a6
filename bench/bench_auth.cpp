// SPDX-License-Identifier: Apache-2.0
// Message authentication's cost per message (docs/security.md "Cost"): seal (the
// trailer, SHA-512 over channel name, payload and header, an Ed25519 signature) and
// open (the key looked up by sender and key id, the signature verified, the sender
// binding, the mission, the replay window) at 100 B, 420 B (a typical SENSOR frame,
// about 15 observations) and 1,200 B (the largest state-repair chunk); and what a
// flood costs a receiver: a datagram signed with a key the roster does not hold
// (refused at the lookup) and one that names a real key with a bad signature
// (refused after the verification).
//   build/bin/bench_auth [--benchmark_repetitions=5 --benchmark_report_aggregates_only=true]
#include <benchmark/benchmark.h>

#include <array>
#include <cstring>
#include <vector>

#include "../tests/support/test_keys.hpp"
#include "elaslam/transport/auth_transport.hpp"

namespace {

using namespace elaslam::transport;
using namespace elaslam::transport::auth;
using elaslam::test::team_setup;

void BM_Seal(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  Authenticator sim(team_setup(kSenderSimulator, 1));
  const std::string channel = "SENSOR_1";
  std::vector<std::uint8_t> buf(n + kTrailerBytes, 0x5a);
  for (auto _ : state) benchmark::DoNotOptimize(sim.seal(channel, buf.data(), n));
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(n));
}

// Each iteration opens a message not seen before (a real stream: the window slides).
void BM_Open(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  Authenticator sim(team_setup(kSenderSimulator, 1));
  Authenticator robot(team_setup(1, 2));
  const std::string channel = "SENSOR_1";
  constexpr int kPool = 4096;
  std::vector<std::vector<std::uint8_t>> pool;
  auto refill = [&] {
    pool.clear();
    for (int i = 0; i < kPool; ++i) {
      std::vector<std::uint8_t> buf(n + kTrailerBytes, static_cast<std::uint8_t>(i));
      sim.seal(channel, buf.data(), n);
      pool.push_back(std::move(buf));
    }
  };
  refill();
  int i = 0;
  std::size_t payload = 0;
  Sender who;
  for (auto _ : state) {
    if (i == kPool) {
      state.PauseTiming();
      refill();
      i = 0;
      state.ResumeTiming();
    }
    const auto& m = pool[static_cast<std::size_t>(i++)];
    if (robot.open(channel, m.data(), m.size(), &payload, &who) != Verdict::kAccepted) state.SkipWithError("refused");
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(n));
}

/// A message the simulator signed, with `flip` applied to it.
std::vector<std::uint8_t> signed_then(std::size_t n, void (*flip)(std::vector<std::uint8_t>*, std::size_t)) {
  Authenticator sim(team_setup(kSenderSimulator, 1));
  std::vector<std::uint8_t> m(n + kTrailerBytes, 0x33);
  sim.seal("SENSOR_1", m.data(), n);
  flip(&m, n);
  return m;
}

// A flood of datagrams naming a key the roster does not hold: refused at the lookup.
void BM_OpenUnknownKey(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  Authenticator robot(team_setup(1, 2));
  const auto m = signed_then(n, [](std::vector<std::uint8_t>* b, std::size_t at) { (*b)[at + 6] ^= 0xff; });
  std::size_t payload = 0;
  Sender who;
  for (auto _ : state) benchmark::DoNotOptimize(robot.open("SENSOR_1", m.data(), m.size(), &payload, &who));
}

// A flood naming the simulator's real key with a signature that does not verify: the
// costliest refusal (a whole verification).
void BM_OpenForged(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  Authenticator robot(team_setup(1, 2));
  const auto m = signed_then(n, [](std::vector<std::uint8_t>* b, std::size_t) { (*b)[0] ^= 0x01; });
  std::size_t payload = 0;
  Sender who;
  for (auto _ : state) benchmark::DoNotOptimize(robot.open("SENSOR_1", m.data(), m.size(), &payload, &who));
}

}  // namespace

BENCHMARK(BM_Seal)->Arg(100)->Arg(420)->Arg(1200);
BENCHMARK(BM_Open)->Arg(100)->Arg(420)->Arg(1200);
BENCHMARK(BM_OpenUnknownKey)->Arg(420);
BENCHMARK(BM_OpenForged)->Arg(100)->Arg(420)->Arg(1200);
BENCHMARK_MAIN();

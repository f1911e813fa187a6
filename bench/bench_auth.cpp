// Message authentication's cost per message (docs/security.md): seal (trailer and
// HMAC-SHA-512-256 over channel name, payload and trailer header) and open (verify
// in constant time, replay window, sender binding) at 100 B, 420 B (a typical
// SENSOR frame, about 15 observations) and 1,200 B (the largest state-repair chunk).
//   build/bin/bench_auth [--benchmark_repetitions=5 --benchmark_report_aggregates_only=true]
#include <benchmark/benchmark.h>

#include <array>
#include <vector>

#include "elaslam/transport/auth_transport.hpp"

namespace {

using namespace elaslam::transport;
using namespace elaslam::transport::auth;

TeamKey bench_key() {
  std::array<std::uint8_t, TeamKey::kBytes> b{};
  for (std::size_t i = 0; i < b.size(); ++i) b[i] = static_cast<std::uint8_t>(5 * i + 3);
  return TeamKey(b);
}

void BM_Seal(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  Authenticator sim(bench_key(), kSenderSimulator, 1);
  const std::string channel = "SENSOR_1";
  std::vector<std::uint8_t> buf(n + kTrailerBytes, 0x5a);
  for (auto _ : state) benchmark::DoNotOptimize(sim.seal(channel, buf.data(), n));
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(n));
}

// Each iteration opens a message not seen before (a real stream: the window slides).
void BM_Open(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  const TeamKey key = bench_key();
  Authenticator sim(key, kSenderSimulator, 1);
  Authenticator robot(key, 1, 2);
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

// A forged message (bad MAC): what a flood of them costs a receiver.
void BM_OpenForged(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  Authenticator robot(bench_key(), 1, 2);
  std::vector<std::uint8_t> m(n + kTrailerBytes, 0x33);
  std::copy(kMagic, kMagic + kMagicBytes, m.begin() + static_cast<std::ptrdiff_t>(n));
  const std::string channel = "SENSOR_1";
  std::size_t payload = 0;
  Sender who;
  for (auto _ : state) benchmark::DoNotOptimize(robot.open(channel, m.data(), m.size(), &payload, &who));
}

}  // namespace

BENCHMARK(BM_Seal)->Arg(100)->Arg(420)->Arg(1200);
BENCHMARK(BM_Open)->Arg(100)->Arg(420)->Arg(1200);
BENCHMARK(BM_OpenForged)->Arg(100)->Arg(420)->Arg(1200);
BENCHMARK_MAIN();

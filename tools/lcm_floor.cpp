// SPDX-License-Identifier: Apache-2.0
// lcm_floor: LCM's own one-way latency on this machine at a given message rate, the
// floor under the team's sensor-to-pose latency (docs/benchmarks.md
// "Latency and LCM's floor"). Two processes (this one forks): a receiver subscribes,
// a sender publishes --count messages of --size bytes at --rate on udpm, each
// carrying its send time (CLOCK_MONOTONIC, one clock for both); the receiver takes
// the difference at its handler: send, loopback, LCM's receive thread, its hand-over
// to the handling thread, the handler, as every node's message goes. The rate
// matters: at 100 Hz the cores idle between messages and every hop pays a wake-up
// that a busy machine does not. Run it where the team runs (tools/latency.sh runs it
// in a network namespace of its own before each rate).
//   lcm_floor [--rate HZ] [--count N] [--size BYTES] [--lcm-url URL]
// Prints one line: rate, size, messages received / sent, one-way p50 / p90 / p99 /
// max [us]. Exit status: 0, 1 when nothing arrived or LCM failed, 2 for a bad
// command line. The payload and the figures are common/latency_floor.hpp's.
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include "elaslam/common/cli.hpp"
#include "elaslam/common/latency_floor.hpp"

namespace {

constexpr const char* kChannel = "ELASLAM_LCM_FLOOR";
using elaslam::latency_floor::kWarmup;

std::int64_t mono_ns() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
}

struct Options {
  double rate = 100.0;
  int count = 2000;
  int size = 200;
  std::string url;
};

struct Receiver {
  elaslam::latency_floor::Delays d;
  void on_message(const lcm::ReceiveBuffer* rb, const std::string&) { d.on_message(rb->data, rb->data_size, mono_ns()); }
};

int receive(const Options& o, int ready_fd) {
  lcm::LCM lc(o.url);
  if (!lc.good()) {
    std::fprintf(stderr, "lcm_floor: LCM did not start on '%s'\n", o.url.c_str());
    return 1;
  }
  Receiver r{elaslam::latency_floor::Delays(o.count)};
  lc.subscribe(kChannel, &Receiver::on_message, &r)->setQueueCapacity(0);
  const char one = 1;
  if (::write(ready_fd, &one, 1) != 1) return 1;
  ::close(ready_fd);
  // Until the last message, or a second past when it was due.
  const std::int64_t total = kWarmup + o.count;
  const std::int64_t deadline = mono_ns() + static_cast<std::int64_t>((static_cast<double>(total) / o.rate + 2.0) * 1e9);
  while (r.d.last_seq() < total - 1 && mono_ns() < deadline) lc.handleTimeout(100);
  if (r.d.empty()) {
    std::fprintf(stderr, "lcm_floor: no message arrived (multicast on this interface? see LCM.md)\n");
    return 1;
  }
  std::fputs(elaslam::latency_floor::floor_line(o.rate, o.size, o.count, r.d).c_str(), stdout);
  return 0;
}

int send(const Options& o) {
  lcm::LCM lc(o.url);
  if (!lc.good()) {
    std::fprintf(stderr, "lcm_floor: LCM did not start on '%s'\n", o.url.c_str());
    return 1;
  }
  std::vector<char> buf(static_cast<std::size_t>(o.size), 0);
  const auto period = static_cast<std::int64_t>(1e9 / o.rate);
  timespec next{};
  clock_gettime(CLOCK_MONOTONIC, &next);
  for (std::int64_t seq = 0; seq < kWarmup + o.count; ++seq) {
    std::int64_t t = static_cast<std::int64_t>(next.tv_sec) * 1'000'000'000 + next.tv_nsec + period;
    next.tv_sec = static_cast<time_t>(t / 1'000'000'000);
    next.tv_nsec = static_cast<long>(t % 1'000'000'000);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr) == EINTR) {
    }
    elaslam::latency_floor::write_payload(seq, mono_ns(), &buf);
    if (lc.publish(kChannel, buf.data(), static_cast<unsigned>(buf.size())) != 0) {
      std::fprintf(stderr, "lcm_floor: publish failed\n");
      return 1;
    }
  }
  return 0;
}

int lcm_floor_main(int argc, char** argv) {
  namespace cli = elaslam::cli;
  Options o;
  CLI::App app{"elaslam lcm_floor: LCM's one-way latency between two processes at a message rate"};
  cli::add_version_flag(app, "lcm_floor");
  app.add_option("--rate", o.rate, "messages per second")->check(cli::range(0.1, 100000.0));
  app.add_option("--count", o.count, "messages timed (after 20 not timed)")->check(cli::range(10, 10000000));
  app.add_option("--size", o.size, "message size [bytes]")->check(cli::range(16, 60000));
  app.add_option("--lcm-url", o.url, "LCM URL (default: $LCM_DEFAULT_URL, else LCM's default)");
  if (const int rc = cli::parse(app, argc, argv); rc >= 0) return rc;
  int ready[2];
  if (::pipe(ready) != 0) return std::perror("lcm_floor: pipe"), 1;
  std::fflush(stdout);
  const pid_t child = ::fork();
  if (child < 0) return std::perror("lcm_floor: fork"), 1;
  if (child == 0) {
    ::close(ready[0]);
    const int rc = receive(o, ready[1]);
    std::fflush(stdout);  // _Exit flushes nothing, and must not run the parent's atexit handlers
    std::_Exit(rc);
  }
  ::close(ready[1]);
  char c = 0;
  const bool up = ::read(ready[0], &c, 1) == 1;  // the receiver subscribed (or died: 0)
  ::close(ready[0]);
  const int sent = up ? send(o) : 1;
  int status = 0;
  if (!up || sent != 0) ::kill(child, SIGTERM);
  while (::waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  if (sent != 0) return sent;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 1;
}

}  // namespace

int main(int argc, char** argv) {
  return elaslam::cli::guarded_main("lcm_floor", [&] { return lcm_floor_main(argc, argv); });
}

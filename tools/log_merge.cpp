// SPDX-License-Identifier: Apache-2.0
// log_merge: several LCM logs into one, in receive-time order: the recordings of a
// team in channel groups (one lcm-logger per group's port, tools/run_team.sh
// --channel-groups) become the one log that evaluate, log_info and lcm-logplayer read.
//   log_merge OUT IN... [--force]
// Events keep their timestamps (the recorders' receive times, one clock on one host);
// equal timestamps keep the order of the inputs on the command line; event numbers are
// renumbered from 0. An input's truncated or corrupt tail ends that input (said, and
// the merge goes on: a recorder killed mid-write loses only its last event); bytes
// between events are skipped and counted (logs/log_reader.hpp).
// Exit status: 0 merged; 2 bad arguments, an input that is not a readable LCM log, or
// OUT exists without --force; 1 when OUT cannot be written.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <queue>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include "elaslam/common/cli.hpp"
#include "elaslam/logs/log_reader.hpp"

namespace {

struct Input {
  std::unique_ptr<elaslam::LogReader> reader;
  elaslam::LogEvent event;
  std::int64_t events = 0;
};

int log_merge_main(int argc, char** argv) {
  std::string out;
  std::vector<std::string> inputs;
  bool force = false;
  CLI::App app{"elaslam log_merge: LCM logs merged into one in receive-time order"};
  elaslam::cli::add_version_flag(app, "log_merge");
  app.add_option("OUT", out, "the merged log")->required();
  app.add_option("IN", inputs, "the logs to merge (lcm-logger's format)")->required();
  app.add_flag("-f,--force", force, "overwrite OUT");
  if (const int rc = elaslam::cli::parse(app, argc, argv); rc >= 0) return rc;

  std::error_code ec;
  if (!force && std::filesystem::exists(out, ec)) {
    std::fprintf(stderr, "log_merge: %s exists (--force overwrites it)\n", out.c_str());
    return elaslam::cli::kExitBadInput;
  }
  std::vector<Input> in(inputs.size());
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    if (std::filesystem::equivalent(inputs[i], out, ec)) {
      std::fprintf(stderr, "log_merge: %s is both an input and the output\n", out.c_str());
      return elaslam::cli::kExitBadInput;
    }
    try {
      in[i].reader = std::make_unique<elaslam::LogReader>(inputs[i]);
    } catch (const std::runtime_error& e) {
      std::fprintf(stderr, "log_merge: %s\n", e.what());
      return elaslam::cli::kExitBadInput;
    }
  }

  lcm::LogFile log(out, "w");
  if (!log.good()) {
    std::fprintf(stderr, "log_merge: cannot write %s\n", out.c_str());
    return elaslam::cli::kExitFailure;
  }
  // The next event of each input, earliest first; ties in input order.
  using Head = std::tuple<std::int64_t, std::size_t>;
  std::priority_queue<Head, std::vector<Head>, std::greater<Head>> heads;
  for (std::size_t i = 0; i < in.size(); ++i)
    if (in[i].reader->next(&in[i].event)) heads.emplace(in[i].event.timestamp, i);
  std::int64_t written = 0;
  while (!heads.empty()) {
    const std::size_t i = std::get<1>(heads.top());
    heads.pop();
    Input& s = in[i];
    lcm::LogEvent ev{};
    ev.eventnum = written;
    ev.timestamp = s.event.timestamp;
    ev.channel = s.event.channel;
    ev.datalen = static_cast<int32_t>(s.event.data.size());
    ev.data = s.event.data.data();
    if (log.writeEvent(&ev) != 0) {
      std::fprintf(stderr, "log_merge: writing %s failed after %lld events\n", out.c_str(),
                   static_cast<long long>(written));
      return elaslam::cli::kExitFailure;
    }
    ++written;
    ++s.events;
    if (s.reader->next(&s.event)) heads.emplace(s.event.timestamp, i);
  }
  if (std::fflush(log.getFilePtr()) != 0) {
    std::fprintf(stderr, "log_merge: writing %s failed\n", out.c_str());
    return elaslam::cli::kExitFailure;
  }
  for (std::size_t i = 0; i < in.size(); ++i) {
    const elaslam::LogReader& r = *in[i].reader;
    if (!r.complete())
      std::fprintf(stderr, "log_merge: %s: a truncated or corrupt tail after %lld events (%lld of %lld bytes read)\n",
                   inputs[i].c_str(), static_cast<long long>(in[i].events),
                   static_cast<long long>(r.end_of_last_event()), static_cast<long long>(r.size()));
    if (r.skipped() > 0)
      std::fprintf(stderr, "log_merge: %s: %lld bytes between events skipped\n", inputs[i].c_str(),
                   static_cast<long long>(r.skipped()));
  }
  std::printf("log_merge: %lld events from %zu logs into %s\n", static_cast<long long>(written), in.size(),
              out.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return elaslam::cli::guarded_main("log_merge", [&] { return log_merge_main(argc, argv); });
}

// SPDX-License-Identifier: Apache-2.0
// record: an LCM recorder that does not die on malformed datagrams (installed as
// elaslam-record). Writes every message of one udpm:// URL (or the channels a
// regular expression matches) to an LCM log file, as lcm-logger does, each event
// stamped with its kernel receive time. lcm-logger (LCM 1.3.1) reads datagrams with
// liblcm's receive thread, which one malformed fragment from anyone on the network
// crashes (transport/udpm_receiver.hpp); this one receives through the team's
// transport, which checks every byte first. It also has no 30-message queue to
// overflow: datagrams wait in the socket's buffer (the URL's recv_buf_size).
//   record [--lcm-url URL] [-c REGEX] [-f] [-q] FILE
// Messages are recorded as they arrived, authenticated or not (evaluate and log_info
// verify a recording with the team's keys). The file is flushed every 100 ms and
// closed on SIGINT / SIGTERM (exit 0).
#include <cstdio>
#include <string>
#include <sys/stat.h>

#include <CLI/CLI.hpp>
#include <lcm/eventlog.h>

#include "elaslam/common/cli.hpp"
#include "elaslam/transport/lcm_transport.hpp"
#include "elaslam/transport/process.hpp"

namespace {

using namespace elaslam;

struct Recorder {
  lcm_eventlog_t* log = nullptr;
  std::int64_t events = 0;
  std::int64_t write_errors = 0;
  std::int64_t bytes = 0;

  static void on_message(const transport::RawMessage& m, void* self) {
    auto& r = *static_cast<Recorder*>(self);
    lcm_eventlog_event_t e{};
    e.timestamp = m.recv_utime != 0 ? m.recv_utime : transport::now_utime();
    e.channellen = static_cast<std::int32_t>(m.channel.size());
    e.datalen = static_cast<std::int32_t>(m.size);
    e.channel = const_cast<char*>(m.channel.c_str());
    e.data = const_cast<std::uint8_t*>(m.data);
    if (lcm_eventlog_write_event(r.log, &e) != 0) {
      if (r.write_errors++ == 0) std::perror("record: cannot write the log");
      return;
    }
    ++r.events;
    r.bytes += static_cast<std::int64_t>(m.size);
  }
};

int record_main(int argc, char** argv) {
  std::string url, channel = ".*", path;
  bool force = false, quiet = false;
  CLI::App app{"elaslam record: an LCM log of every message on a udpm:// URL, robust to malformed datagrams"};
  cli::add_version_flag(app, "record");
  app.add_option("-l,--lcm-url", url, "LCM URL (default: $LCM_DEFAULT_URL, else LCM's default)");
  app.add_option("-c,--channel", channel, "record the channels this regular expression matches")->capture_default_str();
  app.add_flag("-f,--force", force, "overwrite FILE if it exists");
  app.add_flag("-q,--quiet", quiet, "say nothing but errors");
  app.add_option("file", path, "the LCM log to write")->required();
  if (const int rc = cli::parse(app, argc, argv); rc >= 0) return rc;
  struct stat st {};
  if (!force && ::lstat(path.c_str(), &st) == 0) {
    std::fprintf(stderr, "record: %s exists (-f overwrites it)\n", path.c_str());
    return 2;
  }
  transport::install_stop_handlers();
  transport::LcmTransport lcm(url, "record", stderr);
  if (!lcm.good()) {
    std::fprintf(stderr, "record: cannot open LCM (%s)\n", transport::describe_url(url).c_str());
    return 1;
  }
  Recorder r;
  r.log = lcm_eventlog_create(path.c_str(), "w");
  if (r.log == nullptr) {
    std::perror(("record: cannot create " + path).c_str());
    return 1;
  }
  if (lcm.subscribe(channel, &Recorder::on_message, &r, transport::kUnboundedQueue) <= 0) {
    std::fprintf(stderr, "record: cannot subscribe to '%s' (not a regular expression, or no LCM socket)\n",
                 channel.c_str());
    lcm_eventlog_destroy(r.log);
    return channel == ".*" ? 1 : 2;
  }
  if (!quiet) std::fprintf(stderr, "record: %s -> %s\n", transport::describe_url(url).c_str(), path.c_str());
  std::int64_t flushed = transport::now_utime();
  while (!transport::stop_flag().load()) {
    if (lcm.handle_timeout(100) < 0 && !transport::stop_flag().load()) break;
    if (const std::int64_t now = transport::now_utime(); now - flushed >= 100000) {
      std::fflush(r.log->f);
      flushed = now;
    }
  }
  lcm_eventlog_destroy(r.log);  // flushes and closes
  const transport::TransportRefusals refused = lcm.refusals();
  if (!quiet || refused.malformed > 0 || r.write_errors > 0)
    std::fprintf(stderr, "record: %lld events, %lld bytes, %lld malformed datagrams refused, %lld write errors\n",
                 static_cast<long long>(r.events), static_cast<long long>(r.bytes),
                 static_cast<long long>(refused.malformed), static_cast<long long>(r.write_errors));
  return r.write_errors > 0 ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  return elaslam::cli::guarded_main("record", [&] { return record_main(argc, argv); });
}

// monitor: one line that follows a live team (frame k/N, poses received, moving
// landmarks found so far, nodes' health), for a terminal or a log.
//   monitor [--lcm-url URL] [--interval S] [--robots N]
// On a terminal the line is rewritten in place about 5 times a second; otherwise a
// line is printed every --interval seconds. SIGINT / SIGTERM end it (exit 0) with
// the final line. Reads RUN_INFO, SENSOR_*, POSE_*, GLOBAL_MAP, DYNAMIC_NOTICE and
// STATUS_ROBOT_*; decodes defensively (a bad message is counted, never fatal).
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <map>
#include <set>
#include <string>

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include "elaslam/common/cli.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/common/lcm_util.hpp"
#include "elaslam/dynamic_notice_t.hpp"
#include "elaslam/global_map_t.hpp"
#include "elaslam/node_status_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/run_info_t.hpp"
#include "elaslam/sensor_frame_t.hpp"

namespace elaslam {
namespace {

using Clock = std::chrono::steady_clock;

/// What the line shows, filled by the handlers.
class Progress {
 public:
  void subscribe(lcm::LCM& lc) {
    // Bounded queues: the monitor may fall behind, it must never grow without bound.
    subscribe_raw<Progress, &Progress::on_info>(lc, "RUN_INFO", this)->setQueueCapacity(10);
    subscribe_raw<Progress, &Progress::on_sensor>(lc, "SENSOR_[0-9]+", this)->setQueueCapacity(200);
    subscribe_raw<Progress, &Progress::on_pose>(lc, "POSE_[0-9]+", this)->setQueueCapacity(200);
    subscribe_raw<Progress, &Progress::on_map>(lc, "GLOBAL_MAP", this)->setQueueCapacity(20);
    subscribe_raw<Progress, &Progress::on_notice>(lc, "DYNAMIC_NOTICE", this)->setQueueCapacity(200);
    subscribe_raw<Progress, &Progress::on_status>(lc, "STATUS_ROBOT_[0-9]+", this)->setQueueCapacity(50);
  }

  std::string line() const {
    char buf[512];
    const std::string of = frames_ > 0 ? "/" + std::to_string(frames_) : "";
    // Frames are numbered from 0: after frame k, k + 1 are done ("frame 150/150").
    std::snprintf(buf, sizeof buf, "frame %d%s | poses %lld from %zu robot%s | moving landmarks found %zu | notices %lld",
                  frame_ + 1, of.c_str(), poses_, pose_robots_.size(), pose_robots_.size() == 1 ? "" : "s",
                  moving_.size(), notices_);
    std::string out = buf;
    if (dropped_ > 0) out += " | robots report " + std::to_string(dropped_) + " dropped frames";
    if (bad_ > 0) out += " | undecodable " + std::to_string(bad_);
    if (frame_ < 0) out = "waiting for the first frame" + std::string(frames_ > 0 ? " of " + std::to_string(frames_) : "");
    return out;
  }

 private:
  template <typename Msg>
  bool decode(const lcm::ReceiveBuffer* rb, Msg* m) {
    if (m->decode(rb->data, 0, static_cast<int>(rb->data_size)) >= 0) return true;
    ++bad_;
    return false;
  }
  void on_info(const lcm::ReceiveBuffer* rb, const std::string&) {
    run_info_t m;
    if (decode(rb, &m) && m.frames > 0) frames_ = m.frames;
  }
  void on_sensor(const lcm::ReceiveBuffer* rb, const std::string&) {
    sensor_frame_t m;
    if (decode(rb, &m) && m.frame > frame_) frame_ = m.frame;
  }
  void on_pose(const lcm::ReceiveBuffer* rb, const std::string&) {
    pose_estimate_t m;
    if (!decode(rb, &m)) return;
    ++poses_;
    pose_robots_.insert(m.robot_id);
  }
  void on_map(const lcm::ReceiveBuffer* rb, const std::string&) {
    global_map_t m;
    if (!decode(rb, &m)) return;
    for (int i = 0; i < contract::bounded(m.num_moving, contract::kMaxLandmarksPerMessage); ++i) moving_.insert(m.moving_ids[i]);
  }
  void on_notice(const lcm::ReceiveBuffer* rb, const std::string&) {
    dynamic_notice_t m;
    if (!decode(rb, &m)) return;
    ++notices_;
    moving_.insert(m.landmark_id);
  }
  void on_status(const lcm::ReceiveBuffer* rb, const std::string&) {
    node_status_t m;
    if (!decode(rb, &m)) return;
    dropped_by_robot_[m.node_id] = m.frames_dropped;
    dropped_ = 0;
    for (const auto& [id, n] : dropped_by_robot_) dropped_ += n;
  }

  int frame_ = -1, frames_ = 0;
  long long poses_ = 0, notices_ = 0, bad_ = 0, dropped_ = 0;
  std::set<int> pose_robots_, moving_;
  std::map<int, long long> dropped_by_robot_;
};

}  // namespace
}  // namespace elaslam

int main(int argc, char** argv) {
  using namespace elaslam;
  std::string url;
  double interval_s = 5.0;
  CLI::App app{"elaslam monitor: one progress line for a live team (frame, poses, moving landmarks, health)"};
  cli::add_version_flag(app, "monitor");
  app.add_option("--lcm-url", url, "LCM URL (default: $LCM_DEFAULT_URL, else LCM's default)");
  app.add_option("--interval", interval_s, "seconds between lines when not on a terminal")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 3600.0));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  lcm::LCM lc(url);
  if (!lc.good()) {
    std::fprintf(stderr, "monitor: cannot open LCM (%s)\n", describe_lcm_url(url).c_str());
    return 1;
  }
  Progress progress;
  progress.subscribe(lc);
  install_stop_handlers();
  const bool tty = isatty(STDERR_FILENO) == 1;
  const auto period = tty ? std::chrono::milliseconds(200)
                          : std::chrono::milliseconds(static_cast<long long>(interval_s * 1000.0));
  auto next = Clock::now() + period;
  std::string last;
  while (!stop_requested().load()) {
    if (lc.handleTimeout(50) < 0 && !stop_requested().load()) {
      std::fprintf(stderr, "monitor: LCM handle error\n");
      return 1;
    }
    if (Clock::now() < next) continue;
    next += period;
    const std::string l = progress.line();
    if (tty) {
      std::fprintf(stderr, "\r\033[K%s", l.c_str());  // rewrite the line in place
    } else if (l != last) {
      std::fprintf(stderr, "%s\n", l.c_str());
    }
    last = l;
  }
  std::fprintf(stderr, tty ? "\r\033[K%s\n" : "%s\n", progress.line().c_str());
  return 0;
}

// simulator: the world of the paper's experiment as an LCM node (DESIGN.md sections
// 1 and 7). Publishes SENSOR_<r> for every robot and GROUND_TRUTH at F frames/s on
// absolute deadlines, STATUS_SIM and RUN_INFO (what the run is: scenario, seed,
// dynamism, speed, rate, effective config) before the first frame and about once a
// second; with --lockstep it waits after each frame for every robot's POSE_<r> of
// that frame (bounded by a timeout).
//
// Exit codes: 0 done (also after SIGINT/SIGTERM), 1 runtime failure (LCM),
// 2 bad command line or configuration.
#include <algorithm>
#include <atomic>
#include <cerrno>
#include <climits>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <iostream>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/cli.hpp"
#include "elaslam/common/config.hpp"
#include "elaslam/node_status_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/simulator/messages.hpp"
#include "elaslam/simulator/scenario.hpp"
#include "elaslam/simulator/world.hpp"

namespace {

using elaslam::sim::ScenarioOptions;
using elaslam::sim::World;

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop.store(true); }

constexpr std::int64_t kNsPerMs = 1000000;
// A frame is late when it is published more than this after its deadline. 1 ms is
// about the LCM messaging floor's worst case on this class of machine (LCM.md §5)
// and 1 % of a 10 Hz period; at >= 1 kHz every late frame is also an overrun.
constexpr std::int64_t kLateThresholdNs = 1 * kNsPerMs;
// Sleep at most this long at a time so that a signal is noticed promptly even if
// it arrives just before clock_nanosleep is entered.
constexpr std::int64_t kSleepSliceNs = 50 * kNsPerMs;
// POSE_<r> queue: at most one pose per robot per frame arrives between two waits;
// 64 absorbs a robot that catches up after a stall without unbounded memory.
constexpr int kPoseQueueCapacity = 64;
constexpr std::int64_t kTimeoutsReported = 10;
constexpr std::int64_t kLateReported = 10;

std::int64_t mono_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

std::int64_t realtime_us() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000LL + ts.tv_nsec / 1000;
}

/// Sleep until the absolute CLOCK_MONOTONIC time `deadline_ns`. Returns false when a
/// stop was requested meanwhile.
bool sleep_until(std::int64_t deadline_ns) {
  while (!g_stop.load()) {
    const std::int64_t now = mono_ns();
    if (now >= deadline_ns) return true;
    const std::int64_t wake = std::min(deadline_ns, now + kSleepSliceNs);
    timespec ts{};
    ts.tv_sec = static_cast<time_t>(wake / 1000000000LL);
    ts.tv_nsec = static_cast<long>(wake % 1000000000LL);
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);  // EINTR: loop re-checks
  }
  return false;
}

struct Args {
  std::string config;       // as given (--config), "" when not
  std::string config_path;  // the file used (cli::find_config)
  std::string config_origin;
  std::string team_mode;    // recorded in RUN_INFO only
  double rate_hz = 0.0;
  int frames = 0;
  double dynamism_percent = 0.0;
  double speed_mps = 0.0;
  int seed = 0;
  bool lockstep = false;
  int lockstep_timeout_ms = 1000;
  std::string lcm_url;
  int start_delay_ms = 0;
  int wait_for_nodes = 0;
  int wait_timeout_ms = 10000;
  bool list_robots = false;
  bool check = false;
  bool has_rate = false, has_frames = false, has_dynamism = false, has_speed = false, has_seed = false;
};

/// Returns -1 to go on, or the exit code.
int parse_args(int argc, char** argv, Args* a) {
  CLI::App app{"elaslam simulator: publishes SENSOR_<r> and GROUND_TRUTH for the configured scenario"};
  elaslam::cli::add_version_flag(app, "simulator");
  app.add_option("--config", a->config,
                 "YAML config with a scenario: section (default: $ELASLAM_CONFIG, else /etc/elaslam/elaslam.yaml, "
                 "else the installed paper.yaml)");
  app.add_option("--team-mode", a->team_mode, "the robots' mode, recorded in RUN_INFO (the simulator has none)")
      ->check(CLI::IsMember({"ekf", "gated", "ela", "consensus"}));
  auto* rate = app.add_option("--rate", a->rate_hz, "override scenario.rate_hz [frames/s]")
                   ->check(CLI::Range(1e-3, 100000.0));
  auto* frames = app.add_option("--frames", a->frames, "override scenario.frames")->check(CLI::Range(1, 100000000));
  auto* dyn = app.add_option("--dynamism", a->dynamism_percent, "override scenario.dynamism_percent [%]")
                  ->check(CLI::Range(0.0, 100.0));
  auto* speed = app.add_option("--speed", a->speed_mps, "override scenario.landmark_speed_mps [m/s]")
                    ->check(CLI::Range(0.0, 1000.0));
  auto* seed = app.add_option("--seed", a->seed, "override scenario.seed")->check(CLI::Range(0, INT_MAX));
  app.add_flag("--lockstep", a->lockstep, "after each frame wait for every robot's POSE_<r> of that frame");
  app.add_option("--lockstep-timeout-ms", a->lockstep_timeout_ms, "lockstep wait bound per frame [ms]")
      ->capture_default_str()
      ->check(CLI::Range(1, 3600000));
  app.add_option("--lcm-url", a->lcm_url, "LCM URL (default: $LCM_DEFAULT_URL, else LCM's default)");
  app.add_option("--wait-for-nodes", a->wait_for_nodes,
                 "before frame 0, wait until this many nodes announced themselves on STATUS_* (robots + main)")
      ->check(CLI::Range(0, 64));
  app.add_option("--wait-timeout-ms", a->wait_timeout_ms, "bound of --wait-for-nodes [ms]")->check(CLI::Range(1, 600000));
  app.add_flag("--list-robots", a->list_robots, "print the scenario's robot ids (one line) and exit");
  app.add_flag("--check", a->check, "check the configuration with the overrides, print the scenario and exit (0: valid)");
  app.add_option("--start-delay-ms", a->start_delay_ms, "wait before frame 0 so subscribers can join [ms]")
      ->capture_default_str()
      ->check(CLI::Range(0, 3600000));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);  // prints help (rc 0) or the error
    return rc == 0 ? 0 : 2;
  }
  try {
    const auto choice = elaslam::cli::find_config(a->config);
    a->config_path = choice.path;
    a->config_origin = choice.origin;
  } catch (const elaslam::config::ConfigError& e) {
    std::cerr << "simulator: " << e.what() << "\n";
    return 2;
  }
  a->has_rate = rate->count() > 0;
  a->has_frames = frames->count() > 0;
  a->has_dynamism = dyn->count() > 0;
  a->has_speed = speed->count() > 0;
  a->has_seed = seed->count() > 0;
  return -1;
}

/// Load the scenario and apply the command-line overrides; false on error.
bool load(const Args& a, ScenarioOptions* o, std::string* effective_yaml) {
  try {
    *o = elaslam::sim::load_scenario(a.config_path, effective_yaml);
  } catch (const elaslam::config::ConfigError& e) {
    std::cerr << "simulator: " << e.what() << "\n";
    return false;
  }
  if (a.has_rate) o->rate_hz = a.rate_hz;
  if (a.has_frames) o->frames = a.frames;
  if (a.has_dynamism) o->dynamism_percent = a.dynamism_percent;
  if (a.has_speed) o->landmark_speed_mps = a.speed_mps;
  if (a.has_seed) o->seed = a.seed;
  const auto problems = elaslam::sim::check_scenario(*o);
  for (const auto& p : problems)
    std::cerr << "simulator: " << a.config_path << " with command-line overrides: scenario." << p.key << ": " << p.what
              << "\n";
  return problems.empty();
}

/// Lockstep: tracks the newest POSE_<r> frame of every robot. Handlers never throw;
/// bad messages are counted.
class PoseWaiter {
 public:
  PoseWaiter(lcm::LCM* lc, const ScenarioOptions& o) : lc_(lc) {
    for (const auto& r : o.robots) {
      ids_.push_back(r.id);
      newest_.push_back(-1);
      // subscribeFunction, not a member-function subscription: GCC 12's UBSan (vptr)
      // miscompiles LCM 1.3.1's pointer-to-member dispatch and the handler crashes.
      lc_->subscribeFunction(elaslam::channels::pose(r.id), &PoseWaiter::on_pose, this)
          ->setQueueCapacity(kPoseQueueCapacity);
    }
  }

  /// Wait until every robot has reported frame >= k, or the timeout. True if all came.
  bool wait(int k, int timeout_ms) {
    const std::int64_t end = mono_ns() + timeout_ms * kNsPerMs;
    while (!all_at_least(k)) {
      const std::int64_t left_ns = end - mono_ns();
      if (left_ns <= 0 || g_stop.load()) return false;
      const int ms = static_cast<int>(std::min<std::int64_t>((left_ns + kNsPerMs - 1) / kNsPerMs, 50));
      if (lc_->handleTimeout(ms) < 0) {
        if (!g_stop.load()) ++lcm_errors_;
        return false;
      }
    }
    return true;
  }

  std::int64_t rejected() const { return rejected_; }
  std::int64_t decode_errors() const { return decode_errors_; }
  std::int64_t lcm_errors() const { return lcm_errors_; }

 private:
  bool all_at_least(int k) const {
    return std::all_of(newest_.begin(), newest_.end(), [k](int f) { return f >= k; });
  }

  static void on_pose(const lcm::ReceiveBuffer* rbuf, const std::string& channel, PoseWaiter* self) {
    self->handle_pose(rbuf, channel);
  }
  void handle_pose(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    elaslam::pose_estimate_t m;
    if (m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0) {
      ++decode_errors_;
      return;
    }
    for (std::size_t i = 0; i < ids_.size(); ++i) {
      if (channel != elaslam::channels::pose(ids_[i])) continue;
      if (m.robot_id != ids_[i] || m.frame < 0) {
        ++rejected_;  // robot id must match the channel suffix
        return;
      }
      newest_[i] = std::max(newest_[i], static_cast<int>(m.frame));
      return;
    }
    ++rejected_;
  }

  lcm::LCM* lc_;
  std::vector<int> ids_;
  std::vector<int> newest_;
  std::int64_t rejected_ = 0, decode_errors_ = 0, lcm_errors_ = 0;
};

/// Per-frame processing time histogram (1 us buckets up to 10 ms, then overflow).
class TimeHistogram {
 public:
  void add(std::int64_t us) {
    const auto b = static_cast<std::size_t>(std::clamp<std::int64_t>(us, 0, kBuckets - 1));
    ++counts_[b];
    ++n_;
    max_ = std::max(max_, us);
  }
  std::int32_t percentile(double p) const {
    if (n_ == 0) return 0;
    const auto target = static_cast<std::int64_t>(p * static_cast<double>(n_ - 1)) + 1;
    std::int64_t seen = 0;
    for (std::size_t b = 0; b < counts_.size(); ++b)
      if ((seen += counts_[b]) >= target) return static_cast<std::int32_t>(b);
    return max_us();
  }
  std::int32_t max_us() const { return static_cast<std::int32_t>(std::min<std::int64_t>(max_, INT32_MAX)); }

 private:
  static constexpr std::int64_t kBuckets = 10001;
  std::vector<std::int64_t> counts_ = std::vector<std::int64_t>(kBuckets, 0);
  std::int64_t n_ = 0, max_ = 0;
};

struct RunStats {
  std::int64_t published = 0;
  std::int64_t late = 0;      // published > kLateThresholdNs after the deadline
  std::int64_t overruns = 0;  // published at or after the next frame's deadline
  std::int64_t max_late_ns = 0;
  std::int64_t lockstep_timeouts = 0;
  std::int64_t publish_errors = 0;
  std::int64_t first_pub_ns = 0, last_pub_ns = 0;
  int last_frame = -1;  // last frame published
  TimeHistogram processing;
};

void publish_status(lcm::LCM* lc, const RunStats& s, int frame, const PoseWaiter* waiter) {
  elaslam::node_status_t m{};
  m.utime = realtime_us();
  m.frame = frame;
  m.node_kind = elaslam::node_status_t::SIMULATOR;
  m.node_id = 0;
  m.frames = s.published;
  m.frames_dropped = s.publish_errors;  // the simulator loses a frame only if publish fails
  m.rejected_inputs = waiter ? waiter->rejected() : 0;
  m.decode_errors = waiter ? waiter->decode_errors() : 0;
  m.processing_us_p50 = s.processing.percentile(0.50);
  m.processing_us_p99 = s.processing.percentile(0.99);
  m.processing_us_max = s.processing.max_us();
  lc->publish(elaslam::channels::status_sim(), &m);
}

/// Advance the world to frame k and build its messages ahead of the deadline (this
/// is the measured processing time), then publish them at the deadline.
bool publish_frame(lcm::LCM* lc, World* w, int k, std::int64_t deadline_ns, std::int64_t period_ns, RunStats* s,
                   std::vector<elaslam::sensor_frame_t>* sensor_msgs, elaslam::ground_truth_t* truth) {
  const World& world = *w;
  const std::int64_t t_work = mono_ns();
  if (k > 0) w->step();
  for (int r = 0; r < world.num_robots(); ++r)
    (*sensor_msgs)[static_cast<std::size_t>(r)] = elaslam::sim::to_message(world.sensor_frame(r), 0);
  *truth = elaslam::sim::to_message(world, 0);
  s->processing.add((mono_ns() - t_work) / 1000);
  if (!sleep_until(deadline_ns)) return false;

  const std::int64_t t_pub = mono_ns();
  const std::int64_t utime = realtime_us();  // one stamp for the whole frame
  for (int r = 0; r < world.num_robots(); ++r) {
    auto& m = (*sensor_msgs)[static_cast<std::size_t>(r)];
    m.utime = utime;
    if (lc->publish(elaslam::channels::sensor(m.robot_id), &m) < 0) ++s->publish_errors;
  }
  truth->utime = utime;
  if (lc->publish(elaslam::channels::ground_truth(), truth) < 0) ++s->publish_errors;

  const std::int64_t late_ns = t_pub - deadline_ns;
  if (late_ns > kLateThresholdNs && ++s->late <= kLateReported)
    std::fprintf(stderr, "simulator: frame %d published %.3f ms after its deadline%s\n", k, late_ns * 1e-6,
                 s->late == kLateReported ? " (no more reported)" : "");
  if (late_ns >= period_ns) ++s->overruns;
  s->max_late_ns = std::max(s->max_late_ns, late_ns);
  if (s->published == 0) s->first_pub_ns = t_pub;
  s->last_pub_ns = t_pub;
  s->last_frame = k;
  ++s->published;
  return true;
}

void print_summary(const RunStats& s, const World& world, const PoseWaiter* waiter, double rate_hz) {
  const double span_s = static_cast<double>(s.last_pub_ns - s.first_pub_ns) * 1e-9;
  const double achieved = (s.published > 1 && span_s > 0.0) ? static_cast<double>(s.published - 1) / span_s : 0.0;
  std::fprintf(stderr,
               "simulator: done: %lld frames published, achieved %.3f Hz (target %.3f Hz), late frames (>1 ms) %lld, "
               "overruns %lld, max lateness %.3f ms, lockstep timeouts %lld, publish errors %lld, "
               "truncated observations %lld, processing p50 %d us p99 %d us max %d us\n",
               static_cast<long long>(s.published), achieved, rate_hz, static_cast<long long>(s.late),
               static_cast<long long>(s.overruns), static_cast<double>(s.max_late_ns) * 1e-6,
               static_cast<long long>(s.lockstep_timeouts), static_cast<long long>(s.publish_errors),
               static_cast<long long>(world.counters().truncated_obs), s.processing.percentile(0.5),
               s.processing.percentile(0.99), s.processing.max_us());
  if (waiter)
    std::fprintf(stderr, "simulator: POSE inputs rejected %lld, decode errors %lld, LCM errors %lld\n",
                 static_cast<long long>(waiter->rejected()), static_cast<long long>(waiter->decode_errors()),
                 static_cast<long long>(waiter->lcm_errors()));
}

void install_signal_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: a blocking wait returns early
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

// Readiness of the team: every node publishes its STATUS_* channel at start. Waiting
// for them (instead of a fixed start delay) means no frame goes out before every
// subscriber exists.
bool wait_for_nodes(lcm::LCM* lc, int n, int timeout_ms) {
  std::set<std::string> seen;
  auto* sub = lc->subscribeFunction(
      "STATUS_(ROBOT_[0-9]+|MAIN)", +[](const lcm::ReceiveBuffer*, const std::string& ch, std::set<std::string>* s) { s->insert(ch); },
      &seen);
  const std::int64_t end = mono_ns() + static_cast<std::int64_t>(timeout_ms) * kNsPerMs;
  while (static_cast<int>(seen.size()) < n && mono_ns() < end && !g_stop.load()) lc->handleTimeout(20);
  lc->unsubscribe(sub);
  if (static_cast<int>(seen.size()) >= n) {
    std::fprintf(stderr, "simulator: %d nodes ready\n", n);
    return true;
  }
  std::fprintf(stderr, "simulator: only %zu of %d nodes announced themselves within %d ms\n", seen.size(), n, timeout_ms);
  return false;
}

int run(const Args& a, const ScenarioOptions& o, const std::string& effective_yaml) {
  const char* env_url = std::getenv("LCM_DEFAULT_URL");
  const std::string url = !a.lcm_url.empty() ? a.lcm_url : (env_url ? env_url : "");
  lcm::LCM lc(url);
  if (!lc.good()) {
    std::cerr << "simulator: cannot open LCM at '" << (url.empty() ? "(LCM default)" : url)
              << "': for udpm, the network needs a multicast route (e.g. run inside tools/netns_run.sh)\n";
    return 1;
  }
  std::cerr << elaslam::cli::version_line("simulator") << ", config " << a.config_path << " (" << a.config_origin
            << ")\n"
            << elaslam::sim::describe(o) << "simulator: lcm " << (url.empty() ? "(LCM default)" : url)
            << (a.lockstep ? ", lockstep (timeout " + std::to_string(a.lockstep_timeout_ms) + " ms)" : ", free running")
            << ", start delay " << a.start_delay_ms << " ms\n";
  elaslam::run_info_t info = elaslam::sim::to_run_info(o, a.config_path, effective_yaml, a.team_mode, realtime_us());
  auto publish_info = [&](int frame) {
    info.utime = realtime_us();
    info.frame = frame;
    lc.publish(elaslam::channels::run_info(), &info);
  };
  publish_info(-1);  // a recorder that is already listening knows the run before the team starts

  if (a.wait_for_nodes > 0 && !wait_for_nodes(&lc, a.wait_for_nodes, a.wait_timeout_ms)) return 1;
  publish_info(-1);
  World world(o);
  std::unique_ptr<PoseWaiter> waiter;
  if (a.lockstep) waiter = std::make_unique<PoseWaiter>(&lc, o);
  RunStats stats;
  std::vector<elaslam::sensor_frame_t> sensor_msgs(o.robots.size());
  auto truth = std::make_unique<elaslam::ground_truth_t>();  // ~10 KB: keep it off the stack

  const std::int64_t t0 = mono_ns() + a.start_delay_ms * kNsPerMs;
  const std::int64_t period_ns = static_cast<std::int64_t>(1e9 / o.rate_hz);
  std::int64_t next_status = t0;
  for (int k = 0; k < o.frames && !g_stop.load(); ++k) {
    // deadline_k = t0 + k / F from the same origin: no drift accumulates.
    const auto deadline = t0 + static_cast<std::int64_t>(static_cast<long double>(k) * 1e9L / o.rate_hz);
    if (!publish_frame(&lc, &world, k, deadline, period_ns, &stats, &sensor_msgs, truth.get())) break;
    if (waiter && !waiter->wait(k, a.lockstep_timeout_ms) && !g_stop.load()) {
      // Report the first few; the summary has the total.
      if (++stats.lockstep_timeouts <= kTimeoutsReported)
        std::fprintf(stderr, "simulator: lockstep: not every robot's POSE for frame %d within %d ms, going on%s\n",
                     k, a.lockstep_timeout_ms, stats.lockstep_timeouts == kTimeoutsReported ? " (no more reported)" : "");
    }
    if (mono_ns() >= next_status) {
      publish_status(&lc, stats, k, waiter.get());
      publish_info(k);
      next_status += 1000 * kNsPerMs;  // ~1 Hz; after a stall, restart the phase instead of bursting
      if (next_status <= mono_ns()) next_status = mono_ns() + 1000 * kNsPerMs;
    }
  }
  publish_status(&lc, stats, stats.last_frame, waiter.get());
  if (g_stop.load()) std::cerr << "simulator: stopped by signal\n";
  print_summary(stats, world, waiter.get(), o.rate_hz);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  const int rc = parse_args(argc, argv, &args);
  if (rc >= 0) return rc;
  ScenarioOptions options;
  std::string effective_yaml;
  if (!load(args, &options, &effective_yaml)) return 2;
  if (args.check) {
    std::cout << "simulator: " << args.config_path << " (" << args.config_origin << "): valid\n"
              << elaslam::sim::describe(options);
    return 0;
  }
  if (args.list_robots) {
    for (std::size_t i = 0; i < options.robots.size(); ++i) std::printf("%s%d", i ? " " : "", options.robots[i].id);
    std::printf("\n");
    return 0;
  }
  install_signal_handlers();
  return run(args, options, effective_yaml);
}

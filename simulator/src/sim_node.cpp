// SPDX-License-Identifier: Apache-2.0
#include "elaslam/simulator/sim_node.hpp"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <vector>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/node_status_t.hpp"
#include "elaslam/simulator/lockstep.hpp"
#include "elaslam/simulator/messages.hpp"
#include "elaslam/simulator/scheduler.hpp"
#include "elaslam/simulator/world.hpp"

namespace elaslam::sim {
namespace {

constexpr std::int64_t kTimeoutsReported = 10;
constexpr std::int64_t kLateReported = 10;

class SimNode {
 public:
  SimNode(transport::NodeShell& shell, const ScenarioOptions& o, const SimRunOptions& r)
      : shell_(shell), o_(o), r_(r), world_(o), sensor_msgs_(o.robots.size()),
        truth_(std::make_unique<ground_truth_t>()),  // its arrays reused frame to frame
        info_(to_run_info(o, r.config_path, r.effective_yaml, r.team_mode, shell.now_utime())),
        truth_channel_(channels::ground_truth(shell.suffix())) {
    for (std::size_t i = 0; i < o.robots.size(); ++i) {  // built once: no allocation in a frame's burst
      sensor_channels_.push_back(channels::sensor(o.robots[i].id, shell.suffix()));
      sensor_msgs_[i].obs.reserve(static_cast<std::size_t>(o.sensor.max_observations));
    }
  }

  int run();

 private:
  void publish_info(int frame) {
    info_.utime = shell_.now_utime();
    info_.frame = frame;
    shell_.publish(channels::run_info(shell_.suffix()), info_);
  }
  void publish_status(int frame);
  void prepare_frame(int k);
  bool publish_frame(int k, const FrameSchedule& schedule);
  bool sleep_alive(std::int64_t deadline_ns);
  void say_summary() const;
  void note_truncation(int k);
  static constexpr int kAlertFrames = 100;  // at most one truncation line per this many frames

  transport::NodeShell& shell_;
  const ScenarioOptions& o_;
  const SimRunOptions& r_;
  World world_;
  std::optional<LockstepWaiter> waiter_;
  ScheduleStats stats_;
  std::int64_t lockstep_timeouts_ = 0, publish_errors_ = 0;
  std::int64_t truncated_seen_ = 0;                          // world_.counters().truncated_obs already said
  int truncated_frame_ = -1, alerted_frame_ = -1000000;      // last frame truncated / said
  std::vector<sensor_frame_t> sensor_msgs_;
  std::unique_ptr<ground_truth_t> truth_;
  run_info_t info_;
  const std::string truth_channel_;
  std::vector<std::string> sensor_channels_;  // per robot, in the scenario's order
};

int SimNode::run() {
  shell_.ready();    // a service (Type=notify): LCM is open, the world built
  publish_info(-1);  // a recorder that is already listening knows the run before the team starts
  if (r_.wait_for_nodes > 0 && !wait_for_nodes(shell_, r_.wait_for_nodes, r_.wait_timeout_ms)) return 1;
  publish_info(-1);
  if (r_.lockstep) {
    std::vector<int> ids;
    for (const auto& robot : o_.robots) ids.push_back(robot.id);
    waiter_.emplace(shell_, ids);
  }
  const FrameSchedule schedule(o_.rate_hz, mono_ns() + r_.start_delay_ms * kNsPerMs);
  std::int64_t next_status = schedule.deadline_ns(0);
  // Frame k+1 is built while frame k is in flight. In lockstep at once, while the
  // robots work on frame k (the world does not depend on what they send), not after
  // their POSEs; at a set rate half a period after frame k's deadline, when the
  // robots are done with it, not on a core they wait for.
  if (o_.frames > 0) prepare_frame(0);
  for (int k = 0; k < o_.frames && !shell_.stop_requested(); ++k) {
    shell_.alive();  // the frame loop turns: a watchdog ping when due (service_notify.hpp)
    if (!publish_frame(k, schedule)) break;
    if (k + 1 < o_.frames) {
      if (!waiter_ && !sleep_alive(schedule.deadline_ns(k) + schedule.period_ns() / 2)) break;
      prepare_frame(k + 1);
    }
    if (waiter_ && !waiter_->wait(k, r_.lockstep_timeout_ms) && !shell_.stop_requested()) {
      if (++lockstep_timeouts_ <= kTimeoutsReported)  // the first few; the summary has the total
        shell_.say("lockstep: not every robot's POSE for frame " + std::to_string(k) + " within " +
                   std::to_string(r_.lockstep_timeout_ms) + " ms, going on" +
                   (lockstep_timeouts_ == kTimeoutsReported ? " (no more reported)" : ""),
                   log::Priority::kWarning);
    }
    if (mono_ns() >= next_status) {
      publish_status(k);
      publish_info(k);
      next_status += 1000 * kNsPerMs;  // ~1 Hz; after a stall, restart the phase instead of bursting
      if (next_status <= mono_ns()) next_status = mono_ns() + 1000 * kNsPerMs;
    }
  }
  shell_.stopping();  // a service: the frames are done or a signal came
  publish_status(stats_.last_frame);
  if (shell_.stop_requested()) shell_.say("stopped by signal");
  say_summary();
  return 0;
}

void SimNode::publish_status(int frame) {
  node_status_t m{};
  m.utime = shell_.now_utime();
  m.frame = frame;
  m.node_kind = node_status_t::SIMULATOR;
  m.node_id = 0;
  m.odom_turn_scale = m.odom_speed_scale = 1.0f;  // no odometer of its own: the identity
  m.frames = stats_.published;
  m.frames_dropped = publish_errors_;  // the simulator loses a frame only if publish fails
  m.rejected_inputs = waiter_ ? waiter_->rejected() : 0;
  m.decode_errors = waiter_ ? waiter_->decode_errors() : 0;
  // Observations beyond scenario.sensor.max_observations were left out in the last kAlertFrames frames.
  if (truncated_frame_ >= 0 && frame - truncated_frame_ < kAlertFrames) m.fault_flags |= node_status_t::FAULT_CAPACITY;
  shell_.stamp_auth(&m);
  m.processing_us_p50 = static_cast<std::int32_t>(stats_.processing.quantile(0.50));
  m.processing_us_p99 = static_cast<std::int32_t>(stats_.processing.quantile(0.99));
  m.processing_us_max = static_cast<std::int32_t>(std::min<std::int64_t>(stats_.processing.max(), INT32_MAX));
  shell_.publish(channels::status_sim(shell_.suffix()), m);
}

/// Advance the world to frame k and build its messages (the measured processing time).
void SimNode::prepare_frame(int k) {
  const std::int64_t t_work = mono_ns();
  if (k > 0) world_.step();
  for (int r = 0; r < world_.num_robots(); ++r)
    to_message(world_.sensor_frame(r), 0, &sensor_msgs_[static_cast<std::size_t>(r)]);
  note_truncation(k);
  to_message(world_, 0, truth_.get());
  stats_.processing.add((mono_ns() - t_work) / 1000);
}

/// sleep_until in steps of at most 1 s, alive between them: a long --start-delay-ms or
/// a slow rate keeps the watchdog fed. False on a stop.
bool SimNode::sleep_alive(std::int64_t deadline_ns) {
  constexpr std::int64_t kStepNs = 1000 * kNsPerMs;
  for (;;) {
    shell_.alive();
    const std::int64_t step = std::min(deadline_ns, mono_ns() + kStepNs);
    if (!sleep_until(step, shell_.stop())) return false;
    if (step == deadline_ns) return true;
  }
}

/// Publish frame k's messages (prepare_frame) at its deadline. False on a stop.
bool SimNode::publish_frame(int k, const FrameSchedule& schedule) {
  const std::int64_t deadline = schedule.deadline_ns(k);
  if (!sleep_alive(deadline)) return false;

  const std::int64_t t_pub = mono_ns();
  const std::int64_t utime = shell_.now_utime();  // one stamp for the whole frame
  for (std::size_t i = 0; i < sensor_msgs_.size(); ++i) {
    sensor_msgs_[i].utime = utime;
    if (!shell_.publish(sensor_channels_[i], sensor_msgs_[i])) ++publish_errors_;
  }
  truth_->utime = utime;
  if (!shell_.publish(truth_channel_, *truth_)) ++publish_errors_;
  const std::int64_t late_ns = stats_.record(k, t_pub, deadline, schedule.period_ns());
  if (late_ns > ScheduleStats::kLateNs && stats_.late <= kLateReported) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "frame %d published %.3f ms after its deadline%s", k, late_ns * 1e-6,
                  stats_.late == kLateReported ? " (no more reported)" : "");
    shell_.say(buf, log::Priority::kWarning);
  }
  return true;
}

// More landmarks in view than a sensor frame carries (scenario.sensor.max_observations):
// the nearest go out, the rest are left out. Said at once (then at most once per
// kAlertFrames frames) and flagged in STATUS_SIM, not only in the summary line.
void SimNode::note_truncation(int k) {
  const std::int64_t n = world_.counters().truncated_obs;
  if (n == truncated_seen_) return;
  const std::int64_t now = n - truncated_seen_;
  truncated_seen_ = n;
  truncated_frame_ = k;
  if (k - alerted_frame_ < kAlertFrames) return;
  alerted_frame_ = k;
  shell_.say("FAULT: frame " + std::to_string(k) + ": " + std::to_string(now) + " observation(s) beyond the " +
             std::to_string(o_.sensor.max_observations) + " a sensor frame carries (scenario.sensor.max_observations) left out (" +
             std::to_string(n) +
             " so far; the nearest are kept)",
             log::Priority::kWarning);
}

void SimNode::say_summary() const {
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "done: %lld frames published, achieved %.3f Hz (target %.3f Hz), late frames (>1 ms) %lld, "
                "overruns %lld, max lateness %.3f ms, lockstep timeouts %lld, publish errors %lld, "
                "truncated observations %lld, processing p50 %lld us p99 %lld us max %lld us",
                static_cast<long long>(stats_.published), stats_.achieved_hz(), o_.rate_hz,
                static_cast<long long>(stats_.late), static_cast<long long>(stats_.overruns),
                static_cast<double>(stats_.max_late_ns) * 1e-6, static_cast<long long>(lockstep_timeouts_),
                static_cast<long long>(publish_errors_), static_cast<long long>(world_.counters().truncated_obs),
                static_cast<long long>(stats_.processing.quantile(0.5)),
                static_cast<long long>(stats_.processing.quantile(0.99)),
                static_cast<long long>(stats_.processing.max()));
  shell_.say(buf);
  if (waiter_)
    shell_.say("POSE inputs rejected " + std::to_string(waiter_->rejected()) + ", decode errors " +
               std::to_string(waiter_->decode_errors()) + ", LCM errors " + std::to_string(waiter_->transport_errors()));
}

}  // namespace

int run_simulator(transport::NodeShell& shell, const ScenarioOptions& o, const SimRunOptions& r) {
  return SimNode(shell, o, r).run();
}

}  // namespace elaslam::sim

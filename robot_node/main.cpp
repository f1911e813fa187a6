// SPDX-License-Identifier: Apache-2.0
// robot_node: one robot's EKF-SLAM with the ELA gate, as its own process on LCM.
//   robot_node [--config FILE] --robot R [--mode M] [--state PATH] [--lcm-url URL] [--channel-suffix S]
// The config: --config, else $ELASLAM_CONFIG, else /etc/elaslam/elaslam.yaml, else
// the installed default (common/cli.hpp).
// Subscribes SENSOR_<R>, DYNAMIC_NOTICE; publishes POSE_<R>, LMAP_EVENTS (or LMAP_EVENT),
// LMAP_SNAPSHOT, STATUS_ROBOT_<R>. A thin shell: RobotNode on the node shell
// (RobotPorts, robot_node.hpp), exactly as the in-process team run runs it.
// With --state the node's whole state (robot_state.hpp) is saved atomically after
// processed frames at most every node.state_save_interval_s and at exit, and
// resumed at start; a corrupt file is moved aside to PATH.corrupt (docs/deployment.md).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <utility>

#include <CLI/CLI.hpp>

#include "elaslam/common/atomic_file.hpp"
#include "elaslam/common/cli.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/common/log.hpp"
#include "elaslam/robot_node/robot_node.hpp"
#include "elaslam/robot_node/robot_state.hpp"
#include "elaslam/transport/incarnation.hpp"
#include "elaslam/transport/node_shell.hpp"
#include "elaslam/transport/process.hpp"
#include "elaslam/transport/service_notify.hpp"

namespace elaslam {
namespace {

struct Args {
  std::string config;
  int robot = 0;
  std::string mode;
  std::string state;
  transport::TransportArgs transport;
  RobotQueues queues;
  double status_period_s = 1.0;
  bool verbose = false;
  bool check = false;
};

/// The configuration file with --mode over it; false (said why) when it is not valid.
bool load(const Args& a, cli::ConfigChoice* cfg, RobotOptions* o, std::string* effective) {
  try {
    *cfg = cli::find_config(a.config);
    *o = load_robot_options(cfg->path, effective);
  } catch (const config::ConfigError& e) {
    log::print(stderr, log::Priority::kErr, "robot_node: %s\n", e.what());
    return false;
  }
  if (!a.mode.empty() && !parse_mode(a.mode, &o->mode)) {
    log::print(stderr, log::Priority::kErr,
               "robot_node: --mode '%s' is not one of ekf, gated, ela, consensus\n", a.mode.c_str());
    return false;
  }
  if (const std::string advice = config_advice(*o); !advice.empty())
    log::print(stderr, log::Priority::kWarning, "robot_node %d: warning: %s\n", a.robot, advice.c_str());
  if (!o->limits.in_team(a.robot)) {  // its own team would refuse every message it sends
    log::print(stderr, log::Priority::kErr, "robot_node: --robot %d is not in robot.limits.team (%s) of %s\n", a.robot,
               team_text(o->limits.team_mask).c_str(), cfg->path.c_str());
    return false;
  }
  return true;
}

// More event seq numbers than a robot can send in any save interval (at most
// Robot::event_capacity, 3 x 64 + capacity + 8, events a frame).
constexpr std::int64_t kResumeSeqSkip = std::int64_t{1} << 24;

void save(const std::string& path, RobotNode& node, std::uint64_t mission);

/// The state in `path` when there is one (true: resumed); a corrupt one is moved
/// aside to PATH.corrupt (said why) and the node starts fresh: a bad file must not
/// keep a robot down. A fresh start takes this start's incarnation (`incarnation`,
/// transport/incarnation.hpp: later starts have larger ones); a resumed node keeps its own.
/// `mission` (the team's keys' mission, 0: none): a state of another mission is not
/// resumed (robot_state.hpp).
bool resume(const std::string& path, std::int64_t incarnation, std::uint64_t mission, RobotNode* node) {
  node->set_incarnation(incarnation);
  if (path.empty()) return false;
  std::string text, why;
  bool missing = false;
  if (!files::read_all(path, &text, &why, &missing)) {
    if (!missing)
      log::print(stderr, log::Priority::kWarning, "robot_node %d: cannot read state %s: %s; starting fresh\n",
                 node->robot_id(), path.c_str(), why.c_str());
    return false;
  }
  if (load_robot_state(text, node, &why, mission)) {
    // The events sent after the last save carried the next seq numbers, and
    // main_robot has them: numbering on from the file would have them refused as
    // stale. Jump ahead instead: main_robot sees one gap, asks for a snapshot
    // (LMAP_RESYNC) and refuses none of this run's events.
    node->skip_seq(kResumeSeqSkip);
    // Saved at once, before anything is sent: killed again before its first save, the
    // next resume would reuse this run's seq numbers, and main_robot would take its
    // events for duplicates of this run's and see no gap to repair.
    save(path, *node, mission);
    std::fprintf(stderr, "robot_node %d: resumed from %s at frame %d, %d landmarks, seq %lld (incarnation %lld)\n",
                 node->robot_id(), path.c_str(), node->robot().last_frame(), node->robot().filter().num_landmarks(),
                 (long long)node->event_seq(), (long long)node->incarnation());
    return true;
  }
  const std::string aside = path + ".corrupt";
  const bool moved = std::rename(path.c_str(), aside.c_str()) == 0;
  log::print(stderr, log::Priority::kWarning,
             "robot_node %d: state file %s is corrupt: %s; %s, starting fresh\n", node->robot_id(), path.c_str(),
             why.c_str(), moved ? ("moved aside to " + aside).c_str() : "could not move it aside");
  return false;
}

/// A failed save is said once per series (FAULT line) and flagged in STATUS
/// (FAULT_SAVE_FAILED) until a save succeeds again.
void save(const std::string& path, RobotNode& node, std::uint64_t mission) {
  std::string why;
  const bool ok = files::write_atomic(path, save_robot_state(node, mission), &why);
  node.note_save(ok, path + ": " + why);
  if (const std::string alert = node.take_alert(); !alert.empty())
    log::print(stderr, log::Priority::kWarning, "robot_node %d: %s\n", node.robot_id(), alert.c_str());
}

/// --state while running, called every turn of the shell (after a frame's messages
/// went out, never inside Robot::process): saves once a frame was processed, at most
/// every node.state_save_interval_s (0: after every frame). And a resumed state that
/// the arriving frames do not continue (a new run from frame 0, or down longer than
/// node.max_frame_gap: every frame refused as old or too far ahead) is dropped after
/// kMisfitFrames such refusals with none processed: the node starts fresh. Also
/// without --state: a sensor source that starts over while the node runs.
class StateKeeper {
 public:
  static constexpr std::int64_t kMisfitFrames = 10;
  using Clock = std::chrono::steady_clock;

  StateKeeper(std::string path, const RobotOptions& o, RobotNode* node, bool resumed, std::int64_t incarnation,
              std::uint64_t mission)
      : path_(std::move(path)), options_(o), node_(node), watching_(resumed), next_incarnation_(incarnation + 1),
        mission_(mission),
        period_(std::chrono::microseconds(static_cast<std::int64_t>(o.state_save_interval_s * 1e6))),
        next_save_(Clock::now()), saved_frames_(node->counters().frames), frames_at_start_(saved_frames_),
        refused_at_start_(refused()) {}

  void turn() {
    if (watching_ && !path_.empty()) check_fit();
    check_source();
    if (path_.empty()) return;
    const auto now = Clock::now();
    if (now < next_save_ || node_->counters().frames == saved_frames_) return;
    save(path_, *node_, mission_);
    saved_frames_ = node_->counters().frames;
    next_save_ = now + period_;
  }

 private:
  std::int64_t refused() const {
    const RobotNodeCounters& c = node_->counters();
    return c.frames_out_of_order + c.frames_duplicate + c.rejected_inputs;
  }
  void check_fit() {
    if (node_->counters().frames != frames_at_start_) {  // a frame continued the state: it fits
      watching_ = false;
      return;
    }
    if (refused() - refused_at_start_ < kMisfitFrames) return;
    log::print(stderr, log::Priority::kWarning,
               "robot_node %d: the state of %s (frame %d) does not fit the frames arriving (%lld refused, "
               "none processed): starting fresh\n", node_->robot_id(), path_.c_str(), node_->robot().last_frame(),
               (long long)kMisfitFrames);
    start_fresh();
  }
  // A fresh node with a new incarnation, larger than this start's and any resumed one
  // (main_robot takes its stream for a restart).
  void start_fresh() {
    const std::int64_t next = std::max(next_incarnation_, node_->incarnation() + 1);
    *node_ = RobotNode(options_, node_->robot_id());
    node_->set_incarnation(next);
    next_incarnation_ = next + 1;
    watching_ = false;
  }

  // A sensor source that started over while the node ran (kMisfitFrames frames older
  // than the last processed and none processed since, RobotNode::frames_behind): a
  // new run. The old map and frames are of the old one: start fresh, with a new
  // incarnation (so main_robot takes the new stream for a restart). A replayed old
  // recording does the same (the team key refuses one, docs/security.md).
  void check_source() {
    if (node_->frames_behind() < kMisfitFrames) return;
    log::print(stderr, log::Priority::kWarning,
               "robot_node %d: the sensor frames started over (%d in a row older than frame %d, none "
               "processed): a new run, starting fresh\n", node_->robot_id(), node_->frames_behind(),
               node_->robot().last_frame());
    start_fresh();
  }

  const std::string path_;
  const RobotOptions options_;
  RobotNode* node_;
  bool watching_;
  std::int64_t next_incarnation_;
  const std::uint64_t mission_;
  const Clock::duration period_;
  Clock::time_point next_save_;
  std::int64_t saved_frames_;
  const std::int64_t frames_at_start_;
  const std::int64_t refused_at_start_;
};

void final_line(const RobotNode& node, const FrameStages& st) {
  const auto& c = node.counters();
  std::fprintf(stderr,
               "robot_node %d: frames=%lld gaps=%lld duplicates=%lld out_of_order=%lld rejected=%lld "
               "decode_errors=%lld filter_faults=%lld events=%lld notices_applied=%lld notices_stale=%lld landmarks=%d "
               "evictions=%lld restored=%lld frame_us p50=%lld p99=%lld max=%lld\n",
               node.robot_id(), (long long)c.frames, (long long)c.frames_gap, (long long)c.frames_duplicate,
               (long long)c.frames_out_of_order, (long long)c.rejected_inputs, (long long)c.decode_errors,
               (long long)c.filter_faults, (long long)c.events_sent, (long long)c.notices_applied,
               (long long)c.notices_stale, node.robot().filter().num_landmarks(), (long long)c.evictions, (long long)c.restored,
               (long long)node.processing().quantile(0.5),
               (long long)node.processing().quantile(0.99), (long long)node.processing().max());
  // Where the frames' time went (FrameStages; receive needs the sender's clock).
  const auto q = [](const DurationHistogram& h) {
    return std::to_string(h.quantile(0.5)) + "/" + std::to_string(h.quantile(0.99)) + "/" + std::to_string(h.max());
  };
  std::fprintf(stderr, "robot_node %d: stages_us p50/p99/max receive=%s frame=%s outputs=%s pose=%s\n",
               node.robot_id(), q(st.receive).c_str(), q(st.frame).c_str(), q(st.outputs).c_str(),
               q(st.pose).c_str());
  if (node.robot().options().team_map_fuse) {  // robot.team_map: what the other robots' map did
    const TeamCounters& t = node.robot().team_counters();
    std::fprintf(stderr,
                 "robot_node %d: team_map chunks=%lld stale=%lld offered=%lld fused=%lld gated=%lld refused=%lld "
                 "mean_nis=%.2f lost=%lld relocalised=%lld\n",
                 node.robot_id(), (long long)c.team_map_chunks, (long long)c.team_map_stale, (long long)t.offered,
                 (long long)t.fused, (long long)t.gated, (long long)t.refused,
                 t.fused > 0 ? t.nis_sum / static_cast<double>(t.fused) : 0.0, (long long)t.lost,
                 (long long)t.relocalised);
  }
}

int run(const Args& a) {
  cli::ConfigChoice cfg;
  RobotOptions o;
  std::string effective;
  if (!load(a, &cfg, &o, &effective)) return 2;
  if (a.check) {  // e.g. after editing /etc/elaslam/elaslam.yaml, before restarting the service
    std::printf("robot_node %d: %s (%s): valid, mode %s\n", a.robot, cfg.path.c_str(), cfg.origin.c_str(),
                to_string(o.mode));
    if (a.verbose) std::printf("%s\n", effective.c_str());
    std::fflush(stdout);
    return transport::check_transport(a.transport, cfg.path, "robot_node " + std::to_string(a.robot),
                                      static_cast<std::int16_t>(a.robot), true);
  }
  transport::install_stop_handlers();  // before LCM and the start line (process.hpp)
  const std::string name = "robot_node " + std::to_string(a.robot);
  std::string note;
  const std::int64_t incarnation = transport::start_incarnation(a.state, &note);
  int open_rc = 1;  // authenticated when the team's keys are configured (transport/process.hpp)
  transport::AuthInfo auth;  // its mission goes in the state file
  const auto lcm = transport::open_lcm(a.transport, cfg.path, static_cast<std::int16_t>(a.robot), true, incarnation,
                                       name, &open_rc, stderr, &auth);
  if (!lcm) return open_rc;
  transport::ServiceNotifier service;  // systemd's Type=notify and watchdog (service_notify.hpp)
  transport::ShellOptions shell_options(name, a.transport.channel_suffix);
  shell_options.service = &service;
  transport::NodeShell shell(*lcm, shell_options);
  RobotNode node(o, a.robot);
  const bool resumed = resume(a.state, incarnation, auth.mission, &node);
  StateKeeper keeper(a.state, o, &node, resumed, incarnation, auth.mission);
  RobotPorts<transport::NodeShell> ports(shell, node);
  if (!ports.open(a.queues)) {
    shell.say("cannot subscribe", log::Priority::kErr);
    return 1;
  }
  std::fprintf(stderr, "%s: %s, config %s (%s), mode=%s lcm=%s, incarnation %lld (%s)\n", name.c_str(),
               cli::version_line("robot_node").c_str(), cfg.path.c_str(), cfg.origin.c_str(), to_string(o.mode),
               transport::describe_url(a.transport.lcm_url).c_str(), static_cast<long long>(incarnation), note.c_str());
  if (a.verbose) std::fprintf(stderr, "%s\n", effective.c_str());
  shell.every(std::chrono::milliseconds(static_cast<int>(a.status_period_s * 1000)), [&] { ports.publish_status(); });
  shell.every(transport::NodeShell::Clock::duration::zero(), [&] { keeper.turn(); });
  const bool transport_failed = shell.spin(100) == transport::NodeShell::Exit::kTransportError;
  if (!a.state.empty()) save(a.state, node, auth.mission);  // SIGINT / SIGTERM (and a failed transport): the latest state
  if (!transport_failed) ports.publish_status();
  final_line(node, ports.stages());
  return transport_failed ? 1 : 0;
}

}  // namespace
}  // namespace elaslam

int main(int argc, char** argv) {
  return elaslam::cli::guarded_main("robot_node", [&] {
    namespace cli = elaslam::cli;
    elaslam::Args a;
    CLI::App app{"elaslam robot_node: one robot's EKF-SLAM with the ELA gate, on LCM"};
    cli::add_version_flag(app, "robot_node");
    cli::add_config_option(app, &a.config, "its robot: section");
    app.add_option("--robot", a.robot, "this robot's id: 1 to 16, and in robot.limits.team")
        ->required()
        ->check(cli::range(1, elaslam::contract::kMaxRobots));
    app.add_option("--mode", a.mode, "override robot.mode: ekf, gated, ela, consensus");
    app.add_option("--state", a.state, "file to keep this robot's state in (resumed at start, saved atomically)");
    elaslam::transport::add_transport_options(app, &a.transport);
    app.add_option("--sensor-queue", a.queues.sensor, "SENSOR_<R> subscription queue capacity")->check(cli::range(1, 100000));
    app.add_option("--notice-queue", a.queues.notice, "DYNAMIC_NOTICE queue capacity")->check(cli::range(1, 100000));
    app.add_option("--status-period", a.status_period_s, "seconds between STATUS_ROBOT messages")
        ->check(cli::range(0.05, 60.0));
    app.add_flag("--verbose", a.verbose, "print the effective configuration");
    app.add_flag("--check", a.check, "check the configuration, print where it came from and exit (0: valid)");
    if (const int rc = cli::parse(app, argc, argv); rc >= 0) return rc;
    return elaslam::run(a);
  });
}

// SPDX-License-Identifier: Apache-2.0
#include "elaslam/team/team_run.hpp"

#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "elaslam/common/contract.hpp"
#include "elaslam/common/cov.hpp"

#include "elaslam/common/channels.hpp"
#include "elaslam/eval/frame_data.hpp"
#include "elaslam/main_robot/main_ports.hpp"
#include "elaslam/robot_node/robot_ports.hpp"
#include "elaslam/robot_node/state_keeper.hpp"
#include "elaslam/simulator/messages.hpp"
#include "elaslam/simulator/world.hpp"
#include "elaslam/transport/inprocess_transport.hpp"
#include "elaslam/transport/node_shell.hpp"

namespace elaslam {
namespace {

// The oracle: observations of truly moving landmarks never reach the robots.
void remove_moving(const FrameData& f, sensor_frame_t* s) {
  int kept = 0;
  for (int o = 0; o < s->num_obs; ++o) {
    const auto id = static_cast<std::size_t>(s->obs[o].landmark_id);
    if (id < f.truly_moving.size() && f.truly_moving[id]) continue;
    s->obs[static_cast<std::size_t>(kept++)] = s->obs[static_cast<std::size_t>(o)];
  }
  contract::set_count(&s->obs, &s->num_obs, kept);
}

// The ekf baseline takes every landmark as static: its main makes no finding of its
// own either (main.body_radius_m off; its robots ignore notices too, Robot::apply_notice).
GlobalMapOptions for_mode(GlobalMapOptions o, Mode mode) {
  if (mode == Mode::kEkf) o.body_radius_m = 0.0;
  return o;
}

/// present[id] = 1 for the landmarks the ground truth `gt` lists, over ids 0..n-1.
void mark_present(const ground_truth_t& gt, std::size_t n, std::vector<std::uint8_t>* present) {
  present->assign(n, 0);
  for (int i = 0; i < gt.num_landmarks; ++i) {
    const int id = gt.landmarks[i].id;
    if (id >= 0 && id < static_cast<int>(n)) (*present)[static_cast<std::size_t>(id)] = 1;
  }
}

}  // namespace

TeamConfig apply_overrides(const TeamConfig& base, const RunOverrides& o) {
  TeamConfig c = base;
  if (o.mode) c.robot.mode = *o.mode;
  // Each override within the config reader's bounds (sim::limits); written so that nan fails.
  namespace lim = sim::limits;
  const auto refuse = [](const std::string& what, double v) {
    std::ostringstream os;
    os << what << ", got " << v;
    throw std::invalid_argument(os.str());
  };
  if (o.dynamism_percent) {
    if (!(*o.dynamism_percent >= 0.0 && *o.dynamism_percent <= lim::kDynamismMaxPercent))
      refuse("dynamism must be in [0, 100] percent", *o.dynamism_percent);
    c.scenario.dynamism_percent = *o.dynamism_percent;
  }
  if (o.landmark_speed_mps) {
    if (!(*o.landmark_speed_mps >= 0.0 && *o.landmark_speed_mps <= lim::kLandmarkSpeedMaxMps))
      refuse("speed must be in [0, 1000] m/s", *o.landmark_speed_mps);
    c.scenario.landmark_speed_mps = *o.landmark_speed_mps;
  }
  if (o.seed) {
    if (*o.seed < 0) refuse("seed must be >= 0", *o.seed);
    c.scenario.seed = *o.seed;
  }
  if (o.rate_hz) {
    if (!(*o.rate_hz >= lim::kRateMinHz && *o.rate_hz <= lim::kRateMaxHz))
      refuse("rate must be in [0.001, 100000] Hz", *o.rate_hz);
    c.scenario.rate_hz = *o.rate_hz;
  }
  if (o.frames) {
    if (!(*o.frames >= 1 && *o.frames <= lim::kFramesMax)) refuse("frames must be in [1, 100000000]", *o.frames);
    c.scenario.frames = *o.frames;
  }
  const auto problems = sim::check_scenario(c.scenario);
  if (!problems.empty()) throw std::invalid_argument("scenario." + problems.front().key + ": " + problems.front().what);
  // The echo of the effective config follows the overrides (a config built in code,
  // in tests, has none to echo).
  c.effective_yaml = config::edit_yaml(
      c.effective_yaml,
      [&c](YAML::Node& root) {
        if (root["scenario"].IsMap()) {
          YAML::Node s = root["scenario"];
          s["dynamism_percent"] = c.scenario.dynamism_percent;
          s["landmark_speed_mps"] = c.scenario.landmark_speed_mps;
          s["seed"] = c.scenario.seed;
          s["rate_hz"] = c.scenario.rate_hz;
          s["frames"] = c.scenario.frames;
        }
        if (root["robot"].IsMap()) root["robot"]["mode"] = to_string(c.robot.mode);
      },
      /*create=*/false);
  return c;
}

void SimulatorFrames::frame(int k, ground_truth_t* gt, std::vector<sensor_frame_t>* sensors) {
  if (k > 0) world_.step();
  const std::int64_t t0 = 1'000'000'000'000'000;  // a fixed epoch: runs are reproducible
  const std::int64_t utime = t0 + static_cast<std::int64_t>(std::llround(k * options_.dt_s() * 1e6));
  sim::to_message(world_, utime, gt);
  sensors->resize(static_cast<std::size_t>(world_.num_robots()));
  for (int i = 0; i < world_.num_robots(); ++i)
    sim::to_message(world_.sensor_frame(i), utime, &(*sensors)[static_cast<std::size_t>(i)]);
}

RunResult run_team(const TeamConfig& config) {
  SimulatorFrames frames(config.scenario);
  return run_team(config.robot, config.main, frames, config.oracle);
}

namespace {

using transport::NodeShell;

// The team on the in-process transport: main_robot and every robot node on node
// shells with the ports their processes use (MainPorts, RobotPorts), so the live and
// in-process paths share the code from the decoded message to the published one.
// This class plays the rest of the live system: the simulator (GROUND_TRUTH, then
// every robot's SENSOR of the frame, as the simulator publishes them) and the
// recorder (GROUND_TRUTH, POSE_<r> and GLOBAL_MAP into the metrics' frame data, read
// as evaluate reads a recording: frame_data.hpp). Every message crosses the transport
// encoded. The one queue dispatches in publication order, which gives each node the
// order of a lockstep team: robot i gets SENSOR_i of frame k after every notice of
// frame k - 1; main_robot gets robot 1's events, snapshot and POSE of frame k, then
// robot 2's, ...; the notices of frame k reach the robots after their frame k and
// before k + 1; then the GLOBAL_MAP of frame k.
class InProcessTeam {
 public:
  InProcessTeam(const RobotOptions& robot_options, const GlobalMapOptions& main_options, FrameProvider& frames,
                bool oracle);
  void run_frame(int k);
  RunResult finish();

 private:
  NodeShell::Handler<ground_truth_t> on_truth();
  NodeShell::Handler<pose_estimate_t> on_pose();
  transport::ShellOptions quiet(const std::string& name) {  // no log: refusals are counted only
    transport::ShellOptions o(name, "", nullptr);
    o.clock = [this] { return now_utime_; };
    return o;
  }

  FrameProvider& frames_;
  const bool oracle_;
  const int num_robots_;
  transport::InProcessTransport bus_;
  std::int64_t now_utime_ = 0;  // message time: the frame's (runs are reproducible)
  NodeShell main_shell_;
  MainNode main_;
  MainPorts<NodeShell> main_ports_;
  std::vector<std::unique_ptr<NodeShell>> robot_shells_;
  std::vector<RobotNode> robots_;  // reserved: the ports hold references
  std::vector<std::unique_ptr<RobotPorts<NodeShell>>> robot_ports_;
  // The restart policy robot_node runs, without a state file: a sensor source that
  // starts over (a provider that replays) restarts the robot as the process would.
  std::vector<StateKeeper> keepers_;
  NodeShell world_;  // the frame source and the recorder
  int frame_ = 0;
  std::int64_t first_utime_ = 0;
  double time_s_ = 0.0;
  FrameData f_;
  GlobalMapAssembly map_assembly_;  // GLOBAL_MAP chunks -> the map of a publication
  ground_truth_t gt_in_;
  std::vector<sensor_frame_t> sensors_;
  sensor_frame_t sensor_;
  MetricsAccumulator acc_;
  // Confirmed tracks (a second sighting fitted: MoverTrack::confirmed) and, from
  // their fifth sighting on, established ones.
  TrackScorer tracks_{MoverTrack::kConfirmingSightings}, tracks_established_{TrackScorer::kEstablishedSightings};
  // Each robot's track operations replayed with its true pose (RunMetrics::tracks_true_pose).
  std::vector<MoverTracks> true_pose_tracks_;
  std::vector<std::int64_t> tracks_ended_;  // per robot: its tracks' `ended` count at the last frame
  std::vector<int> replayed_frame_;         // per robot: the last frame whose operations were replayed
  bool true_poses_ = true;  // every frame so far had every robot's true pose
  TrackScorer true_pose_scorer_{MoverTrack::kConfirmingSightings},
      true_pose_established_{TrackScorer::kEstablishedSightings};
  std::vector<TrackSample> samples_;
  std::vector<std::uint8_t> present_;
  void score_tracks();
  RunResult out_;
};

InProcessTeam::InProcessTeam(const RobotOptions& robot_options, const GlobalMapOptions& main_options,
                             FrameProvider& frames, bool oracle)
    : frames_(frames),
      oracle_(oracle),
      num_robots_(frames.num_robots()),
      main_shell_(bus_, quiet("main_robot")),
      main_(for_mode(main_options, robot_options.mode)),
      main_ports_(main_shell_, main_),
      world_(bus_, quiet("team")) {
  const auto R = static_cast<std::size_t>(num_robots_);
  out_.estimated.resize(R);
  out_.truth.resize(R);
  out_.corrections_by_landmark.assign(static_cast<std::size_t>(robot_options.ekf.max_landmark_id), 0);
  // Subscription order is dispatch order for a message with several subscribers:
  // main_robot, the robots in order (DYNAMIC_NOTICE), the recorder.
  main_ports_.open();
  robots_.reserve(R);
  keepers_.reserve(R);
  for (int i = 0; i < num_robots_; ++i) {
    const int id = frames.robot_id(i);
    robot_shells_.push_back(std::make_unique<NodeShell>(bus_, quiet("robot_node " + std::to_string(id))));
    RobotNode& node = robots_.emplace_back(robot_options, id);
    auto& ports = *robot_ports_.emplace_back(std::make_unique<RobotPorts<NodeShell>>(*robot_shells_.back(), node));
    keepers_.emplace_back(std::string(), robot_options, &node, /*resumed=*/false, node.incarnation(), /*mission=*/0);
    true_pose_tracks_.emplace_back(robot_options.tracking, robot_options.ekf.max_landmark_id);
    tracks_ended_.push_back(0);
    replayed_frame_.push_back(-1);
    ports.open();
    ports.after_frame([this](const RobotNode& n) {  // observations that corrected the pose, by landmark
      for (const GateRecord& g : n.robot().gate_records())
        if (g.inside && g.kind != GateKind::kCandidate && g.landmark_id >= 0 &&
            g.landmark_id < static_cast<int>(out_.corrections_by_landmark.size()))
          ++out_.corrections_by_landmark[static_cast<std::size_t>(g.landmark_id)];
    });
  }
  world_.subscribe<ground_truth_t>(channels::ground_truth(), on_truth(), transport::kUnboundedQueue);
  world_.subscribe<pose_estimate_t>(channels::any_pose(), on_pose(), transport::kUnboundedQueue);
  world_.subscribe<global_map_t>(
      channels::global_map(),
      [this](const global_map_t& g, const std::string&) {
        if (map_assembly_.add(g)) read_map(map_assembly_.map(), &f_.map_landmarks, &f_.map_moving);
      },
      transport::kUnboundedQueue);
}

NodeShell::Handler<ground_truth_t> InProcessTeam::on_truth() {
  return [this](const ground_truth_t& gt, const std::string&) {
    if (frame_ == 0) first_utime_ = gt.utime;
    time_s_ = static_cast<double>(gt.utime - first_utime_) * 1e-6;
    set_truth(gt, &f_);
    f_.frame = frame_;
    f_.time_s = time_s_;
    clear_estimates(static_cast<std::size_t>(num_robots_), &f_);
  };
}

NodeShell::Handler<pose_estimate_t> InProcessTeam::on_pose() {
  return [this](const pose_estimate_t& p, const std::string&) {
    for (std::size_t i = 0; i < robots_.size(); ++i) {
      if (robots_[i].robot_id() != p.robot_id) continue;
      set_pose(i, p, &f_);
      out_.estimated[i].push_back({time_s_, {p.x, p.y, p.theta}, read_cov(p.cov)});
      if (i < f_.true_poses.size()) out_.truth[i].push_back({time_s_, f_.true_poses[i]});
    }
  };
}

void InProcessTeam::run_frame(int k) {
  frame_ = k;
  frames_.frame(k, &gt_in_, &sensors_);
  now_utime_ = gt_in_.utime;
  world_.publish(channels::ground_truth(), gt_in_);
  bus_.dispatch_all();  // the frame's truth first: the oracle reads it
  for (int i = 0; i < num_robots_; ++i) {
    sensor_ = sensors_[static_cast<std::size_t>(i)];
    if (oracle_) remove_moving(f_, &sensor_);
    add_observed(sensor_, &f_.observed);
    world_.publish(channels::sensor(frames_.robot_id(i)), sensor_);
  }
  bus_.dispatch_all();  // robots -> main_robot -> notices -> robots
  for (StateKeeper& keeper : keepers_) keeper.turn();
  main_ports_.publish_map(k);
  bus_.dispatch_all();  // -> the recorder
  acc_.add(f_);
  score_tracks();
}

// Each robot's tracks at this frame against the truth the frame came with; and the
// same operations replayed on tracks fed the robot's true pose.
void InProcessTeam::score_tracks() {
  mark_present(gt_in_, f_.true_landmarks.size(), &present_);
  const auto sample = [](std::size_t r, int id, const MoverTrack& t) {
    return TrackSample{static_cast<int>(r), id, t.mean(), t.covariance(), t.stopped(), t.sightings()};
  };
  samples_.clear();
  for (std::size_t r = 0; r < robots_.size(); ++r) {
    const MoverTracks& tracks = robots_[r].robot().tracks();
    for (const int id : tracks.ids()) samples_.push_back(sample(r, id, tracks.track(id)));
  }
  tracks_.add(time_s_, f_.true_landmarks, present_, samples_);
  tracks_established_.add(time_s_, f_.true_landmarks, present_, samples_);
  true_poses_ = true_poses_ && f_.true_poses.size() >= robots_.size();
  if (!true_poses_) return;
  samples_.clear();
  for (std::size_t r = 0; r < robots_.size(); ++r) {
    const Robot& robot = robots_[r].robot();
    MoverTracks& shadow = true_pose_tracks_[r];
    // A reset or relocalisation ended the robot's tracks: end the replay's too.
    if (robot.tracks().counters().ended != tracks_ended_[r]) shadow.clear();
    tracks_ended_[r] = robot.tracks().counters().ended;
    TrackSighting base;
    base.pose = f_.true_poses[r];
    base.R = robot.filter().measurement_cov();
    if (robot.last_frame() != replayed_frame_[r]) {  // a robot that took no frame has nothing new
      shadow.apply(robot.track_ops(), base, robot.clock_s());
      replayed_frame_[r] = robot.last_frame();
    }
    for (const int id : shadow.ids()) samples_.push_back(sample(r, id, shadow.track(id)));
  }
  true_pose_scorer_.add(time_s_, f_.true_landmarks, present_, samples_);
  true_pose_established_.add(time_s_, f_.true_landmarks, present_, samples_);
}

RunResult InProcessTeam::finish() {
  RunResult out = std::move(out_);
  out.metrics = acc_.finish();
  if (!robots_.empty() && robots_.front().robot().tracks().enabled()) {
    out.metrics.tracks_scored = true;
    out.metrics.tracks = tracks_.finish();
    out.metrics.tracks_established = tracks_established_.finish();
    out.metrics.tracks_true_pose_scored = true_poses_;
    if (true_poses_) {
      out.metrics.tracks_true_pose = true_pose_scorer_.finish();
      out.metrics.tracks_true_pose_established = true_pose_established_.finish();
    }
  }
  out.frames = acc_.frames();
  out.robot_ids = acc_.robot_ids();
  for (RobotMetrics& rm : out.metrics.robots)
    for (const RobotNode& node : robots_) {
      if (node.robot_id() != rm.id) continue;
      rm.node_counters = true;
      rm.filter_full = node.counters().filter_full;
      rm.evictions = node.counters().evictions;
      rm.restored = node.counters().restored;
      rm.mover_corrections = node.counters().mover_corrections;
      rm.movers_followed = node.counters().movers_followed;
      rm.final_landmarks = node.robot().filter().num_landmarks();
      rm.team_lost = node.robot().team_counters().lost;
      rm.relocalised = node.robot().team_counters().relocalised;
      rm.own_drifted_frames = node.counters().own_drifted_frames;
      const EkfSlam& f = node.robot().filter();
      if (f.calibration_estimated()) {
        const OdometryCalibration c = f.calibration();
        const Eigen::Vector3d sigma = f.calibration_cov().diagonal().cwiseMax(0.0).cwiseSqrt();
        rm.calibration_estimated = true;
        rm.turn_scale = c.turn_scale, rm.turn_scale_sigma = sigma(0);
        rm.speed_scale = c.speed_scale, rm.speed_scale_sigma = sigma(1);
        rm.turn_bias_rad_s = c.turn_bias, rm.turn_bias_sigma_rad_s = sigma(2);
      }
    }
  for (int id = 0; id < main_.map().max_landmark_id(); ++id) {
    const GlobalEntry& g = main_.map().entry(id);
    if (g.status == GlobalStatus::kStatic) out.final_map.push_back({id, g.fused, g.fused_cov});
    if (g.status == GlobalStatus::kMoving) out.final_moving.push_back(id);
  }
  out.final_truth = f_.true_landmarks;
  out.truly_moving = f_.truly_moving;
  mark_present(gt_in_, f_.true_landmarks.size(), &out.truth_present);
  out.bus_messages = bus_.published();
  out.occupied = main_.counters().occupied;
  for (const int id : out.robot_ids) out.team_map_left_out.push_back(main_.map().team_check(id).rounds_left_out);
  return out;
}

}  // namespace

RunResult run_team(const RobotOptions& robot_options, const GlobalMapOptions& main_options, FrameProvider& frames,
                   bool oracle) {
  InProcessTeam team(robot_options, main_options, frames, oracle);
  for (int k = 0; k < frames.num_frames(); ++k) team.run_frame(k);
  return team.finish();
}

}  // namespace elaslam

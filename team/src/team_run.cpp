#include "elaslam/team/team_run.hpp"

#include <cmath>
#include <stdexcept>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "elaslam/main_robot/main_node.hpp"
#include "elaslam/robot_node/robot_node.hpp"
#include "elaslam/simulator/messages.hpp"
#include "elaslam/simulator/world.hpp"
#include "elaslam/team/frame_data.hpp"

namespace elaslam {
namespace {

// The in-process bus: every message crosses it encoded, exactly as on LCM, so the
// in-process run exercises the message contract the live team uses.
class Bus {
 public:
  template <typename Msg>
  Msg carry(const Msg& m) {
    const int size = m.getEncodedSize();
    if (buf_.size() < static_cast<std::size_t>(size)) buf_.resize(static_cast<std::size_t>(size));
    Msg out;
    if (m.encode(buf_.data(), 0, size) != size || out.decode(buf_.data(), 0, size) != size)
      throw std::logic_error(std::string("in-process bus: cannot encode/decode ") + Msg::getTypeName());
    ++messages_;
    return out;
  }
  long long messages() const { return messages_; }

 private:
  std::vector<std::uint8_t> buf_;
  long long messages_ = 0;
};

// The oracle: observations of truly moving landmarks never reach the robots.
void remove_moving(const FrameData& f, sensor_frame_t* s) {
  int kept = 0;
  for (int o = 0; o < s->num_obs; ++o) {
    const auto id = static_cast<std::size_t>(s->obs[o].landmark_id);
    if (id < f.truly_moving.size() && f.truly_moving[id]) continue;
    s->obs[kept++] = s->obs[o];
  }
  s->num_obs = static_cast<std::int16_t>(kept);
}

}  // namespace

TeamConfig apply_overrides(const TeamConfig& base, const RunOverrides& o) {
  TeamConfig c = base;
  if (o.mode) c.robot.mode = *o.mode;
  if (o.dynamism_percent) {
    if (!(*o.dynamism_percent >= 0.0 && *o.dynamism_percent <= 100.0))
      throw std::invalid_argument("dynamism must be in [0, 100] percent");
    c.scenario.dynamism_percent = *o.dynamism_percent;
  }
  if (o.landmark_speed_mps) {
    if (!(*o.landmark_speed_mps >= 0.0 && *o.landmark_speed_mps <= 100.0))
      throw std::invalid_argument("speed must be in [0, 100] m/s");
    c.scenario.landmark_speed_mps = *o.landmark_speed_mps;
  }
  if (o.seed) {
    if (*o.seed < 0) throw std::invalid_argument("seed must be >= 0");
    c.scenario.seed = *o.seed;
  }
  if (o.rate_hz) {
    if (!(*o.rate_hz >= 1e-3 && *o.rate_hz <= 100000.0)) throw std::invalid_argument("rate must be in [0.001, 100000] Hz");
    c.scenario.rate_hz = *o.rate_hz;
  }
  if (o.frames) {
    if (*o.frames < 1) throw std::invalid_argument("frames must be at least 1");
    c.scenario.frames = *o.frames;
  }
  const auto problems = sim::check_scenario(c.scenario);
  if (!problems.empty()) throw std::invalid_argument("scenario." + problems.front().key + ": " + problems.front().what);
  // The echo of the effective config follows the overrides.
  YAML::Node root;
  try {
    root = YAML::Load(c.effective_yaml);
  } catch (const YAML::Exception&) {
  }
  if (!root.IsMap()) return c;  // a config built in code (tests): nothing to echo
  if (root["scenario"].IsMap()) {
    YAML::Node s = root["scenario"];
    s["dynamism_percent"] = c.scenario.dynamism_percent;
    s["landmark_speed_mps"] = c.scenario.landmark_speed_mps;
    s["seed"] = c.scenario.seed;
    s["rate_hz"] = c.scenario.rate_hz;
    s["frames"] = c.scenario.frames;
  }
  if (root["robot"].IsMap()) root["robot"]["mode"] = to_string(c.robot.mode);
  YAML::Emitter out;
  out << root;
  c.effective_yaml = out.c_str();
  return c;
}

namespace {

// The simulator as a frame source: the world steps once per frame.
class SimulatorFrames : public FrameProvider {
 public:
  explicit SimulatorFrames(const sim::ScenarioOptions& o) : options_(o), world_(o) {}
  int num_frames() const override { return options_.frames; }
  int num_robots() const override { return world_.num_robots(); }
  int robot_id(int i) const override { return options_.robots[static_cast<std::size_t>(i)].id; }
  void frame(int k, ground_truth_t* gt, std::vector<sensor_frame_t>* sensors) override {
    if (k > 0) world_.step();
    const std::int64_t t0 = 1'000'000'000'000'000;  // a fixed epoch: runs are reproducible
    const std::int64_t utime = t0 + static_cast<std::int64_t>(std::llround(k * options_.dt_s() * 1e6));
    *gt = sim::to_message(world_, utime);
    sensors->resize(static_cast<std::size_t>(world_.num_robots()));
    for (int i = 0; i < world_.num_robots(); ++i)
      (*sensors)[static_cast<std::size_t>(i)] = sim::to_message(world_.sensor_frame(i), utime);
  }

 private:
  sim::ScenarioOptions options_;
  sim::World world_;
};

}  // namespace

RunResult run_team(const TeamConfig& config) {
  SimulatorFrames frames(config.scenario);
  return run_team(config.robot, config.main, frames, config.oracle);
}

RunResult run_team(const RobotOptions& robot_options, const GlobalMapOptions& main_options, FrameProvider& frames,
                   bool oracle) {
  const int R = frames.num_robots();
  std::vector<RobotNode> robots;
  robots.reserve(static_cast<std::size_t>(R));
  for (int i = 0; i < R; ++i) robots.emplace_back(robot_options, frames.robot_id(i));
  MainNode main(main_options);
  Bus bus;
  MetricsAccumulator acc;
  RunResult out;
  out.estimated.resize(static_cast<std::size_t>(R));
  out.truth.resize(static_cast<std::size_t>(R));
  out.corrections_by_landmark.assign(static_cast<std::size_t>(robot_options.ekf.max_landmark_id), 0);

  FrameData f;
  ground_truth_t gt_in;
  std::vector<sensor_frame_t> sensors;
  std::int64_t first_utime = 0;
  for (int k = 0; k < frames.num_frames(); ++k) {
    frames.frame(k, &gt_in, &sensors);
    const ground_truth_t gt = bus.carry(gt_in);
    const std::int64_t utime = gt.utime;
    if (k == 0) first_utime = utime;
    const double t = static_cast<double>(utime - first_utime) * 1e-6;
    set_truth(gt, &f);
    f.frame = k;
    f.time_s = t;
    clear_estimates(static_cast<std::size_t>(R), &f);
    // Sensors of frame k -> robots -> main_robot.
    for (int i = 0; i < R; ++i) {
      sensor_frame_t s = bus.carry(sensors[static_cast<std::size_t>(i)]);
      if (oracle) remove_moving(f, &s);
      add_observed(s, &f.observed);
      RobotNode& node = robots[static_cast<std::size_t>(i)];
      if (node.on_sensor(s, utime) != RobotNode::Verdict::kProcessed) continue;
      for (const GateRecord& g : node.robot().gate_records())
        if (g.inside && g.kind != GateKind::kCandidate && g.landmark_id >= 0 &&
            g.landmark_id < static_cast<int>(out.corrections_by_landmark.size()))
          ++out.corrections_by_landmark[static_cast<std::size_t>(g.landmark_id)];
      const pose_estimate_t p = bus.carry(node.pose_msg());
      set_pose(static_cast<std::size_t>(i), p, &f);
      out.estimated[static_cast<std::size_t>(i)].push_back({t, {p.x, p.y, p.theta}});
      if (static_cast<std::size_t>(i) < f.true_poses.size())
        out.truth[static_cast<std::size_t>(i)].push_back({t, f.true_poses[static_cast<std::size_t>(i)]});
      for (const auto& ev : node.event_msgs()) main.on_event(bus.carry(ev));
      if (node.snapshot_ready()) main.on_snapshot(bus.carry(node.snapshot_msg()));
      main.on_robot_frame(p.robot_id, p.frame);  // as main_robot does on each POSE
    }
    // -> notices, before frame k + 1.
    for (const auto& n : main.take_notices(utime)) {
      const dynamic_notice_t msg = bus.carry(n);
      for (auto& node : robots) node.on_notice(msg);
    }
    read_map(bus.carry(main.global_map_msg(utime, k)), &f.map_landmarks, &f.map_moving);
    acc.add(f);
  }
  out.metrics = acc.finish();
  out.frames = acc.frames();
  out.robot_ids = acc.robot_ids();
  for (int id = 0; id < main.map().max_landmark_id(); ++id) {
    const GlobalEntry& g = main.map().entry(id);
    if (g.status == GlobalStatus::kStatic) out.final_map.push_back({id, g.fused, g.fused_cov});
    if (g.status == GlobalStatus::kMoving) out.final_moving.push_back(id);
  }
  out.final_truth = f.true_landmarks;
  out.truly_moving = f.truly_moving;
  out.truth_present.assign(f.true_landmarks.size(), 0);
  for (int i = 0; i < gt_in.num_landmarks; ++i) {
    const int id = gt_in.landmarks[i].id;
    if (id >= 0 && id < static_cast<int>(out.truth_present.size())) out.truth_present[static_cast<std::size_t>(id)] = 1;
  }
  out.bus_messages = bus.messages();
  return out;
}

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// The whole team in one process, in lockstep (docs/design.md section 1, way 2):
// simulator + every robot node + main_robot, frame by frame, over the in-process
// transport (transport/inprocess_transport.hpp), each node on the node shell with the
// ports its process uses (RobotPorts, MainPorts): the live and in-process paths share
// the code, and every message crosses encoded as on LCM. Order per frame: sensors of
// frame k -> robots -> main_robot -> notices, before frame k+1; then GLOBAL_MAP.
// Deterministic: the same config gives the same result (timing aside).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "elaslam/eval/run_result.hpp"
#include "elaslam/ground_truth_t.hpp"
#include "elaslam/sensor_frame_t.hpp"
#include "elaslam/simulator/world.hpp"
#include "elaslam/team/team_config.hpp"

namespace elaslam {

struct RunOverrides {
  std::optional<Mode> mode;
  std::optional<double> dynamism_percent;
  std::optional<double> landmark_speed_mps;
  std::optional<int> seed;
  std::optional<double> rate_hz;  // the live team's --rate: motion per frame changes with it
  std::optional<int> frames;
};

/// Apply overrides to a copy of the config and to its effective_yaml (so that what
/// metrics.json echoes is what ran). The scenario is checked again as a whole
/// (sim::check_scenario: e.g. a speed too high for the rate); throws
/// std::invalid_argument naming the field on a bad value.
TeamConfig apply_overrides(const TeamConfig& base, const RunOverrides& o);

/// Where the frames come from: the simulator or a recorded dataset. Frames are
/// asked for in order, k = 0, 1, 2, ...; robot i of the sensor list is robot_id(i).
class FrameProvider {
 public:
  virtual ~FrameProvider() = default;
  virtual int num_frames() const = 0;
  virtual int num_robots() const = 0;
  virtual int robot_id(int i) const = 0;
  virtual void frame(int k, ground_truth_t* gt, std::vector<sensor_frame_t>* sensors) = 0;
};

/// The simulator as a frame source: the world steps once per frame; message times
/// from a fixed epoch (runs are reproducible).
class SimulatorFrames : public FrameProvider {
 public:
  explicit SimulatorFrames(const sim::ScenarioOptions& o) : options_(o), world_(o) {}
  int num_frames() const override { return options_.frames; }
  int num_robots() const override { return world_.num_robots(); }
  int robot_id(int i) const override { return options_.robots[static_cast<std::size_t>(i)].id; }
  void frame(int k, ground_truth_t* gt, std::vector<sensor_frame_t>* sensors) override;

 private:
  sim::ScenarioOptions options_;
  sim::World world_;
};

/// Run the configured scenario (the simulator) end to end.
RunResult run_team(const TeamConfig& config);

/// Run the team on any frame source. `oracle`: see TeamConfig::oracle.
RunResult run_team(const RobotOptions& robot, const GlobalMapOptions& main, FrameProvider& frames,
                   bool oracle = false);

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// The simulator's frames with the SENSOR messages changed before the robots get
// them, for the team tests of robots whose input goes wrong.
#pragma once

#include <functional>
#include <utility>
#include <vector>

#include "elaslam/team/team_run.hpp"

namespace elaslam::test {

/// SimulatorFrames whose frame k's SENSOR messages (one per robot, by index) go
/// through edit(k, &sensors) first.
class EditedFrames : public SimulatorFrames {
 public:
  using Edit = std::function<void(int k, std::vector<sensor_frame_t>* sensors)>;
  EditedFrames(const sim::ScenarioOptions& o, Edit edit) : SimulatorFrames(o), edit_(std::move(edit)) {}
  void frame(int k, ground_truth_t* gt, std::vector<sensor_frame_t>* sensors) override {
    SimulatorFrames::frame(k, gt, sensors);
    edit_(k, sensors);
  }

 private:
  Edit edit_;
};

}  // namespace elaslam::test

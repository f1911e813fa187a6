// SPDX-License-Identifier: Apache-2.0
// Shared helpers of the simulator tests.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "elaslam/common/geometry.hpp"
#include "elaslam/simulator/messages.hpp"
#include "elaslam/simulator/scenario.hpp"
#include "elaslam/simulator/world.hpp"

namespace elaslam::sim::test {

inline std::string paper_yaml_path() { return std::string(ELASLAM_SOURCE_DIR) + "/config/paper.yaml"; }

/// The default scenario (config/paper.yaml), for tests to modify.
inline ScenarioOptions paper() { return load_scenario(paper_yaml_path()); }

template <typename Msg>
void append_encoded(const Msg& m, std::vector<std::uint8_t>* out) {
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  ASSERT_EQ(m.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  out->insert(out->end(), buf.begin(), buf.end());
}

/// Every message of a whole run (each robot's sensor_frame_t and the ground_truth_t
/// of every frame), encoded and concatenated: equal bytes are a bit-identical run.
inline std::vector<std::uint8_t> run_bytes(const ScenarioOptions& o) {
  std::vector<std::uint8_t> bytes;
  World w(o);
  for (int k = 0; k < o.frames; ++k) {
    if (k > 0) w.step();
    for (int r = 0; r < w.num_robots(); ++r) append_encoded(to_message(w.sensor_frame(r), k), &bytes);
    append_encoded(to_message(w, k), &bytes);
  }
  return bytes;
}

/// The text of a file (tests read config/*.yaml to edit it).
inline std::string read_text(const std::string& path) {
  std::string text;
  if (FILE* f = std::fopen(path.c_str(), "rb")) {
    char buf[4096];
    for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, f)) > 0;) text.append(buf, n);
    std::fclose(f);
  }
  return text;
}

/// Sample mean and variance accumulator (Welford).
struct Moments {
  long n = 0;
  double mean = 0.0, m2 = 0.0;
  void add(double x) {
    ++n;
    const double d = x - mean;
    mean += d / static_cast<double>(n);
    m2 += d * (x - mean);
  }
  double var() const { return n > 1 ? m2 / static_cast<double>(n - 1) : 0.0; }
};

/// Runs `w` to frame frames - 1 and calls each(k, r, u_true, u_odo) for every robot r
/// at every frame k >= 1: its true motion and the motion its odometer reported since
/// frame k - 1, both in its body frame at k - 1.
template <typename Each>
void for_each_increment(World& w, int frames, Each each) {
  std::vector<Pose2> odo, truth;
  for (int r = 0; r < w.num_robots(); ++r) {
    odo.push_back(w.sensor_frame(r).odometer);
    truth.push_back(w.robot_pose(r));
  }
  for (int k = 1; k < frames; ++k) {
    w.step();
    for (int r = 0; r < w.num_robots(); ++r) {
      const auto i = static_cast<std::size_t>(r);
      each(k, r, between(truth[i], w.robot_pose(r)), between(odo[i], w.sensor_frame(r).odometer));
      odo[i] = w.sensor_frame(r).odometer;
      truth[i] = w.robot_pose(r);
    }
  }
}

}  // namespace elaslam::sim::test

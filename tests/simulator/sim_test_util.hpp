// Shared helpers of the simulator tests.
#pragma once

#include <string>

#include <gtest/gtest.h>

#include "elaslam/simulator/scenario.hpp"

namespace elaslam::sim::test {

inline std::string paper_yaml_path() { return std::string(ELASLAM_SOURCE_DIR) + "/config/paper.yaml"; }

/// The default scenario (config/paper.yaml), for tests to modify.
inline ScenarioOptions paper() { return load_scenario(paper_yaml_path()); }

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

}  // namespace elaslam::sim::test

// SPDX-License-Identifier: Apache-2.0
// Proof of "no heap allocation" in a region of code, for the fixed-memory tests.
// Link no_alloc.cpp into the test: it replaces the global operator new (every form)
// with one that counts calls made inside a NoAllocRegion. Compile the code under
// test into the same target with EIGEN_RUNTIME_NO_MALLOC and assertions on, so that
// any Eigen heap allocation inside the region also aborts.
#pragma once

#include <Eigen/Core>

namespace elaslam::test {

/// Allocations counted inside the last (or current) region.
long allocations_in_region();

class NoAllocRegion {
 public:
  NoAllocRegion();
  ~NoAllocRegion();
  NoAllocRegion(const NoAllocRegion&) = delete;
  NoAllocRegion& operator=(const NoAllocRegion&) = delete;
};

}  // namespace elaslam::test

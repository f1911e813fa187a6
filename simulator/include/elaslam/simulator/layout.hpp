// SPDX-License-Identifier: Apache-2.0
// Initial landmark positions (world frame W). Independent of the dynamism, the
// landmark speed and the robots: only the layout keys and, for "random", the
// layout stream of the seed decide them.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "elaslam/simulator/scenario.hpp"

namespace elaslam::sim {

/// Fill *p_LinW with landmarks.count positions less those inside an enabled
/// landmarks.empty_region, index = landmark id (consecutive, in the layout's
/// order). Returns false and says why (in *why) when the layout cannot be built
/// (e.g. random spacing too large for the world, no landmark left); never throws.
bool generate_layout(const ScenarioOptions& o, std::vector<Eigen::Vector2d>* p_LinW, std::string* why);

}  // namespace elaslam::sim

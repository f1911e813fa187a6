// SPDX-License-Identifier: Apache-2.0
#include "elaslam/simulator/layout.hpp"

#include <algorithm>
#include <cmath>

#include "elaslam/common/contract.hpp"
#include "elaslam/simulator/random.hpp"

namespace elaslam::sim {
namespace {

// Cell centres of a columns x rows division of the world, row by row from
// (x_min, y_min): a uniform spread, each landmark half a cell from its neighbours' border.
bool grid(const ScenarioOptions& o, std::vector<Eigen::Vector2d>* p, std::string* why) {
  const LandmarkOptions& l = o.landmarks;
  const long long cells = static_cast<long long>(l.grid_columns) * l.grid_rows;
  if (l.grid_columns < 1 || l.grid_rows < 1 || cells != l.count) {
    *why = "grid_columns x grid_rows = " + std::to_string(cells) +
           " must equal count = " + std::to_string(l.count);
    return false;
  }
  const double cw = (o.world.x_max_m - o.world.x_min_m) / l.grid_columns;
  const double ch = (o.world.y_max_m - o.world.y_min_m) / l.grid_rows;
  for (int r = 0; r < l.grid_rows; ++r)
    for (int c = 0; c < l.grid_columns; ++c)
      p->emplace_back(o.world.x_min_m + (c + 0.5) * cw, o.world.y_min_m + (r + 0.5) * ch);
  return true;
}

// A point at arc length s along the perimeter of the square of half-width h centred
// at c, counter-clockwise from the corner (c.x - h, c.y - h).
Eigen::Vector2d on_square(const Eigen::Vector2d& c, double h, double s) {
  const double side = 2.0 * h;
  const int edge = static_cast<int>(std::floor(s / side)) % 4;
  const double t = s - edge * side;
  switch (edge) {
    case 0: return {c.x() - h + t, c.y() - h};
    case 1: return {c.x() + h, c.y() - h + t};
    case 2: return {c.x() + h - t, c.y() + h};
    default: return {c.x() - h, c.y() + h - t};
  }
}

// Sola's "cloister": concentric square rings; each ring gets a share of the
// landmarks proportional to its perimeter, evenly spaced along it.
bool cloister(const ScenarioOptions& o, std::vector<Eigen::Vector2d>* p, std::string* why) {
  const LandmarkOptions& l = o.landmarks;
  const Eigen::Vector2d c(0.5 * (o.world.x_min_m + o.world.x_max_m), 0.5 * (o.world.y_min_m + o.world.y_max_m));
  const double half_w = 0.5 * std::min(o.world.x_max_m - o.world.x_min_m, o.world.y_max_m - o.world.y_min_m);
  if (l.cloister_rings < 1 || l.cloister_rings > l.count) {
    *why = "cloister_rings must be in [1, count]";
    return false;
  }
  if (l.cloister_inner_half_width_m > l.cloister_outer_half_width_m || l.cloister_outer_half_width_m > half_w) {
    *why = "cloister needs inner_half_width <= outer_half_width <= half the world's size (" +
           std::to_string(half_w) + " m)";
    return false;
  }
  std::vector<double> h(static_cast<std::size_t>(l.cloister_rings));
  double sum_h = 0.0;
  for (int r = 0; r < l.cloister_rings; ++r) {
    const double f = l.cloister_rings == 1 ? 0.0 : static_cast<double>(r) / (l.cloister_rings - 1);
    h[r] = l.cloister_inner_half_width_m + f * (l.cloister_outer_half_width_m - l.cloister_inner_half_width_m);
    sum_h += h[r];
  }
  int placed = 0;
  for (int r = 0; r < l.cloister_rings; ++r) {
    const int n = (r + 1 == l.cloister_rings) ? l.count - placed
                                               : static_cast<int>(std::lround(l.count * h[r] / sum_h));
    if (n < 1 || h[r] <= 0.0) {
      *why = "cloister ring " + std::to_string(r) + " gets no landmarks: use fewer rings or more landmarks";
      return false;
    }
    for (int j = 0; j < n; ++j) p->push_back(on_square(c, h[r], (j + 0.5) * 8.0 * h[r] / n));
    placed += n;
  }
  return true;
}

// Uniform in the world with a minimum spacing (rejection sampling, bounded tries).
bool random_layout(const ScenarioOptions& o, std::vector<Eigen::Vector2d>* p, std::string* why) {
  const LandmarkOptions& l = o.landmarks;
  Rng rng(static_cast<std::uint64_t>(o.seed), stream::kLayout);
  const long max_tries = 2000L * l.count;
  long tries = 0;
  while (static_cast<int>(p->size()) < l.count) {
    if (++tries > max_tries) {
      *why = "could not place " + std::to_string(l.count) + " landmarks at least " +
             std::to_string(l.min_spacing_m) + " m apart in " + std::to_string(max_tries) +
             " tries: lower min_spacing_m or count";
      return false;
    }
    const Eigen::Vector2d q(rng.uniform(o.world.x_min_m, o.world.x_max_m),
                            rng.uniform(o.world.y_min_m, o.world.y_max_m));
    bool ok = true;
    for (const auto& e : *p) ok = ok && (e - q).norm() >= l.min_spacing_m;
    if (ok) p->push_back(q);
  }
  return true;
}

// The empty region's landmarks left out after the layout placed them all, so that
// the layout outside the region is the one without it; the ids of the rest stay
// consecutive, in the layout's order.
bool leave_out(const EmptyRegion& e, std::vector<Eigen::Vector2d>* p, std::string* why) {
  if (!e.enabled) return true;
  const auto n = p->size();
  p->erase(std::remove_if(p->begin(), p->end(), [&](const Eigen::Vector2d& q) { return e.contains(q.x(), q.y()); }),
           p->end());
  if (p->empty()) {
    *why = "the empty region holds all " + std::to_string(n) + " landmarks of the layout: shrink empty_region";
    return false;
  }
  return true;
}

}  // namespace

bool generate_layout(const ScenarioOptions& o, std::vector<Eigen::Vector2d>* p_LinW, std::string* why) {
  p_LinW->clear();
  if (o.landmarks.count < 1 || o.landmarks.count > contract::kMaxWorldLandmarks) {
    *why = "count must be in [1, " + std::to_string(contract::kMaxWorldLandmarks) + "] (ground_truth_t holds " +
           std::to_string(contract::kMaxWorldLandmarks) + " landmarks)";
    return false;
  }
  p_LinW->reserve(static_cast<std::size_t>(std::max(o.landmarks.count, 0)));
  bool ok = false;
  switch (o.landmarks.layout) {
    case Layout::kGrid: ok = grid(o, p_LinW, why); break;
    case Layout::kCloister: ok = cloister(o, p_LinW, why); break;
    case Layout::kRandom: ok = random_layout(o, p_LinW, why); break;
  }
  if (!ok) return false;
  return leave_out(o.landmarks.empty_region, p_LinW, why);
}

}  // namespace elaslam::sim

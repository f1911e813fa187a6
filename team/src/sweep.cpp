// SPDX-License-Identifier: Apache-2.0
// The sweep's grid, its jobs and their parallel run (the files: sweep_tables.cpp).
#include "elaslam/team/sweep.hpp"

#include <atomic>
#include <cmath>
#include <mutex>
#include <sstream>
#include <stdexcept>

#include "elaslam/simulator/scenario.hpp"
#include "elaslam/team/parallel.hpp"

namespace elaslam {

std::vector<double> parse_number_list(const std::string& text, const char* what, double lo, double hi) {
  std::vector<double> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    std::size_t pos = 0;
    double x = 0.0;
    try {
      x = std::stod(item, &pos);
    } catch (const std::out_of_range&) {  // beyond a double: as good as inf
      x = HUGE_VAL;
      pos = item.size();
    } catch (const std::exception&) {
      pos = 0;
    }
    const std::string where = std::string(what) + ": '" + item + "'";
    if (pos == 0 || pos != item.size()) throw std::invalid_argument(where + " is not a number");
    if (!std::isfinite(x)) throw std::invalid_argument(where + " is not a finite number");
    if (!(x >= lo && x <= hi)) {
      std::ostringstream range;
      range << "[" << lo << ", " << hi << "]";
      throw std::invalid_argument(where + " is out of range: expected a number in " + range.str());
    }
    v.push_back(x);
  }
  if (v.empty()) throw std::invalid_argument(std::string(what) + ": empty list");
  return v;
}

std::vector<Mode> parse_mode_names(const std::string& text) {
  std::vector<Mode> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    Mode m;
    if (!parse_mode(item, &m)) throw std::invalid_argument("--modes: '" + item + "' is not ekf, gated, ela or consensus");
    v.push_back(m);
  }
  if (v.empty()) throw std::invalid_argument("--modes: empty list");
  return v;
}

SweepGrid make_grid(const std::string& modes, const std::string& dynamism, const std::string& speed, int runs) {
  SweepGrid g;
  g.modes = parse_mode_names(modes);
  g.dynamism = parse_number_list(dynamism, "--dynamism", 0.0, sim::limits::kDynamismMaxPercent);
  g.speed = parse_number_list(speed, "--speed", 0.0, sim::limits::kLandmarkSpeedMaxMps);
  g.runs = runs;
  return g;
}

void check_grid(const TeamConfig& base, const SweepGrid& g) {
  for (double d : g.dynamism)
    for (double v : g.speed) {
      RunOverrides o;
      o.dynamism_percent = d;
      o.landmark_speed_mps = v;
      apply_overrides(base, o);
    }
}

std::vector<SweepJob> make_jobs(const SweepGrid& g, int seed_base) {
  std::vector<SweepJob> jobs;
  for (Mode m : g.modes)
    for (double d : g.dynamism)
      for (double v : g.speed)
        for (int r = 0; r < g.runs; ++r) jobs.push_back({m, d, v, r, seed_base + r});
  return jobs;
}

void run_sweep(const TeamConfig& base, const std::vector<SweepJob>& jobs, int threads, std::vector<SweepResult>* out,
               const SweepProgress& progress) {
  out->assign(jobs.size(), SweepResult{});
  std::atomic<std::size_t> done{0};
  std::mutex report;
  run_parallel(jobs.size(), threads, [&](std::size_t i) {
    const SweepJob& j = jobs[i];
    RunOverrides o;
    o.mode = j.mode;
    o.dynamism_percent = j.dynamism;
    o.landmark_speed_mps = j.speed;
    o.seed = j.seed;
    (*out)[i] = summarise(run_team(apply_overrides(base, o)));
    const std::size_t d = ++done;
    std::lock_guard<std::mutex> lock(report);
    if (progress) progress(d, jobs.size());
  });
}

RunOverrides map_run(const SweepGrid& g, int seed_base) {
  Mode map_mode = g.modes.front();
  for (Mode m : g.modes)
    if (m == Mode::kEla) map_mode = m;
  RunOverrides o;
  o.mode = map_mode;
  o.dynamism_percent = g.dynamism[g.dynamism.size() / 2];
  o.landmark_speed_mps = g.speed[g.speed.size() / 2];
  o.seed = seed_base;
  return o;
}

}  // namespace elaslam

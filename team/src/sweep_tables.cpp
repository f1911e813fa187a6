// SPDX-License-Identifier: Apache-2.0
// The sweep's files: runs.csv, frames.csv and tables.md (sweep.hpp).
#include "elaslam/team/sweep.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace elaslam {
namespace {

std::ofstream open(const std::filesystem::path& p) {
  std::ofstream out(p);
  if (!out) throw std::runtime_error("cannot write " + p.string());
  return out;
}

std::string g9(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

struct Stat {
  double mean = 0.0, sd = 0.0;
};

Stat stat(const std::vector<double>& v) {
  Stat s;
  if (v.empty()) return s;
  for (double x : v) s.mean += x / static_cast<double>(v.size());
  if (v.size() > 1) {
    double ss = 0.0;
    for (double x : v) ss += (x - s.mean) * (x - s.mean);
    s.sd = std::sqrt(ss / static_cast<double>(v.size() - 1));
  }
  return s;
}

using Metric = std::function<double(const SweepResult&)>;

// Values of one metric in one (mode, dynamism, speed) cell, over its runs.
std::vector<double> cell(const SweepGrid& g, const std::vector<SweepJob>& jobs, const std::vector<SweepResult>& res,
                         Mode m, double d, double v, const Metric& f) {
  std::vector<double> out;
  for (std::size_t i = 0; i < jobs.size(); ++i)
    if (jobs[i].mode == m && jobs[i].dynamism == d && jobs[i].speed == v) out.push_back(f(res[i]));
  (void)g;
  return out;
}

// A table in the paper's layout: rows dynamism, a column group per speed, a column per mode.
void table(std::ostream& out, const std::string& title, const SweepGrid& g, const std::vector<SweepJob>& jobs,
           const std::vector<SweepResult>& res, const Metric& f, int digits) {
  out << "### " << title << "\n\n| dynamism [%] |";
  for (double v : g.speed)
    for (Mode m : g.modes) out << ' ' << v << " m/s " << to_string(m) << " |";
  out << "\n|---|";
  for (std::size_t i = 0; i < g.speed.size() * g.modes.size(); ++i) out << "---|";
  out << '\n' << std::fixed << std::setprecision(digits);
  for (double d : g.dynamism) {
    out << "| " << std::setprecision(0) << d << std::setprecision(digits) << " |";
    for (double v : g.speed)
      for (Mode m : g.modes) {
        const Stat s = stat(cell(g, jobs, res, m, d, v, f));
        out << ' ' << s.mean << " ± " << s.sd << " |";
      }
    out << '\n';
  }
  out << std::defaultfloat << "\n";
}

// For each metric: in how many cells each mode has the lowest mean.
void cells_won(std::ostream& out, const SweepGrid& g, const std::vector<SweepJob>& jobs,
               const std::vector<SweepResult>& res, const std::vector<std::pair<std::string, Metric>>& metrics) {
  out << "### Cells won (lowest mean over runs; " << g.dynamism.size() * g.speed.size() << " cells)\n\n| metric |";
  for (Mode m : g.modes) out << ' ' << to_string(m) << " |";
  out << "\n|---|";
  for (std::size_t i = 0; i < g.modes.size(); ++i) out << "---|";
  out << '\n';
  for (const auto& [name, f] : metrics) {
    std::vector<int> won(g.modes.size(), 0);
    for (double d : g.dynamism)
      for (double v : g.speed) {
        std::size_t best = 0;
        double best_mean = INFINITY;
        for (std::size_t k = 0; k < g.modes.size(); ++k) {
          const double mean = stat(cell(g, jobs, res, g.modes[k], d, v, f)).mean;
          if (mean < best_mean) best_mean = mean, best = k;
        }
        ++won[best];
      }
    out << "| " << name << " |";
    for (int w : won) out << ' ' << w << " |";
    out << '\n';
  }
  out << '\n';
}

const char* kPaperTables = R"(## The paper's figures (Badalkhani & Havangi 2021, Tables 1-2), for reference

Their D, F and noise are not given, so their absolute errors (metres, several
times ours) come from a different world: compare trends (EKF degrading with
dynamism and speed, the proposed method flat), not values.

Table 1, landmark RMSE [m], EKF / Prop., speeds 0.1 0.3 0.5 0.7 0.9 m/s:

| dynamism [%] | 0.1 | 0.3 | 0.5 | 0.7 | 0.9 |
|---|---|---|---|---|---|
| 5 | 4.07 / 2.55 | 3.70 / 2.63 | 3.44 / 2.67 | 3.46 / 2.86 | 3.66 / 2.93 |
| 20 | 3.98 / 2.81 | 3.90 / 2.65 | 4.21 / 3.10 | 4.20 / 2.95 | 3.93 / 3.12 |
| 35 | 5.08 / 2.96 | 4.70 / 3.05 | 4.72 / 2.93 | 4.98 / 2.86 | 4.59 / 2.76 |
| 50 | 5.38 / 2.78 | 5.33 / 3.17 | 5.21 / 2.96 | 5.15 / 2.71 | 5.52 / 3.16 |
| 65 | 5.54 / 2.68 | 5.35 / 2.79 | 5.79 / 2.61 | 5.57 / 2.78 | 5.97 / 3.14 |
| 80 | 5.49 / 3.09 | 5.63 / 3.04 | 5.78 / 3.26 | 6.01 / 3.29 | 6.21 / 3.41 |

Table 2, robot 1 RMSE [m], EKF / Prop.:

| dynamism [%] | 0.1 | 0.3 | 0.5 | 0.7 | 0.9 |
|---|---|---|---|---|---|
| 5 | 0.490 / 0.225 | 0.592 / 0.240 | 0.407 / 0.232 | 0.426 / 0.278 | 0.516 / 0.314 |
| 20 | 0.456 / 0.250 | 0.562 / 0.245 | 0.503 / 0.266 | 0.498 / 0.391 | 0.485 / 0.287 |
| 35 | 0.764 / 0.324 | 0.838 / 0.369 | 0.648 / 0.283 | 0.651 / 0.294 | 0.508 / 0.253 |
| 50 | 0.873 / 0.265 | 0.894 / 0.359 | 0.699 / 0.286 | 0.664 / 0.248 | 0.899 / 0.318 |
| 65 | 1.467 / 0.212 | 0.791 / 0.257 | 0.910 / 0.218 | 0.778 / 0.269 | 0.899 / 0.353 |
| 80 | 1.707 / 0.217 | 1.288 / 0.217 | 0.987 / 0.257 | 1.116 / 0.230 | 0.873 / 0.272 |

)";

}  // namespace

SweepResult summarise(const RunResult& r) {
  SweepResult s;
  s.landmark_error = r.metrics.landmark_error_mean;
  s.landmark_rms = r.metrics.landmark_error_rms;
  s.landmark_static = r.metrics.landmark_error_static;
  for (const auto& rm : r.metrics.robots) {
    s.robot_error.push_back(rm.error_mean);
    s.robot_rms.push_back(rm.error_rms);
    s.robot_uncertainty.push_back(rm.final_uncertainty);
  }
  s.precision = r.metrics.precision;
  s.recall = r.metrics.recall;
  s.frames_to_detect = r.metrics.mean_frames_to_detect;
  s.flagged = r.metrics.flagged;
  for (const auto& f : r.frames) {
    s.frame_landmark_error.push_back(f.landmark_error);
    double sum = 0.0;
    int n = 0;
    for (double e : f.robot_error)
      if (!std::isnan(e)) sum += e, ++n;
    s.frame_robot_error.push_back(n ? sum / n : NAN);
  }
  return s;
}

namespace {

namespace fs = std::filesystem;

void write_runs_csv(const fs::path& path, const SweepGrid& g, const std::vector<SweepJob>& jobs,
                    const std::vector<SweepResult>& res) {
  std::ofstream out = open(path);
  out << "mode,dynamism,speed,run,seed,landmark_error,landmark_rms,";
  for (int id : g.robot_ids) out << "robot" << id << "_error,robot" << id << "_rms,robot" << id << "_uncertainty,";
  out << "precision,recall,static_landmark_error,frames_to_detect,flagged\n";
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    const SweepJob& j = jobs[i];
    const SweepResult& r = res[i];
    out << to_string(j.mode) << ',' << g9(j.dynamism) << ',' << g9(j.speed) << ',' << j.run << ',' << j.seed << ','
        << g9(r.landmark_error) << ',' << g9(r.landmark_rms) << ',';
    for (std::size_t k = 0; k < r.robot_error.size(); ++k)
      out << g9(r.robot_error[k]) << ',' << g9(r.robot_rms[k]) << ',' << g9(r.robot_uncertainty[k]) << ',';
    out << g9(r.precision) << ',' << g9(r.recall) << ',' << g9(r.landmark_static) << ',' << g9(r.frames_to_detect)
        << ',' << r.flagged << '\n';
  }
}

// Mean over runs of the per-frame errors (Fig 7).
void write_frames_csv(const fs::path& path, const SweepGrid& g, const std::vector<SweepJob>& jobs,
                      const std::vector<SweepResult>& res) {
  std::ofstream out = open(path);
  out << "mode,dynamism,speed,frame,landmark_error,robot_error_mean\n";
  for (std::size_t first = 0; first < jobs.size(); first += static_cast<std::size_t>(g.runs)) {
    const std::size_t frames = res[first].frame_landmark_error.size();
    for (std::size_t k = 0; k < frames; ++k) {
      double lm = 0.0, rb = 0.0;
      int nl = 0, nr = 0;
      for (std::size_t i = first; i < first + static_cast<std::size_t>(g.runs); ++i) {
        if (k < res[i].frame_landmark_error.size() && !std::isnan(res[i].frame_landmark_error[k]))
          lm += res[i].frame_landmark_error[k], ++nl;
        if (k < res[i].frame_robot_error.size() && !std::isnan(res[i].frame_robot_error[k]))
          rb += res[i].frame_robot_error[k], ++nr;
      }
      out << to_string(jobs[first].mode) << ',' << g9(jobs[first].dynamism) << ',' << g9(jobs[first].speed) << ','
          << k << ',' << (nl ? g9(lm / nl) : "nan") << ',' << (nr ? g9(rb / nr) : "nan") << '\n';
    }
  }
}

void write_tables_md(const fs::path& path, const SweepGrid& g, const std::vector<SweepJob>& jobs,
                     const std::vector<SweepResult>& res) {
  std::ofstream out = open(path);
  out << "# Sweep results\n\nEntries: mean ± sample standard deviation over " << g.runs
      << " runs (seeds seed_base .. seed_base + runs - 1, the same for every mode and cell). "
         "Errors in metres (docs/design.md section 7: landmark error = eq 18, robot error = mean position error).\n\n";
  if (g.oracle)
    out << "**Oracle runs** (`--oracle`): every observation of a truly moving landmark was removed before the "
           "robots saw it, so these figures are the bound a perfect detector would reach.\n\n";
  std::vector<std::pair<std::string, Metric>> won;
  table(out, "Table 1: landmark error of the global map [m]", g, jobs, res,
        [](const SweepResult& r) { return r.landmark_error; }, 3);
  won.push_back({"landmark error", [](const SweepResult& r) { return r.landmark_error; }});
  // Eq 18 scores each mode on the landmarks of its own map: a mover that ela deletes
  // drops out of its error while ekf is scored on its drifting movers. The same
  // error over the truly static landmarks of each map, beside it.
  const Metric static_only = [](const SweepResult& r) { return r.landmark_static; };
  table(out, "Table 1b: landmark error of the global map, truly static landmarks only [m]", g, jobs, res,
        static_only, 3);
  won.push_back({"landmark error, static only", static_only});
  for (std::size_t k = 0; k < g.robot_ids.size(); ++k) {
    const Metric f = [k](const SweepResult& r) { return r.robot_error[k]; };
    table(out, "Table " + std::to_string(k + 2) + ": error of robot " + std::to_string(g.robot_ids[k]) + " [m]", g,
          jobs, res, f, 3);
    won.push_back({"robot " + std::to_string(g.robot_ids[k]) + " error", f});
  }
  const Metric unc = [](const SweepResult& r) {
    double s = 0.0;
    for (double u : r.robot_uncertainty) s += u / static_cast<double>(r.robot_uncertainty.size());
    return s;
  };
  table(out, "Final uncertainty, mean(diag(P)) at the last frame, mean over robots (eq 19, Fig 8)", g, jobs, res, unc, 5);
  won.push_back({"final uncertainty", unc});
  table(out, "Moving-landmark detection precision", g, jobs, res, [](const SweepResult& r) { return r.precision; }, 2);
  table(out, "Moving-landmark detection recall", g, jobs, res, [](const SweepResult& r) { return r.recall; }, 2);
  cells_won(out, g, jobs, res, won);
  out << kPaperTables;
}

}  // namespace

void write_sweep(const std::string& dir, const SweepGrid& g, const std::vector<SweepJob>& jobs,
                 const std::vector<SweepResult>& res) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error("cannot create " + dir + ": " + ec.message());
  write_runs_csv(fs::path(dir) / "runs.csv", g, jobs, res);
  write_frames_csv(fs::path(dir) / "frames.csv", g, jobs, res);
  write_tables_md(fs::path(dir) / "tables.md", g, jobs, res);
}

}  // namespace elaslam

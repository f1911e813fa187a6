// SPDX-License-Identifier: Apache-2.0
#include "elaslam/eval/report.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "elaslam/common/version.hpp"

namespace elaslam {
namespace {

// YAML (the effective config) to JSON, scalars typed as numbers/bools where they parse.
nlohmann::json yaml_to_json(const YAML::Node& n) {
  if (n.IsMap()) {
    nlohmann::json j = nlohmann::json::object();
    for (const auto& kv : n) j[kv.first.as<std::string>()] = yaml_to_json(kv.second);
    return j;
  }
  if (n.IsSequence()) {
    nlohmann::json j = nlohmann::json::array();
    for (const auto& v : n) j.push_back(yaml_to_json(v));
    return j;
  }
  if (!n.IsScalar()) return nullptr;
  const std::string s = n.Scalar();
  if (s == "true" || s == "false") return s == "true";
  try {
    std::size_t pos = 0;
    const double d = std::stod(s, &pos);
    if (pos == s.size()) {
      if (s.find_first_of(".eE") == std::string::npos) return static_cast<long long>(d);
      return d;
    }
  } catch (const std::exception&) {
  }
  return s;
}


std::ofstream open(const std::filesystem::path& p) {
  std::ofstream out(p);
  if (!out) throw std::runtime_error("cannot write " + p.string());
  out << std::setprecision(10);
  return out;
}

}  // namespace

nlohmann::json yaml_text_to_json(const std::string& yaml) {
  if (yaml.empty()) return nullptr;
  try {
    return yaml_to_json(YAML::Load(yaml));
  } catch (const YAML::Exception&) {
    return yaml;
  }
}

namespace {

// A figure over `count` samples: null when there is none (never "0 of 0").
nlohmann::json over(std::int64_t count, double value) { return count > 0 ? nlohmann::json(value) : nlohmann::json(); }

}  // namespace

nlohmann::json tracks_json(const TrackMetrics& t) {
  return {{"samples", t.samples},
          {"position_rms_m", over(t.samples, t.position_rms_m)},
          {"moving_samples", t.moving_samples},
          {"speed_rms_mps", over(t.moving_samples, t.speed_rms_mps)},
          {"heading_rms_deg", over(t.moving_samples, t.heading_rms_deg)},
          {"stopped_verdicts", t.stopped_verdicts},
          {"at_rest_samples", t.at_rest_samples},
          {"stop_precision", over(t.stopped_verdicts, t.stop_precision)},
          {"stop_recall", over(t.at_rest_samples, t.stop_recall)},
          {"stops", t.stops},
          {"stops_found", t.stops_found},
          {"stop_latency_s", over(t.stops_found, t.stop_latency_s)},
          {"nees_samples", t.nees_samples},
          {"nees_mean", over(t.nees_samples, t.nees_mean)},
          {"nees_in_band", over(t.nees_samples, t.nees_in_band)},
          {"segments", t.segments},
          {"mean_segment_s", over(t.segments, t.mean_segment_s)}};
}

nlohmann::json metrics_json(const RunInfo& info, const RunResult& r) {
  const RunMetrics& m = r.metrics;
  nlohmann::json j;
  j["schema_version"] = kMetricsSchemaVersion;
  j["elaslam_version"] = std::string(version()) + " (git " + git_commit() + ")";
  j["command_line"] = info.command_line;
  j["mode"] = info.mode;
  j["dynamism"] = info.dynamism_percent;
  j["speed"] = info.speed_mps;
  j["seed"] = info.seed;
  j["frames"] = m.frames;
  j["landmark_error"] = {{"mean_euclidean", m.landmark_error_mean},
                         {"rms", m.landmark_error_rms},
                         {"static_only_mean_euclidean", m.landmark_error_static}};
  nlohmann::json robots = nlohmann::json::array();
  for (const auto& rm : m.robots) {
    nlohmann::json r = {{"id", rm.id},
                        {"error_mean", rm.error_mean},
                        {"error_rms", rm.error_rms},
                        {"final_uncertainty", rm.final_uncertainty},
                        {"frames", rm.frames}};
    if (rm.node_counters) {
      r["filter_full"] = rm.filter_full;
      r["evictions"] = rm.evictions;
      r["restored"] = rm.restored;
      r["mover_corrections"] = rm.mover_corrections;
      r["movers_followed"] = rm.movers_followed;
      r["final_landmarks"] = rm.final_landmarks;
      r["team_lost"] = rm.team_lost;
      r["relocalised"] = rm.relocalised;
      r["own_drifted_frames"] = rm.own_drifted_frames;
    }
    if (rm.calibration_estimated)  // robot.odometry_calibration on (absent otherwise)
      r["odometry_calibration"] = {{"turn_scale", rm.turn_scale},
                                   {"turn_scale_sigma", rm.turn_scale_sigma},
                                   {"speed_scale", rm.speed_scale},
                                   {"speed_scale_sigma", rm.speed_scale_sigma},
                                   {"turn_bias_rad_s", rm.turn_bias_rad_s},
                                   {"turn_bias_sigma_rad_s", rm.turn_bias_sigma_rad_s}};
    robots.push_back(std::move(r));
  }
  j["robots"] = robots;
  j["detection"] = {{"precision", m.precision},
                    {"recall", m.recall},
                    {"mean_frames_to_detect", m.mean_frames_to_detect},
                    {"flagged", m.flagged},
                    {"true_positives", m.true_positives},
                    {"detectable", m.detectable}};
  j["timing"] = {{"frame_us_p50", m.frame_us_p50}, {"frame_us_p99", m.frame_us_p99}, {"frame_us_max", m.frame_us_max}};
  if (m.tracks_scored) {
    j["tracks"] = tracks_json(m.tracks);
    j["tracks"]["established"] = tracks_json(m.tracks_established);
    if (m.tracks_true_pose_scored) {
      j["tracks"]["true_pose"] = tracks_json(m.tracks_true_pose);
      j["tracks"]["true_pose"]["established"] = tracks_json(m.tracks_true_pose_established);
    }
  }
  if (m.global_tracks_scored) j["global_tracks"] = tracks_json(m.global_tracks);
  j["final_map"] = {{"static", r.final_map.size()}, {"moving", r.final_moving.size()}};
  j["source"] = info.source;
  j["config"] = yaml_text_to_json(info.effective_config);
  return j;
}

void write_tum(std::ostream& out, const std::vector<TrajectoryPoint>& traj) {
  out << "# timestamp tx ty tz qx qy qz qw\n";
  for (const auto& p : traj)
    out << p.time_s << ' ' << p.pose.x << ' ' << p.pose.y << " 0 0 0 " << std::sin(0.5 * p.pose.theta) << ' '
        << std::cos(0.5 * p.pose.theta) << '\n';
}

void write_outputs(const std::string& dir, const nlohmann::json& metrics, const RunResult& r) {
  namespace fs = std::filesystem;
  const fs::path root(dir);
  std::error_code ec;
  fs::create_directories(root / "trajectories", ec);
  if (ec) throw std::runtime_error("cannot create " + (root / "trajectories").string() + ": " + ec.message());
  {
    std::ofstream out = open(root / "metrics.json");
    out << metrics.dump(2) << '\n';
  }
  {
    std::ofstream out = open(root / "frames.csv");
    out << "frame,time_s,landmark_error,landmark_rms,landmark_static_error,map_landmarks,map_moving";
    for (int id : r.robot_ids) out << ",robot" << id << "_error,robot" << id << "_uncertainty";
    out << '\n';
    for (const auto& f : r.frames) {
      out << f.frame << ',' << f.time_s << ',' << f.landmark_error << ',' << f.landmark_rms << ','
          << f.landmark_static_error << ',' << f.map_landmarks << ',' << f.map_moving;
      for (std::size_t i = 0; i < r.robot_ids.size(); ++i)
        out << ',' << (i < f.robot_error.size() ? f.robot_error[i] : NAN) << ','
            << (i < f.robot_uncertainty.size() ? f.robot_uncertainty[i] : NAN);
      out << '\n';
    }
  }
  for (std::size_t i = 0; i < r.robot_ids.size(); ++i) {
    const std::string base = "robot" + std::to_string(r.robot_ids[i]);
    std::ofstream est = open(root / "trajectories" / (base + ".tum"));
    write_tum(est, r.estimated[i]);
    std::ofstream gt = open(root / "trajectories" / (base + "_gt.tum"));
    write_tum(gt, r.truth[i]);
  }
  {
    // The final global map, for plots (true and estimated landmarks, ellipses).
    std::ofstream out = open(root / "map.csv");
    out << "id,true_x,true_y,truly_moving,status,est_x,est_y,cov_xx,cov_xy,cov_yy\n";
    std::vector<int> status(r.final_truth.size(), 0);
    for (const auto& l : r.final_map) {
      if (l.id < 0 || l.id >= static_cast<int>(r.final_truth.size())) continue;
      status[static_cast<std::size_t>(l.id)] = 1;
      out << l.id << ',' << r.final_truth[static_cast<std::size_t>(l.id)].x() << ','
          << r.final_truth[static_cast<std::size_t>(l.id)].y() << ',' << int(r.truly_moving[static_cast<std::size_t>(l.id)])
          << ",static," << l.p.x() << ',' << l.p.y() << ',' << l.cov(0, 0) << ',' << l.cov(0, 1) << ',' << l.cov(1, 1)
          << '\n';
    }
    for (std::size_t id = 0; id < r.final_truth.size(); ++id) {
      if (status[id]) continue;
      if (!r.truth_present.empty() && !r.truth_present[id]) continue;  // no such landmark
      const bool flagged = std::find(r.final_moving.begin(), r.final_moving.end(), static_cast<int>(id)) != r.final_moving.end();
      out << id << ',' << r.final_truth[id].x() << ',' << r.final_truth[id].y() << ',' << int(r.truly_moving[id]) << ','
          << (flagged ? "moving" : "absent") << ",,,,,\n";
    }
  }
}

void print_comparison(std::ostream& out, const RunInfo& info, const RunResult& r, const RunInfo& base_info,
                      const RunResult& base, const std::string& how) {
  const RunMetrics& a = r.metrics;
  const RunMetrics& b = base.metrics;
  auto change = [](double x, double ref) -> std::string {
    if (!(ref > 0.0) || !std::isfinite(x)) return "";
    std::ostringstream os;
    os << std::showpos << std::fixed << std::setprecision(0) << 100.0 * (x - ref) / ref << " %";
    return os.str();
  };
  auto row = [&](const std::string& name, double x, double ref) {
    out << "    " << std::left << std::setw(24) << name << std::right << std::fixed << std::setprecision(3)
        << std::setw(10) << x << std::setw(10) << ref << std::setw(10) << change(x, ref) << '\n';
  };
  out << "  against " << base_info.mode << " on the same scenario and seed (" << how << "):\n";
  out << "    " << std::left << std::setw(24) << "" << std::right << std::setw(10) << info.mode << std::setw(10)
      << base_info.mode << std::setw(10) << "change" << '\n';
  row("landmark error [m]", a.landmark_error_mean, b.landmark_error_mean);
  for (std::size_t i = 0; i < a.robots.size() && i < b.robots.size(); ++i)
    row("robot " + std::to_string(a.robots[i].id) + " error [m]", a.robots[i].error_mean, b.robots[i].error_mean);
  auto map_text = [](const RunResult& x) {
    return std::to_string(x.final_map.size()) + " + " + std::to_string(x.final_moving.size());
  };
  out << "    " << std::left << std::setw(24) << "final map, static + moving" << std::right << std::setw(10)
      << map_text(r) << std::setw(10) << map_text(base) << '\n';
  auto found = [](const RunMetrics& m) {
    return std::to_string(m.true_positives) + "/" + std::to_string(m.detectable);
  };
  out << "    " << std::left << std::setw(24) << "movers detected" << std::right << std::setw(10) << found(a)
      << std::setw(10) << found(b) << '\n';
  out.unsetf(std::ios::floatfield);
}

nlohmann::json baseline_json(const RunInfo& base_info, const RunResult& base, const std::string& how) {
  nlohmann::json j = metrics_json(base_info, base);
  for (const char* key : {"config", "command_line", "schema_version", "elaslam_version", "source"}) j.erase(key);
  j["how"] = how;
  return j;
}

void print_summary(std::ostream& out, const RunInfo& info, const RunResult& r) {
  const RunMetrics& m = r.metrics;
  out << std::fixed << std::setprecision(3);
  if (info.simulated)
    out << "mode " << info.mode << ", dynamism " << info.dynamism_percent << " %, speed " << info.speed_mps
        << " m/s, seed " << info.seed << ", " << m.frames << " frames\n";
  else
    out << "mode " << info.mode << ", " << (info.data.empty() ? std::string("recorded data") : info.data) << ", "
        << m.robots.size() << " robots, " << m.frames << " frames\n";
  out << "  global map landmark error (eq 18): " << m.landmark_error_mean << " m mean, " << m.landmark_error_rms
      << " m rms, " << m.landmark_error_static << " m static-only; final map " << r.final_map.size() << " static, "
      << r.final_moving.size() << " moving\n";
  out << "  robot   error_mean  error_rms  final_uncertainty\n";
  for (const auto& rm : m.robots)
    out << "  " << std::setw(5) << rm.id << "  " << std::setw(10) << rm.error_mean << "  " << std::setw(9)
        << rm.error_rms << "  " << std::setw(17) << std::setprecision(6) << rm.final_uncertainty << std::setprecision(3)
        << '\n';
  // Precision and recall of nothing say nothing: with no mover in the ground truth
  // every flag is a false alarm, and that is what is printed.
  if (m.detectable == 0)
    out << "  moving landmarks: none in the ground truth; " << m.flagged << " flagged (false alarms)\n";
  else
    out << "  moving landmarks: precision " << m.precision << ", recall " << m.recall << " (" << m.true_positives
        << " of " << m.detectable << " detected, " << m.flagged << " flagged), " << m.mean_frames_to_detect
        << " frames to detect\n";
  out << "  frame time: p50 " << m.frame_us_p50 << " us, p99 " << m.frame_us_p99 << " us, max " << m.frame_us_max
      << " us\n";
}

}  // namespace elaslam

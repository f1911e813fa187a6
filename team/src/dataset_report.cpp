// SPDX-License-Identifier: Apache-2.0
#include "elaslam/team/dataset_report.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "elaslam/eval/report.hpp"
#include "elaslam/team/parallel.hpp"

namespace elaslam {
namespace {

std::string f3(double v) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(3) << v;
  return s.str();
}

const char* barcodes_text(bool barcodes) { return barcodes ? ", robot barcodes kept" : ", robot barcodes removed"; }

// report.md's odometer calibration (robot.odometry_calibration on): each robot's
// final estimate per run, and the least-squares fit of Vicon's increments on the
// odometer's over the same frames (mrclam::fit_odometry; mrclam_stats prints it too).
void write_calibration(std::ostream& out, const mrclam::FrameSource& src, const std::vector<DatasetRun>& runs) {
  const bool any = std::any_of(runs.begin(), runs.end(), [](const DatasetRun& r) {
    return std::any_of(r.result.metrics.robots.begin(), r.result.metrics.robots.end(),
                       [](const RobotMetrics& m) { return m.calibration_estimated; });
  });
  if (!any) return;
  const auto pm = [](double v, double s, int digits) {
    std::ostringstream o;
    o << std::fixed << std::setprecision(digits) << v << " ± " << s;
    return o.str();
  };
  out << "\nOdometer calibration (robot.odometry_calibration): true increment = speed scale x reported "
         "translation, turn scale x reported turn + bias x dt. Each robot's own filter at the end of the run "
         "(estimate ± sigma), and the offline least-squares fit against Vicon over the same frames (windows of 5 s: "
         "mrclam_stats --calibration-window).\n\n"
         "| run | robot | turn scale | speed scale | turn bias [rad/s] |\n|---|---|---|---|---|\n";
  // Windows of 5 s: mrclam::fit_odometry says why.
  const int window = std::max(1, static_cast<int>(std::lround(5.0 / src.dt_s())));
  const int n = src.num_frames();
  for (const auto& [name, first] : {std::pair<const char*, int>{"offline fit (Vicon), the run", 0},
                                    std::pair<const char*, int>{"offline fit (Vicon), its second half", n / 2}})
    for (std::size_t i = 0; i < src.robot_ids().size(); ++i) {
      const mrclam::OdometryFit f = mrclam::fit_odometry(src, static_cast<int>(i), first, -1, window);
      out << "| " << name << " | " << src.robot_ids()[i] << " | " << std::fixed << std::setprecision(4)
          << f.turn_scale << " (" << f.turn_scale_without_bias << " without bias) | " << f.speed_scale << " | "
          << std::setprecision(5) << f.turn_bias_rad_s << " |\n";
    }
  for (const auto& run : runs)
    for (const auto& rm : run.result.metrics.robots) {
      if (!rm.calibration_estimated) continue;
      out << "| " << run.mode << (run.barcodes ? ", robot barcodes kept" : "") << " | " << rm.id << " | "
          << pm(rm.turn_scale, rm.turn_scale_sigma, 4) << " | " << pm(rm.speed_scale, rm.speed_scale_sigma, 4)
          << " | " << pm(rm.turn_bias_rad_s, rm.turn_bias_sigma_rad_s, 5) << " |\n";
    }
}

// A track score as "position / speed / heading / stops found of true (latency) /
// NEES": "-" where nothing was scored.
std::string track_cells(const TrackMetrics& t) {
  const auto fig = [](std::int64_t n, double v, int digits) {
    if (n <= 0) return std::string("-");
    std::ostringstream o;
    o << std::fixed << std::setprecision(digits) << v;
    return o.str();
  };
  return fig(t.samples, t.position_rms_m, 3) + " | " + fig(t.moving_samples, t.speed_rms_mps, 3) + " | " +
         fig(t.moving_samples, t.heading_rms_deg, 0) + " | " + std::to_string(t.stops_found) + " / " +
         std::to_string(t.stops) + " (" + fig(t.stops_found, t.stop_latency_s, 2) + " s) | " +
         fig(t.nees_samples, t.nees_mean, 1) + " | " + std::to_string(t.samples);
}

// report.md's tracks of moving landmarks (robot.tracking): with the robot barcodes
// kept, the other robots are the movers and Vicon their truth (docs/tracking.md).
void write_tracks(std::ostream& out, const std::vector<DatasetRun>& runs) {
  const bool any = std::any_of(runs.begin(), runs.end(), [](const DatasetRun& r) {
    return r.result.metrics.tracks_scored && r.result.metrics.tracks.samples > 0;
  });
  if (!any) return;
  out << "\nTracks of moving landmarks (robot.tracking) against Vicon: position RMS [m], speed RMS [m/s] and "
         "heading RMS [deg] (true speed above 0.03 m/s), stops found of true stops (mean latency), mean NEES of "
         "(p, v) (4 dof), samples. 'from 5th sighting': samples of a track from its fifth sighting on; 'true "
         "observer pose': the same sightings tracked from the observer's Vicon pose (tracking error alone).\n\n"
         "| run | scored | position | speed | heading | stops | NEES | samples |\n"
         "|---|---|---|---|---|---|---|---|\n";
  for (const auto& run : runs) {
    const RunMetrics& m = run.result.metrics;
    if (!m.tracks_scored || m.tracks.samples == 0) continue;
    const std::string name = run.mode + (run.barcodes ? ", robot barcodes kept" : "");
    out << "| " << name << " | all | " << track_cells(m.tracks) << " |\n";
    out << "| " << name << " | from 5th sighting | " << track_cells(m.tracks_established) << " |\n";
    if (!m.tracks_true_pose_scored) continue;
    out << "| " << name << " | true observer pose | " << track_cells(m.tracks_true_pose) << " |\n";
    out << "| " << name << " | true observer pose, from 5th sighting | "
        << track_cells(m.tracks_true_pose_established) << " |\n";
  }
}

// One run's summary as run_dataset prints it after writing its files.
void print_run(std::ostream& log, const RunInfo& info, const DatasetRun& run, const std::vector<DeadReckoning>& dr) {
  log << "== " << run.mode << barcodes_text(run.barcodes) << '\n';
  print_summary(log, info, run.result);
  log << "  dead reckoning RMS:";
  for (const auto& d : dr) log << " robot " << d.id << ' ' << f3(d.error_rms);
  log << "\n  robot-barcode observations that corrected a pose: " << run.robot_corrections << "\n";
  log << "  landmarks taken as moving where a robot was (main.body_radius_m): " << run.result.occupied << "\n";
  const RunMetrics& m = run.result.metrics;
  if (m.tracks_scored && m.tracks.samples > 0) {
    log << "  tracks (position m | speed m/s | heading deg | stops (latency) | NEES | samples): all "
        << track_cells(m.tracks) << "; from 5th sighting " << track_cells(m.tracks_established) << '\n';
    if (m.tracks_true_pose_scored)
      log << "  tracks from the true observer pose: all " << track_cells(m.tracks_true_pose)
          << "; from 5th sighting " << track_cells(m.tracks_true_pose_established) << '\n';
  }
  log << "  rounds of team maps each robot was left out of (main.team_map_check_probability):";
  for (std::size_t i = 0; i < run.result.robot_ids.size(); ++i)
    log << " robot " << run.result.robot_ids[i] << ' ' << run.result.team_map_left_out[i];
  log << '\n';
}

}  // namespace

long robot_corrections(const RunResult& r) {
  long n = 0;
  for (int id = 1; id <= mrclam::kMaxRobotSubject; ++id)
    if (id < static_cast<int>(r.corrections_by_landmark.size())) n += r.corrections_by_landmark[static_cast<std::size_t>(id)];
  return n;
}

std::vector<DatasetRun> dataset_runs(const std::vector<std::string>& modes, bool report, bool barcodes) {
  std::vector<DatasetRun> runs;
  for (const auto& m : modes) {
    if (report || !barcodes) runs.push_back({m, false, {}, 0});
    if (report || barcodes) runs.push_back({m, true, {}, 0});
  }
  return runs;
}

bool parse_mode_list(const std::string& text, std::vector<std::string>* modes, std::string* why) {
  std::stringstream ss(text);
  for (std::string m; std::getline(ss, m, ',');) {
    Mode parsed;
    if (!parse_mode(m, &parsed)) {
      *why = "unknown mode '" + m + "' (ekf, gated, ela, consensus)";
      return false;
    }
    modes->push_back(m);
  }
  return true;
}

DatasetSources load_sources(const std::string& dir, const mrclam::Options& o, bool without, bool with) {
  DatasetSources src;
  src.data = std::make_unique<mrclam::Dataset>(mrclam::Dataset::load(dir, o.robots));
  mrclam::Options no = o, yes = o;
  no.with_robot_barcodes = false;
  yes.with_robot_barcodes = true;
  if (without) src.without = std::make_unique<mrclam::FrameSource>(*src.data, no);
  if (with) src.with = std::make_unique<mrclam::FrameSource>(*src.data, yes);
  return src;
}

void run_dataset_runs(const DatasetConfig& cfg, const DatasetSources& src, int jobs, std::vector<DatasetRun>* runs) {
  run_parallel(runs->size(), jobs, [&](std::size_t i) {
    DatasetRun& run = (*runs)[i];
    RobotOptions ro = cfg.robot;
    parse_mode(run.mode, &ro.mode);
    DatasetFrames frames(src.of(run.barcodes));
    run.result = run_team(ro, cfg.main, frames);
    run.robot_corrections = robot_corrections(run.result);
  });
}

nlohmann::json dataset_json(const mrclam::FrameSource& src, const mrclam::Options& o, const std::string& dir,
                            const std::vector<DeadReckoning>& dr) {
  nlohmann::json j;
  j["dir"] = dir;
  j["rate_hz"] = o.rate_hz;
  j["with_robot_barcodes"] = o.with_robot_barcodes;
  j["frames"] = src.num_frames();
  j["start_utime"] = src.frame_utime(0);
  nlohmann::json robots = nlohmann::json::array();
  for (std::size_t i = 0; i < src.stats().robots.size(); ++i) {
    const auto& s = src.stats().robots[i];
    robots.push_back({{"id", s.id},
                      {"measurements", s.measurements},
                      {"used", s.used},
                      {"misreads", s.misreads},
                      {"robot_barcodes", s.robot_barcodes},
                      {"duplicates", s.duplicates},
                      {"odometry_gaps", s.odometry_gaps},
                      {"dead_reckoning_error_mean", dr[i].error_mean},
                      {"dead_reckoning_error_rms", dr[i].error_rms}});
  }
  j["robots"] = robots;
  return j;
}

std::vector<std::string> write_dataset_runs(const DatasetOutputs& out, const DatasetConfig& cfg,
                                            const DatasetSources& src, const std::vector<DeadReckoning>& dr,
                                            const std::vector<DatasetRun>& runs, std::ostream& log) {
  std::vector<std::string> dirs;
  nlohmann::json all = nlohmann::json::array();
  for (const auto& run : runs) {
    mrclam::Options so = cfg.dataset;
    so.with_robot_barcodes = run.barcodes;
    RunInfo info{run.mode, 0.0, 0.0, 0, out.config_path, cfg.effective_yaml, out.command};
    info.simulated = false;
    info.data = "MRCLAM " + std::filesystem::path(out.dataset_dir).lexically_normal().filename().string() +
                barcodes_text(run.barcodes);
    nlohmann::json j = metrics_json(info, run.result);
    j["dataset"] = dataset_json(src.of(run.barcodes), so, out.dataset_dir, dr);
    j["robot_barcode_corrections"] = run.robot_corrections;
    j["landmarks_where_a_robot_was"] = run.result.occupied;  // main.body_radius_m
    j["team_map_rounds_left_out"] = run.result.team_map_left_out;  // by robot, main.team_map_check_probability
    const std::string dir = out.report ? out.out_dir + "/" + run.mode + (run.barcodes ? "_barcodes" : "") : out.out_dir;
    write_outputs(dir, j, run.result);
    dirs.push_back(dir);
    all.push_back(j);
    print_run(log, info, run, dr);
  }
  if (out.report) {
    const std::string path = out.out_dir + "/report.md";
    std::ofstream md(path);
    if (!md) throw std::runtime_error("cannot write " + path);
    write_dataset_report(md, src.any(), dr, runs, out.command);
    std::ofstream(out.out_dir + "/report.json") << all.dump(1) << '\n';
    log << "wrote " << out.out_dir << "/report.md\n";
  }
  return dirs;
}

void write_dataset_report(std::ostream& out, const mrclam::FrameSource& src, const std::vector<DeadReckoning>& dr,
                          const std::vector<DatasetRun>& runs, const std::string& command) {
  out << "# MRCLAM run report\n\nCommand: `" << command << "`\n\n" << src.num_frames() << " frames at "
      << 1.0 / src.dt_s() << " Hz (" << f3(src.num_frames() * src.dt_s()) << " s), robots";
  for (int id : src.robot_ids()) out << ' ' << id;
  out << ".\n\nPosition error against Vicon per robot, RMS / mean over the frames [m]; the last column is the mean over "
         "robots of each robot's RMS (the reference figures' statistic).\n\n| run |";
  for (int id : src.robot_ids()) out << " robot " << id << " |";
  out << " mean of RMS | global map error [m] | robot-barcode corrections |\n|---|";
  for (std::size_t i = 0; i < src.robot_ids().size() + 3; ++i) out << "---|";
  out << '\n';
  double dr_mean = 0.0;
  out << "| dead reckoning |";
  for (const auto& d : dr) {
    out << ' ' << f3(d.error_rms) << " / " << f3(d.error_mean) << " |";
    dr_mean += d.error_rms / static_cast<double>(dr.size());
  }
  out << ' ' << f3(dr_mean) << " | - | - |\n";
  for (const auto& run : runs) {
    const RunMetrics& m = run.result.metrics;
    double mean = 0.0;
    out << "| " << run.mode << (run.barcodes ? ", robot barcodes kept" : "") << " |";
    for (const auto& rm : m.robots) {
      out << ' ' << f3(rm.error_rms) << " / " << f3(rm.error_mean) << " |";
      mean += rm.error_rms / static_cast<double>(m.robots.size());
    }
    out << " **" << f3(mean) << "** | " << f3(m.landmark_error_mean) << " | "
        << (run.barcodes ? std::to_string(run.robot_corrections) : std::string("-")) << " |\n";
  }
  out << "\nRobot-barcode corrections: observations of another robot's barcode that corrected a robot's pose "
         "(summed over robots; candidates' landmark-only updates not counted). Sightings available: ";
  long avail = 0;
  for (const auto& s : src.stats().robots) avail += s.robot_barcodes;
  out << avail << ".\n";
  write_calibration(out, src, runs);
  write_tracks(out, runs);
}

}  // namespace elaslam

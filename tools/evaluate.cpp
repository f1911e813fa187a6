// evaluate: the metrics of a recorded run (an LCM log of the live team, made by
// lcm-logger) against its ground truth, with the same definitions and output files
// as run_scenario, plus latency and dropped frames.
//   evaluate --log FILE [--out DIR] [--mode NAME] [--quiet]
//
// Latency: POSE_<r> receive time in the log (lcm-logger's timestamp) minus its
// source_utime (the SENSOR frame's publish time), `latency_us`; the robot's own
// publish time of the POSE (its utime) minus source_utime, `pose_publish_latency_us`
// (sensor publish to pose publish: no logger hop); global-map latency: receive time
// of the first GLOBAL_MAP whose frame is >= k minus the latest SENSOR utime of
// frame k. Both clocks are the same machine's wall clock.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include "elaslam/global_map_t.hpp"
#include "elaslam/ground_truth_t.hpp"
#include "elaslam/node_status_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/sensor_frame_t.hpp"
#include "elaslam/team/report.hpp"

namespace elaslam {
namespace {

struct PoseRecord {
  pose_estimate_t msg;
  std::int64_t received_us = 0;
};

struct MapRecord {
  std::vector<std::pair<int, Eigen::Vector2d>> landmarks;
  std::vector<RunResult::MapLandmark> full;
  std::vector<int> moving;
  std::int64_t received_us = 0;
};

struct LogData {
  std::map<int, FrameData> truth;                       // frame -> truth part
  std::map<int, std::map<int, PoseRecord>> poses;       // frame -> robot -> pose
  std::map<int, std::int64_t> sensor_utime;             // frame -> latest SENSOR utime
  std::map<int, std::vector<int>> observed;             // frame -> observed ids
  std::map<int, MapRecord> maps;                        // frame -> first GLOBAL_MAP of that frame
  std::map<int, std::int64_t> first_map_receive;        // frame -> first receive of a map with that frame
  std::map<int, std::int64_t> node_dropped;             // robot -> last STATUS frames_dropped
  std::map<std::string, long> decode_errors;
  long events = 0;
};

template <typename Msg>
bool decode(const lcm::LogEvent* ev, Msg* m, LogData* d) {
  if (m->decode(ev->data, 0, static_cast<int>(ev->datalen)) >= 0) return true;
  ++d->decode_errors[ev->channel];
  return false;
}

void on_truth(const ground_truth_t& gt, LogData* d) {
  FrameData f;
  f.frame = gt.frame;
  for (int i = 0; i < gt.num_robots && i < 8; ++i) {
    f.robot_ids.push_back(gt.robot_ids[i]);
    f.true_poses.push_back({gt.robots[i].x, gt.robots[i].y, gt.robots[i].theta});
  }
  int max_id = -1;
  for (int i = 0; i < gt.num_landmarks && i < 256; ++i) max_id = std::max(max_id, gt.landmarks[i].id);
  f.true_landmarks.assign(static_cast<std::size_t>(max_id + 1), Eigen::Vector2d::Zero());
  f.truly_moving.assign(static_cast<std::size_t>(max_id + 1), 0);
  for (int i = 0; i < gt.num_landmarks && i < 256; ++i) {
    const auto& l = gt.landmarks[i];
    if (l.id < 0) continue;
    f.true_landmarks[static_cast<std::size_t>(l.id)] = {l.x, l.y};
    f.truly_moving[static_cast<std::size_t>(l.id)] = l.moving ? 1 : 0;
  }
  f.time_s = static_cast<double>(gt.utime) * 1e-6;
  d->truth[gt.frame] = std::move(f);
}

void on_map(const global_map_t& g, std::int64_t received, LogData* d) {
  MapRecord m;
  m.received_us = received;
  for (int i = 0; i < g.num_landmarks && i < 256; ++i) {
    const auto& l = g.landmarks[i];
    m.landmarks.push_back({l.id, {l.x, l.y}});
    Eigen::Matrix2d C;
    C << l.cov[0][0], l.cov[0][1], l.cov[1][0], l.cov[1][1];
    m.full.push_back({l.id, {l.x, l.y}, C});
  }
  for (int i = 0; i < g.num_moving && i < 256; ++i) m.moving.push_back(g.moving_ids[i]);
  // The first GLOBAL_MAP stamped k is the one main_robot sends when every robot has
  // finished frame k; later ones stamped k (the periodic publication) may already
  // hold some of frame k+1's events.
  d->maps.emplace(g.frame, std::move(m));
  d->first_map_receive.emplace(g.frame, received);
}

int robot_of(const std::string& channel, const std::string& prefix) {
  if (channel.rfind(prefix, 0) != 0) return -1;
  try {
    return std::stoi(channel.substr(prefix.size()));
  } catch (const std::exception&) {
    return -1;
  }
}

// Read every event; our channels are decoded, others ignored.
bool read_log(const std::string& path, LogData* d, std::string* why) {
  lcm::LogFile log(path, "r");
  if (!log.good()) {
    *why = "cannot open the log " + path;
    return false;
  }
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    ++d->events;
    const std::string& ch = ev->channel;
    if (ch == "GROUND_TRUTH") {
      ground_truth_t m;
      if (decode(ev, &m, d)) on_truth(m, d);
    } else if (ch == "GLOBAL_MAP") {
      global_map_t m;
      if (decode(ev, &m, d)) on_map(m, ev->timestamp, d);
    } else if (robot_of(ch, "POSE_") > 0) {
      pose_estimate_t m;
      if (decode(ev, &m, d)) d->poses[m.frame][m.robot_id] = {m, ev->timestamp};
    } else if (robot_of(ch, "SENSOR_") > 0) {
      sensor_frame_t m;
      if (!decode(ev, &m, d)) continue;
      auto& t = d->sensor_utime[m.frame];
      t = std::max(t, m.utime);
      for (int i = 0; i < m.num_obs && i < 64; ++i) d->observed[m.frame].push_back(m.obs[i].landmark_id);
    } else if (robot_of(ch, "STATUS_ROBOT_") > 0) {
      node_status_t m;
      if (decode(ev, &m, d)) d->node_dropped[m.node_id] = m.frames_dropped;
    }
  }
  if (d->truth.empty()) {
    *why = "no GROUND_TRUTH in " + path + " (was the simulator's channel recorded?)";
    return false;
  }
  return true;
}

struct Quantiles {
  std::int64_t p50 = 0, p99 = 0, max = 0;
  std::size_t count = 0;
};

Quantiles quantiles(std::vector<std::int64_t> v) {
  Quantiles q;
  q.count = v.size();
  if (v.empty()) return q;
  std::sort(v.begin(), v.end());
  auto at = [&](double f) { return v[std::min(v.size() - 1, static_cast<std::size_t>(f * static_cast<double>(v.size())))]; };
  q.p50 = at(0.5);
  q.p99 = at(0.99);
  q.max = v.back();
  return q;
}

nlohmann::json to_json(const Quantiles& q) {
  return {{"p50", q.p50}, {"p99", q.p99}, {"max", q.max}, {"count", q.count}};
}

}  // namespace
}  // namespace elaslam

int main(int argc, char** argv) {
  using namespace elaslam;
  std::string log_path, out_dir, mode = "unknown";
  bool quiet = false;
  double dynamism = -1.0, speed = -1.0;
  long long seed = -1;
  CLI::App app{"elaslam evaluate: metrics of a recorded LCM log against its ground truth"};
  app.add_option("--log", log_path, "LCM log (lcm-logger)")->required();
  app.add_option("--out", out_dir, "directory for metrics.json, frames.csv, trajectories/");
  app.add_option("--mode", mode, "mode name to record in metrics.json");
  app.add_flag("--quiet", quiet, "no summary on stdout");
  // The log does not carry the run's settings: the launcher passes them to record.
  app.add_option("--dynamism", dynamism, "dynamism [%] to record (default: from the ground truth's moving flags)");
  app.add_option("--speed", speed, "landmark speed [m/s] to record");
  app.add_option("--seed", seed, "seed to record");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  LogData d;
  std::string why;
  if (!read_log(log_path, &d, &why)) {
    std::fprintf(stderr, "evaluate: %s\n", why.c_str());
    return 2;
  }
  const std::vector<int> robot_ids = d.truth.begin()->second.robot_ids;
  const std::size_t R = robot_ids.size();
  MetricsAccumulator acc;
  RunResult r;
  r.estimated.resize(R);
  r.truth.resize(R);
  std::vector<std::vector<std::int64_t>> latency(R), publish_latency(R);
  std::vector<std::int64_t> all_latency, all_publish_latency, map_latency;
  std::vector<long> missing(R, 0);
  const double t0 = d.truth.begin()->second.time_s;
  const MapRecord* map = nullptr;
  for (auto& [k, f] : d.truth) {
    f.time_s -= t0;
    f.has_pose.assign(R, 0);
    f.est_poses.assign(R, Pose2{});
    f.mean_diag_p.assign(R, 0.0);
    f.processing_us.assign(R, 0);
    const auto poses = d.poses.find(k);
    for (std::size_t i = 0; i < R && i < f.robot_ids.size(); ++i) {
      const PoseRecord* p = nullptr;
      if (poses != d.poses.end()) {
        const auto it = poses->second.find(f.robot_ids[i]);
        if (it != poses->second.end()) p = &it->second;
      }
      if (!p) {
        ++missing[i];
        continue;
      }
      f.has_pose[i] = 1;
      f.est_poses[i] = {p->msg.x, p->msg.y, p->msg.theta};
      f.mean_diag_p[i] = p->msg.mean_diag_p;
      f.processing_us[i] = p->msg.processing_us;
      latency[i].push_back(p->received_us - p->msg.source_utime);
      all_latency.push_back(latency[i].back());
      publish_latency[i].push_back(p->msg.utime - p->msg.source_utime);
      all_publish_latency.push_back(publish_latency[i].back());
      r.estimated[i].push_back({f.time_s, f.est_poses[i]});
      r.truth[i].push_back({f.time_s, f.true_poses[i]});
    }
    // The map of frame k: the first one stamped k, else the newest older one.
    const auto m = d.maps.upper_bound(k);
    if (m != d.maps.begin()) map = &std::prev(m)->second;
    f.map_landmarks = map ? map->landmarks : decltype(f.map_landmarks){};
    f.map_moving = map ? map->moving : std::vector<int>{};
    f.observed = d.observed[k];
    const auto first = d.first_map_receive.lower_bound(k);
    const auto sensed = d.sensor_utime.find(k);
    if (first != d.first_map_receive.end() && sensed != d.sensor_utime.end())
      map_latency.push_back(first->second - sensed->second);
    acc.add(f);
  }
  r.metrics = acc.finish();
  r.frames = acc.frames();
  r.robot_ids = acc.robot_ids();
  if (map) {
    r.final_map = map->full;
    r.final_moving = map->moving;
  }
  r.final_truth = d.truth.rbegin()->second.true_landmarks;
  r.truly_moving = d.truth.rbegin()->second.truly_moving;

  const FrameData& last = d.truth.rbegin()->second;
  int moving = 0;
  for (auto m : last.truly_moving) moving += m;
  const double moving_percent =
      last.truly_moving.empty() ? 0.0 : 100.0 * moving / static_cast<double>(last.truly_moving.size());
  RunInfo info{mode, dynamism >= 0.0 ? dynamism : moving_percent, std::max(speed, 0.0), std::max(seed, 0LL), log_path, ""};
  nlohmann::json j = metrics_json(info, r);
  long dropped = 0;
  for (std::size_t i = 0; i < R; ++i) {
    j["robots"][i]["latency_us"] = to_json(quantiles(latency[i]));
    j["robots"][i]["pose_publish_latency_us"] = to_json(quantiles(publish_latency[i]));
    j["robots"][i]["frames_dropped"] = missing[i];
    const auto nd = d.node_dropped.find(robot_ids[i]);
    j["robots"][i]["frames_dropped_reported_by_node"] = nd != d.node_dropped.end() ? nd->second : 0;
    dropped += missing[i];
  }
  const Quantiles lq = quantiles(all_latency), mq = quantiles(map_latency), pq = quantiles(all_publish_latency);
  j["latency_us"] = to_json(lq);
  j["pose_publish_latency_us"] = to_json(pq);
  j["global_map_latency_us"] = to_json(mq);
  j["frames_dropped"] = dropped;
  j["log_events"] = d.events;
  for (const auto& [ch, n] : d.decode_errors) j["decode_errors"][ch] = n;
  if (!quiet) {
    print_summary(std::cout, info, r);
    std::cout << "  latency_us (sensor -> pose): p50 " << lq.p50 << " p99 " << lq.p99 << " max " << lq.max << " ("
              << lq.count << " poses)\n"
              << "  pose publish latency_us (sensor publish -> pose publish): p50 " << pq.p50 << " p99 " << pq.p99
              << " max " << pq.max << "\n"
              << "  global map latency_us (sensor -> map including the frame): p50 " << mq.p50 << " p99 " << mq.p99
              << " max " << mq.max << "\n"
              << "  frames dropped: " << dropped << "\n";
    for (const auto& [ch, n] : d.decode_errors) std::cout << "  undecodable events on " << ch << ": " << n << "\n";
  }
  if (!out_dir.empty()) {
    try {
      write_outputs(out_dir, j, r);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "evaluate: %s\n", e.what());
      return 1;
    }
  }
  return 0;
}

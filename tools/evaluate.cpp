// SPDX-License-Identifier: Apache-2.0
// evaluate: the metrics of a recorded run (an LCM log of the live team, made by
// lcm-logger) against its ground truth, with the same definitions and output files
// as run_scenario, plus latency and frame accounting.
//   evaluate --log FILE [--out DIR] [--config FILE] [--baseline MODE] [--quiet]
//            [--channel-suffix S] [--mode M] [--dynamism P] [--speed V] [--seed S]
//
// What the run was comes from the log: RUN_INFO (the frame source's scenario, seed,
// dynamism, speed, rate, frames, effective config) and the robots' STATUS (their
// mode). --mode / --dynamism / --speed / --seed are fallbacks for logs without them.
// --config FILE: the team's config file; with RUN_INFO's values over it, it becomes
// the effective config echoed into metrics.json (without it only the frame source's
// section is known). --baseline MODE (needs --config): the same scenario and seed in
// process with MODE (e.g. plain ekf), side by side with the live run.
//
// Frames per robot (team/frame_accounting.hpp, account_frames): a frame is "dropped" only
// when the robot did not process it after it had started; frames before its first
// are "not started"; a frame it processed whose POSE is not in the log is the
// recorder's loss ("missing from the log"), told apart by POSE.frames_processed.
//
// Latency: POSE_<r> receive time in the log (lcm-logger's timestamp) minus its
// source_utime (the SENSOR frame's publish time), `latency_us`; the robot's own
// publish time of the POSE (its utime) minus source_utime, `pose_publish_latency_us`
// (sensor publish to pose publish: no logger hop); global-map latency: receive time
// of the first GLOBAL_MAP whose frame is >= k minus the latest SENSOR utime of
// frame k. Both clocks are the same machine's wall clock.
#include <algorithm>
#include <array>
#include <cstdio>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/cli.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/common/cov.hpp"
#include "elaslam/common/quantile.hpp"
#include "elaslam/global_map_t.hpp"
#include "elaslam/ground_truth_t.hpp"
#include "elaslam/node_status_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/run_info_t.hpp"
#include "elaslam/sensor_frame_t.hpp"
#include "elaslam/team/frame_accounting.hpp"
#include "elaslam/team/log_auth.hpp"
#include "elaslam/team/log_reader.hpp"
#include "elaslam/team/log_summary.hpp"
#include "elaslam/team/frame_data.hpp"
#include "elaslam/team/report.hpp"
#include "elaslam/team/team_run.hpp"

namespace elaslam {
namespace {

struct PoseRecord {
  pose_estimate_t msg;
  std::int64_t received_us = 0;
};

struct MapRecord {
  std::vector<std::pair<int, Eigen::Vector2d>> landmarks;
  std::vector<int> moving;
  std::vector<RunResult::MapLandmark> full;  // with covariances, for map.csv
  std::int64_t received_us = 0;
};

struct LogData {
  std::map<int, FrameData> truth;                       // frame -> truth part
  std::map<int, std::map<int, PoseRecord>> poses;       // frame -> robot -> pose
  std::map<int, std::int64_t> sensor_utime;             // frame -> latest SENSOR utime
  std::map<int, std::vector<int>> observed;             // frame -> observed ids
  std::map<int, MapRecord> maps;                        // frame -> first GLOBAL_MAP of that frame
  std::map<int, std::int64_t> first_map_receive;        // frame -> first receive of a map with that frame
  std::map<int, std::vector<StatusCheckpoint>> status;  // robot -> STATUS_ROBOT checkpoints
  std::map<int, std::vector<int>> sensor_frames;        // robot -> SENSOR frames seen
  std::map<int, int> robot_mode;                        // robot -> node_status_t::MODE_* (last)
  std::optional<run_info_t> run_info;                   // the last RUN_INFO
  std::map<std::string, long> decode_errors;
  // Messages that decode but that a node would refuse (frame_data.hpp, check_logged):
  // not evaluated; per channel and reason.
  std::map<std::string, std::map<std::string, long>> invalid;
  MessageLimits limits;
  // From STATUS_ROBOT_<r> / STATUS_MAIN / STATUS_SIM: nodes that raised FAULT_CAPACITY
  // (results no longer what the inputs said), and each node's last refusal counts.
  std::set<std::string> capacity_faults;
  std::map<std::string, std::array<std::int64_t, kNumRefusals>> refused;
  long events = 0;
  std::int64_t bytes_skipped = 0;  // [bytes] between events, not an event (a damaged log)
  bool complete = true;            // false: the log ends in a truncated event
  GlobalMapAssembly map_assembly;  // GLOBAL_MAP chunks -> the map of one publication
  // With the team's roster (the --config's team.public_keys and mission): events are
  // verified as the nodes verify them; what they refuse (forged, another mission,
  // replayed...) is not evaluated.
  std::unique_ptr<LogAuth> auth;
  std::string roster;
};

template <typename Msg>
bool decode(const LogEvent& ev, Msg* m, LogData* d) {
  try {  // a negative count of a variable-length array makes LCM's decoder throw
    if (m->decode(ev.data.data(), 0, static_cast<int>(ev.data.size())) >= 0) return true;
  } catch (const std::exception&) {
  }
  ++d->decode_errors[ev.channel];
  return false;
}

/// True when the message holds; else counted (channel, reason) and to be skipped.
template <typename Msg, typename... Extra>
bool holds(const LogEvent& ev, const Msg& m, LogData* d, Extra... extra) {
  Refusal reason = Refusal::kMalformed;
  if (check_logged(m, extra..., d->limits, &reason).empty()) return true;
  ++d->invalid[ev.channel][to_string(reason)];
  return false;
}

void note_health(const std::string& channel, const node_status_t& m, LogData* d) {
  if (m.fault_flags & node_status_t::FAULT_CAPACITY) d->capacity_faults.insert(channel);
  auto& r = d->refused[channel];
  for (int k = 0; k < kNumRefusals; ++k) r[static_cast<std::size_t>(k)] = m.refused[k];
}

void on_map(const global_map_t& g, std::int64_t received, LogData* d) {
  MapRecord m;
  m.received_us = received;
  read_map(g, &m.landmarks, &m.moving);
  for (int i = 0; i < contract::bounded(g.num_landmarks, static_cast<int>(g.landmarks.size())); ++i) {
    const auto& l = g.landmarks[i];
    m.full.push_back({l.id, {l.x, l.y}, read_cov(l.cov)});
  }
  // The first GLOBAL_MAP stamped k is the one main_robot sends when every robot has
  // finished frame k; later ones stamped k (the periodic publication) may already
  // hold some of frame k+1's events.
  d->maps.emplace(g.frame, std::move(m));
  d->first_map_receive.emplace(g.frame, received);
}


// One event of the log: the team's channels (with its suffix) are decoded (an
// undecodable one is counted), others ignored.
void on_event(const LogEvent& ev, const std::string& sfx, LogData* d) {
  const std::string& ch = ev.channel;
  if (ch == channels::ground_truth(sfx)) {
    ground_truth_t m;
    if (!decode(ev, &m, d)) return;
    FrameData& f = d->truth[m.frame];
    set_truth(m, &f);
    f.time_s = static_cast<double>(m.utime) * 1e-6;
  } else if (ch == channels::global_map(sfx)) {
    global_map_t m;
    if (decode(ev, &m, d) && holds(ev, m, d) && d->map_assembly.add(m)) on_map(d->map_assembly.map(), ev.timestamp, d);
  } else if (channels::robot_of(ch, "POSE_", sfx) > 0) {
    pose_estimate_t m;
    // The first valid POSE of a robot's frame (a later copy is a duplicate or a replay).
    if (decode(ev, &m, d) && holds(ev, m, d, ev.timestamp)) d->poses[m.frame].emplace(m.robot_id, PoseRecord{m, ev.timestamp});
  } else if (ch == channels::run_info(sfx)) {
    run_info_t m;
    if (decode(ev, &m, d)) d->run_info = m;
  } else if (channels::robot_of(ch, "SENSOR_", sfx) > 0) {
    sensor_frame_t m;
    if (!decode(ev, &m, d) || !holds(ev, m, d)) return;
    d->sensor_frames[m.robot_id].push_back(m.frame);
    auto& t = d->sensor_utime[m.frame];
    t = std::max(t, m.utime);
    add_observed(m, &d->observed[m.frame]);
  } else if (ch == channels::status_main(sfx) || ch == channels::status_sim(sfx)) {
    node_status_t m;
    if (!decode(ev, &m, d)) return;
    note_health(ch, m, d);
  } else if (channels::robot_of(ch, "STATUS_ROBOT_", sfx) > 0) {
    node_status_t m;
    if (!decode(ev, &m, d)) return;
    note_health(ch, m, d);
    d->status[m.node_id].push_back({m.frame, m.frames, m.frames_dropped});
    if (m.mode != node_status_t::MODE_NONE) d->robot_mode[m.node_id] = m.mode;
  }
}

// A damaged log (stray bytes, a truncated tail) is read as far as it holds whole
// events (team/log_reader.hpp); what was skipped is counted.
bool read_log(const std::string& path, const std::string& suffix, LogData* d, std::string* why) {
  std::optional<LogReader> log;
  try {
    log.emplace(path);
  } catch (const std::runtime_error& e) {
    *why = e.what();
    return false;
  }
  LogEvent ev;
  while (log->next(&ev)) {
    ++d->events;
    if (d->auth && !d->auth->admit(&ev)) continue;
    on_event(ev, suffix, d);
  }
  d->bytes_skipped = log->skipped();
  d->complete = log->complete();
  if (d->truth.empty() && d->auth && d->auth->refused() > 0 && d->auth->accepted() == 0) {
    *why = "no event of " + path + " verifies with the roster and mission of " + d->roster + " (" +
           std::to_string(d->auth->refused()) + " refused): another team or mission recorded it";
    return false;
  }
  if (d->truth.empty()) {
    *why = "no " + channels::ground_truth(suffix) + " in " + path + " (was the simulator's channel recorded?)";
    return false;
  }
  return true;
}

struct Quantiles {
  std::int64_t p50 = 0, p99 = 0, max = 0;
  std::size_t count = 0;
};

Quantiles quantiles(const std::vector<std::int64_t>& v) {
  Quantiles q;
  q.count = v.size();
  if (v.empty()) return q;
  q.p50 = quantile(v, 0.5);
  q.p99 = quantile(v, 0.99);
  q.max = *std::max_element(v.begin(), v.end());
  return q;
}

nlohmann::json to_json(const Quantiles& q) {
  return {{"p50", q.p50}, {"p99", q.p99}, {"max", q.max}, {"count", q.count}};
}

/// The log as the metrics' frames, with the latencies and each robot's POSE
/// checkpoints (for the frame accounting) gathered on the way.
struct Assembled {
  RunResult r;
  std::vector<int> robot_ids;
  std::vector<std::vector<std::int64_t>> latency, publish_latency;  // [us] per robot
  std::vector<std::int64_t> all_latency, all_publish_latency, map_latency;
  std::vector<std::vector<PoseCheckpoint>> checkpoints;  // per robot
};

const PoseRecord* pose_of(const LogData& d, int frame, int robot_id) {
  const auto poses = d.poses.find(frame);
  if (poses == d.poses.end()) return nullptr;
  const auto it = poses->second.find(robot_id);
  return it != poses->second.end() ? &it->second : nullptr;
}

void add_pose(std::size_t i, int k, const PoseRecord& p, FrameData* f, Assembled* x) {
  x->checkpoints[i].push_back({k, p.msg.frames_processed});
  set_pose(i, p.msg, f);
  x->latency[i].push_back(p.received_us - p.msg.source_utime);
  x->all_latency.push_back(x->latency[i].back());
  x->publish_latency[i].push_back(p.msg.utime - p.msg.source_utime);
  x->all_publish_latency.push_back(x->publish_latency[i].back());
  x->r.estimated[i].push_back({f->time_s, f->est_poses[i]});
  x->r.truth[i].push_back({f->time_s, f->true_poses[i]});
}

Assembled assemble(LogData& d) {
  Assembled x;
  x.robot_ids = d.truth.begin()->second.robot_ids;
  const std::size_t R = x.robot_ids.size();
  x.r.estimated.resize(R);
  x.r.truth.resize(R);
  x.latency.resize(R);
  x.publish_latency.resize(R);
  x.checkpoints.resize(R);
  MetricsAccumulator acc;
  const double t0 = d.truth.begin()->second.time_s;
  const MapRecord* map = nullptr;
  for (auto& [k, f] : d.truth) {
    f.time_s -= t0;
    clear_estimates(R, &f);
    for (std::size_t i = 0; i < R && i < f.robot_ids.size(); ++i)
      if (const PoseRecord* p = pose_of(d, k, f.robot_ids[i])) add_pose(i, k, *p, &f, &x);
    // The map of frame k: the first one stamped k, else the newest older one.
    const auto m = d.maps.upper_bound(k);
    if (m != d.maps.begin()) map = &std::prev(m)->second;
    f.map_landmarks = map ? map->landmarks : decltype(f.map_landmarks){};
    f.map_moving = map ? map->moving : std::vector<int>{};
    f.observed = d.observed[k];
    const auto first = d.first_map_receive.lower_bound(k);
    const auto sensed = d.sensor_utime.find(k);
    if (first != d.first_map_receive.end() && sensed != d.sensor_utime.end())
      x.map_latency.push_back(first->second - sensed->second);
    acc.add(f);
  }
  x.r.metrics = acc.finish();
  x.r.frames = acc.frames();
  x.r.robot_ids = acc.robot_ids();
  if (map) {
    x.r.final_map = map->full;
    x.r.final_moving = map->moving;
  }
  x.r.final_truth = d.truth.rbegin()->second.true_landmarks;
  x.r.truly_moving = d.truth.rbegin()->second.truly_moving;
  return x;
}

/// The robots' mode as they report it (STATUS_ROBOT): "" when they did not report
/// or disagree (then `*disagree`).
std::string reported_mode(const LogData& d, bool* disagree) {
  std::string mode;
  *disagree = false;
  for (const auto& [id, m] : d.robot_mode) {
    const std::string name = status_mode_name(m);
    if (mode.empty()) mode = name;
    if (name != mode) *disagree = true;
  }
  return *disagree ? "" : mode;
}

nlohmann::json run_info_json(const run_info_t& m) {
  nlohmann::json robots = nlohmann::json::array();
  const int n = contract::bounded(m.num_robots, static_cast<int>(m.robot_ids.size()));
  for (std::size_t i = 0; i < static_cast<std::size_t>(n); ++i) robots.push_back(m.robot_ids[i]);
  return {{"source", m.source},   {"version", m.version},
          {"scenario", m.scenario}, {"mode", m.mode},
          {"seed", m.seed},       {"dynamism_percent", m.dynamism_percent},
          {"landmark_speed_mps", m.landmark_speed_mps}, {"rate_hz", m.rate_hz},
          {"frames", m.frames},   {"robots", robots},
          {"schema_version", m.schema_version}};
}

struct Args {
  std::string log_path, out_dir, config, baseline, mode, channel_suffix, mission, roster;
  bool quiet = false;
  double dynamism = -1.0, speed = -1.0;
  long long seed = -1;
};

/// The run's facts: RUN_INFO first (what the source ran), then the robots' STATUS
/// (mode), then the command line's fallbacks, then what the ground truth shows.
RunInfo run_facts(const Args& a, const LogData& d, const std::string& command) {
  RunInfo info;
  info.source = a.log_path;
  info.command_line = command;
  bool disagree = false;
  info.mode = reported_mode(d, &disagree);
  if (disagree) std::fprintf(stderr, "evaluate: the robots report different modes in STATUS_ROBOT\n");
  if (info.mode.empty() && d.run_info) info.mode = d.run_info->mode;
  if (info.mode.empty()) info.mode = a.mode;
  if (!a.mode.empty() && info.mode != a.mode)
    std::fprintf(stderr, "evaluate: --mode %s, but the robots report %s: using theirs\n", a.mode.c_str(),
                 info.mode.c_str());
  if (info.mode.empty()) info.mode = "unknown";
  const FrameData& last = d.truth.rbegin()->second;
  int moving = 0;
  for (auto m : last.truly_moving) moving += m;
  const double moving_percent =
      last.truly_moving.empty() ? 0.0 : 100.0 * moving / static_cast<double>(last.truly_moving.size());
  const bool sim = d.run_info && d.run_info->seed >= 0;
  // Recorded data (RUN_INFO without a seed) has no simulator parameters, unless the
  // command line gives them.
  info.simulated = sim || a.dynamism >= 0.0 || a.speed >= 0.0 || a.seed >= 0;
  if (!info.simulated) {
    if (d.run_info)
      info.data = "recorded by " + d.run_info->source +
                  (d.run_info->scenario.empty() ? std::string() : " from " + d.run_info->scenario);
    info.data += (info.data.empty() ? "" : ", ") + std::to_string(moving) + " of " +
                 std::to_string(last.truly_moving.size()) + " landmarks moving in the ground truth";
  }
  info.dynamism_percent = sim ? d.run_info->dynamism_percent : a.dynamism >= 0.0 ? a.dynamism : moving_percent;
  info.speed_mps = sim ? d.run_info->landmark_speed_mps : std::max(a.speed, 0.0);
  info.seed = sim ? d.run_info->seed : std::max(a.seed, 0LL);
  if (sim && ((a.dynamism >= 0.0 && a.dynamism != info.dynamism_percent) ||
              (a.speed >= 0.0 && a.speed != info.speed_mps) || (a.seed >= 0 && a.seed != info.seed)))
    std::fprintf(stderr, "evaluate: the command line's dynamism/speed/seed differ from the log's RUN_INFO: using the log's\n");
  return info;
}

/// The team config that ran: --config's (`cfg`) with the log's run facts over it
/// (mode, dynamism, speed, seed, rate, frames). Throws std::invalid_argument when
/// the log's facts do not fit the config.
TeamConfig team_config_of_run(const TeamConfig& cfg, const RunInfo& info, const LogData& d) {
  RunOverrides ov;
  Mode m;
  if (parse_mode(info.mode, &m)) ov.mode = m;
  ov.dynamism_percent = info.dynamism_percent;
  ov.landmark_speed_mps = info.speed_mps;
  ov.seed = static_cast<int>(info.seed);
  if (d.run_info && d.run_info->seed >= 0) {
    ov.rate_hz = d.run_info->rate_hz;
    ov.frames = d.run_info->frames;
  }
  return apply_overrides(cfg, ov);
}

/// Every frame of the run, per robot (team/frame_accounting.hpp), into metrics.json.
std::vector<RobotFrameAccount> account(const LogData& d, const Assembled& x, nlohmann::json* j) {
  const int first_frame = d.truth.begin()->first, last_frame = d.truth.rbegin()->first;
  long dropped = 0, not_started = 0, missing_from_log = 0;
  std::vector<RobotFrameAccount> accounts;
  for (std::size_t i = 0; i < x.robot_ids.size(); ++i) {
    const int id = x.robot_ids[i];
    const auto st = d.status.find(id);
    const auto se = d.sensor_frames.find(id);
    const RobotFrameAccount& acct = accounts.emplace_back(account_frames(
        id, first_frame, last_frame, x.checkpoints[i], st != d.status.end() ? st->second : std::vector<StatusCheckpoint>{},
        se != d.sensor_frames.end() ? se->second : std::vector<int>{}));
    auto& jr = (*j)["robots"][i];
    jr["frames_dropped"] = acct.dropped;
    jr["frames_not_started"] = acct.not_started;
    jr["poses_missing_from_log"] = acct.missing_from_log;
    jr["restarts"] = acct.restarts;
    jr["frames_dropped_reported_by_node"] = acct.node_reported_dropped;
    dropped += acct.dropped;
    not_started += acct.not_started;
    missing_from_log += acct.missing_from_log;
  }
  (*j)["frames_dropped"] = dropped;
  (*j)["frames_not_started"] = not_started;
  (*j)["poses_missing_from_log"] = missing_from_log;
  return accounts;
}

/// Latency quantiles (overall and per robot) and the log's own figures into metrics.json.
void add_log_figures(const LogData& d, const Assembled& x, nlohmann::json* j) {
  for (std::size_t i = 0; i < x.robot_ids.size(); ++i) {
    (*j)["robots"][i]["latency_us"] = to_json(quantiles(x.latency[i]));
    (*j)["robots"][i]["pose_publish_latency_us"] = to_json(quantiles(x.publish_latency[i]));
  }
  (*j)["latency_us"] = to_json(quantiles(x.all_latency));
  (*j)["pose_publish_latency_us"] = to_json(quantiles(x.all_publish_latency));
  (*j)["global_map_latency_us"] = to_json(quantiles(x.map_latency));
  (*j)["log_events"] = d.events;
  (*j)["log_bytes_skipped"] = d.bytes_skipped;
  (*j)["log_complete"] = d.complete;
  for (const auto& [ch, n] : d.decode_errors) (*j)["decode_errors"][ch] = n;
  for (const auto& [ch, reasons] : d.invalid)
    for (const auto& [why, n] : reasons) (*j)["invalid_messages"][ch][why] = n;
  (*j)["authentication"] = d.auth ? d.auth->to_json(d.roster) : nlohmann::json(nullptr);
  (*j)["capacity_faults"] = d.capacity_faults;  // STATUS channels that raised FAULT_CAPACITY
  for (const auto& [ch, counts] : d.refused)
    for (int k = 0; k < kNumRefusals; ++k)
      if (counts[static_cast<std::size_t>(k)] > 0) (*j)["refused_by_nodes"][ch][to_string(static_cast<Refusal>(k))] = counts[static_cast<std::size_t>(k)];
}

void print_frames(const std::vector<RobotFrameAccount>& accounts, long dropped, long missing_from_log) {
  std::cout << "  frames dropped: " << dropped << " (frames a robot did not process after it started)\n";
  for (const auto& acct : accounts) {
    if (acct.not_started > 0)
      std::cout << "  robot " << acct.robot_id << ": not yet started for its first " << acct.not_started << " frames\n";
    if (acct.dropped == 0 && acct.missing_from_log == 0 && acct.restarts == 0) continue;
    std::cout << "  robot " << acct.robot_id << ":";
    if (acct.dropped > 0) std::cout << " " << acct.dropped << " frames dropped;";
    if (acct.restarts > 0) std::cout << " " << acct.restarts << (acct.restarts == 1 ? " restart;" : " restarts;");
    if (acct.missing_from_log > 0)
      std::cout << " " << acct.missing_from_log << " frames processed but their POSE missing from the log;";
    std::cout << " no POSE in the log for frames " << format_ranges(acct.missing_pose_ranges) << "\n";
  }
  if (missing_from_log > 0)
    std::cout << "  (POSEs missing from the log are the recorder's loss: lcm-logger drops messages when more "
                 "than 30 wait in its queue, as in the burst of landmark events a few frames into a run)\n";
}

void print_report(const LogData& d, const Assembled& x, const RunInfo& info, const nlohmann::json& j,
                  const std::vector<RobotFrameAccount>& accounts) {
  print_summary(std::cout, info, x.r);
  const Quantiles lq = quantiles(x.all_latency), mq = quantiles(x.map_latency), pq = quantiles(x.all_publish_latency);
  // A replayed recording (tools/replay_team.sh, lcm-logplayer) keeps its SENSOR
  // frames' original stamps: a "latency" of minutes or years measures nothing.
  constexpr double kReplayedUs = 60e6;
  if (lq.count > 0 && lq.p50 > kReplayedUs) {
    std::cout << "  latency: not measured (the SENSOR frames' stamps are " << static_cast<long long>(lq.p50 / 1e6)
              << " s before their poses: a replayed recording)\n";
  } else {
    std::cout << "  latency_us (sensor -> pose): p50 " << lq.p50 << " p99 " << lq.p99 << " max " << lq.max << " ("
              << lq.count << " poses)\n"
              << "  pose publish latency_us (sensor publish -> pose publish): p50 " << pq.p50 << " p99 " << pq.p99
              << " max " << pq.max << "\n"
              << "  global map latency_us (sensor -> map including the frame): p50 " << mq.p50 << " p99 " << mq.p99
              << " max " << mq.max << "\n";
  }
  print_frames(accounts, j["frames_dropped"].get<long>(), j["poses_missing_from_log"].get<long>());
  for (const auto& [ch, n] : d.decode_errors) std::cout << "  undecodable events on " << ch << ": " << n << "\n";
  for (const auto& [ch, reasons] : d.invalid)
    for (const auto& [why, n] : reasons)
      std::cout << "  invalid messages on " << ch << " (" << why << "), not evaluated: " << n << "\n";
  if (d.auth) {
    std::cout << "  authentication (" << d.roster << ", mission " << transport::mission_text(d.auth->mission())
              << "): " << d.auth->accepted() << " events verified, " << d.auth->refused() << " refused and not evaluated\n";
    for (const auto& [ch, reasons] : d.auth->refused_by_channel())
      for (const auto& [why, n] : reasons) std::cout << "    refused on " << ch << " (" << why << "): " << n << "\n";
  }
  for (const auto& ch : d.capacity_faults)
    std::cout << "  FAULT_CAPACITY raised by " << ch << ": a capacity was exceeded, results are not what the inputs said\n";
  if (d.bytes_skipped > 0 || !d.complete)
    std::cout << "  damaged log: " << d.bytes_skipped << " bytes between events skipped"
              << (d.complete ? "" : ", the last event truncated") << "\n";
}

/// -1 to go on, else the exit code.
int parse_args(int argc, char** argv, Args* a) {
  namespace lim = sim::limits;
  CLI::App app{"elaslam evaluate: metrics of a recorded LCM log against its ground truth"};
  cli::add_version_flag(app, "evaluate");
  app.add_option("--log", a->log_path, "LCM log (lcm-logger)")->required();
  app.add_option("--out", a->out_dir, "directory for metrics.json, frames.csv, trajectories/");
  app.add_option("--config", a->config, "the team's config file: its sections with the log's run facts become the "
                                        "effective config in metrics.json");
  app.add_option("--baseline", a->baseline, "also run this mode in process on the same scenario and seed and compare "
                                            "(needs --config)")
      ->check(CLI::IsMember({"ekf", "gated", "ela", "consensus"}));
  app.add_flag("--quiet", a->quiet, "no summary on stdout");
  app.add_option("--channel-suffix", a->channel_suffix, "the team's channel suffix (its processes' --channel-suffix)");
  app.add_option("--roster", a->roster, "the team's roster file (elaslam-keys team): every event is verified as the "
                                        "nodes do and what they would refuse is left out (default: the config's "
                                        "team: section; none: the log is trusted)");
  app.add_option("--mission", a->mission, "the mission to verify the events of (default: the roster's)");
  // Fallbacks for logs without RUN_INFO / STATUS_ROBOT (recorded before they existed),
  // in the simulator's ranges.
  app.add_option("--mode", a->mode, "mode to record when the robots' STATUS does not say");
  app.add_option("--dynamism", a->dynamism, "dynamism [%] to record when the log has no RUN_INFO "
                                            "(default: from the ground truth's moving flags)")
      ->check(cli::range(0.0, lim::kDynamismMaxPercent));
  app.add_option("--speed", a->speed, "landmark speed [m/s] to record when the log has no RUN_INFO")
      ->check(cli::range(0.0, lim::kLandmarkSpeedMaxMps));
  app.add_option("--seed", a->seed, "seed to record when the log has no RUN_INFO")->check(cli::range(0, lim::kSeedMax));
  if (const int rc = cli::parse(app, argc, argv); rc >= 0) return rc;
  if (!a->baseline.empty() && a->config.empty()) {
    std::fprintf(stderr, "evaluate: --baseline needs --config (the team's config file)\n");
    return cli::kExitBadInput;
  }
  return -1;
}

int evaluate_main(int argc, char** argv) {
  Args a;
  if (const int rc = parse_args(argc, argv, &a); rc >= 0) return rc;
  // The config first: a bad one is refused (ConfigError, exit 2 through guarded_main)
  // before a long log is read.
  TeamConfig file_config;
  if (!a.config.empty()) file_config = load_team_config(a.config);
  LogData d;
  if (!open_log_auth(a.roster, a.mission, a.config, a.channel_suffix, "evaluate", &d.auth, &d.roster))
    return cli::kExitBadInput;
  std::string why;
  if (!read_log(a.log_path, a.channel_suffix, &d, &why)) {
    std::fprintf(stderr, "evaluate: %s\n", why.c_str());
    return cli::kExitBadInput;
  }
  const Assembled x = assemble(d);
  const std::string command = cli::command_line(argc, argv);
  RunInfo info = run_facts(a, d, command);
  TeamConfig team;
  if (!a.config.empty()) {
    try {
      team = team_config_of_run(file_config, info, d);
      info.effective_config = team.effective_yaml;
    } catch (const std::invalid_argument& e) {
      std::fprintf(stderr, "evaluate: --config %s with the log's run facts: %s\n", a.config.c_str(), e.what());
      return cli::kExitBadInput;
    }
  } else if (d.run_info) {
    info.effective_config = d.run_info->config_yaml;  // the frame source's section only
  }
  nlohmann::json j = metrics_json(info, x.r);
  if (a.config.empty())
    j["config_note"] = d.run_info ? "the frame source's section only (RUN_INFO); pass --config for the nodes' sections"
                                  : "unknown: no RUN_INFO in the log and no --config";
  j["run_info"] = d.run_info ? run_info_json(*d.run_info) : nlohmann::json(nullptr);
  add_log_figures(d, x, &j);
  const std::vector<RobotFrameAccount> accounts = account(d, x, &j);
  if (!a.quiet) print_report(d, x, info, j, accounts);
  if (!a.baseline.empty())  // the same scenario and seed in process, with the baseline's mode
    j["baseline"] = run_baseline(team, a.config, a.baseline, info, x.r, a.quiet ? nullptr : &std::cout);
  if (!a.out_dir.empty()) {
    try {
      write_outputs(a.out_dir, j, x.r);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "evaluate: %s\n", e.what());
      return cli::kExitFailure;
    }
  }
  return 0;
}

}  // namespace
}  // namespace elaslam

int main(int argc, char** argv) {
  return elaslam::cli::guarded_main("evaluate", [&] { return elaslam::evaluate_main(argc, argv); });
}

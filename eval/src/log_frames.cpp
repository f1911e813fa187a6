// SPDX-License-Identifier: Apache-2.0
#include "elaslam/eval/log_frames.hpp"

#include <algorithm>
#include <exception>
#include <iterator>
#include <ostream>
#include <stdexcept>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/common/cov.hpp"
#include "elaslam/common/quantile.hpp"
#include "elaslam/common/track_checks.hpp"
#include "elaslam/global_map_t.hpp"
#include "elaslam/ground_truth_t.hpp"
#include "elaslam/logs/log_summary.hpp"
#include "elaslam/node_status_t.hpp"
#include "elaslam/sensor_frame_t.hpp"
#include "elaslam/transport/keys.hpp"

namespace elaslam {
namespace {

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

/// A logged TRACKS_<r> or GLOBAL_TRACKS that a receiver would take (track_checks.hpp);
/// else counted (channel, reason).
template <typename Msg, typename Check>
bool tracks_hold(const LogEvent& ev, const Msg& m, LogData* d, Check check) {
  Refusal reason = Refusal::kMalformed;
  if (check(m, d->limits, contract::kMaxLandmarkIdLimit, &reason).empty()) return true;
  ++d->invalid[ev.channel][to_string(reason)];
  return false;
}

/// A valid chunk of a TRACKS_<r> (`robot`) or GLOBAL_TRACKS (robot 0) publication
/// whose samples of its frame so far are `out`: true when it is to be taken, a chunk
/// not taken before (a later copy, or a chunk of a later publication of the frame
/// (another utime: main repeats a frame's map in a quiet period), is skipped: the
/// frame's first publication is scored). One whose num_chunks differs from its
/// publication's other chunks, or that lists a landmark an earlier chunk listed, is
/// counted (channel, reason) and skipped, as main_robot refuses it.
template <typename Msg>
bool take_chunk(const LogEvent& ev, const Msg& m, int robot, LogData::TrackChunks* held,
                const std::vector<TrackSample>& out, LogData* d) {
  if (held->num_chunks == 0) {
    held->num_chunks = m.num_chunks;
    held->utime = m.utime;
  }
  if (m.utime != held->utime) return false;
  if (m.num_chunks != held->num_chunks) {
    ++d->invalid[ev.channel][to_string(Refusal::kMalformed)];
    return false;
  }
  if ((held->taken >> m.chunk) & 1u) return false;  // a later copy of the chunk
  for (int k = 0; k < m.num_tracks; ++k)
    for (const TrackSample& s : out)
      if (s.robot == robot && s.landmark_id == m.tracks[static_cast<std::size_t>(k)].id) {
        ++d->invalid[ev.channel][to_string(Refusal::kDuplicateId)];
        return false;
      }
  held->taken |= 1u << m.chunk;
  return true;
}

template <typename Track>
TrackSample sample_of(const Track& t, int robot) {
  TrackSample s;
  s.robot = robot;
  s.landmark_id = t.id;
  s.x << t.x, t.y, t.vx, t.vy;
  s.P = read_cov_upper(t.cov);
  s.stopped = t.stopped != 0;
  return s;
}

const PoseRecord* pose_of(const LogData& d, int frame, int robot_id) {
  const auto poses = d.poses.find(frame);
  if (poses == d.poses.end()) return nullptr;
  const auto it = poses->second.find(robot_id);
  return it != poses->second.end() ? &it->second : nullptr;
}

void add_pose(std::size_t i, int k, const PoseRecord& p, FrameData* f, AssembledRun* x) {
  x->checkpoints[i].push_back({k, p.msg.frames_processed});
  set_pose(i, p.msg, f);
  x->latency[i].push_back(p.received_us - p.msg.source_utime);
  x->all_latency.push_back(x->latency[i].back());
  x->publish_latency[i].push_back(p.msg.utime - p.msg.source_utime);
  x->all_publish_latency.push_back(x->publish_latency[i].back());
  x->r.estimated[i].push_back({f->time_s, f->est_poses[i]});
  x->r.truth[i].push_back({f->time_s, f->true_poses[i]});
}

void print_frames(std::ostream& out, const std::vector<RobotFrameAccount>& accounts, long dropped,
                  long missing_from_log) {
  out << "  frames dropped: " << dropped << " (frames a robot did not process after it started)\n";
  for (const auto& acct : accounts) {
    if (acct.not_started > 0)
      out << "  robot " << acct.robot_id << ": not yet started for its first " << acct.not_started << " frames\n";
    if (acct.dropped == 0 && acct.missing_from_log == 0 && acct.restarts == 0) continue;
    out << "  robot " << acct.robot_id << ":";
    if (acct.dropped > 0) out << " " << acct.dropped << " frames dropped;";
    if (acct.restarts > 0) out << " " << acct.restarts << (acct.restarts == 1 ? " restart;" : " restarts;");
    if (acct.missing_from_log > 0)
      out << " " << acct.missing_from_log << " frames processed but their POSE missing from the log;";
    out << " no POSE in the log for frames " << format_ranges(acct.missing_pose_ranges) << "\n";
  }
  if (missing_from_log > 0)
    out << "  (POSEs missing from the log are the recorder's loss: lcm-logger drops messages when more "
           "than 30 wait in its queue, as in the burst of landmark events a few frames into a run)\n";
}

}  // namespace

void add_log_event(const LogEvent& ev, const std::string& sfx, LogData* d) {
  const std::string& ch = ev.channel;
  if (ch == channels::ground_truth(sfx)) {
    ground_truth_t m;
    if (!decode(ev, &m, d)) return;
    FrameData& f = d->truth[m.frame];
    set_truth(m, &f);
    f.time_s = static_cast<double>(m.utime) * 1e-6;
    std::vector<std::uint8_t>& present = d->truth_present[m.frame];
    present.assign(f.true_landmarks.size(), 0);
    for (int i = 0; i < contract::bounded(m.num_landmarks, static_cast<int>(m.landmarks.size())); ++i) {
      const int id = m.landmarks[static_cast<std::size_t>(i)].id;
      if (id >= 0 && id < static_cast<int>(present.size())) present[static_cast<std::size_t>(id)] = 1;
    }
  } else if (channels::robot_of(ch, channels::kTracksPrefix, sfx) > 0) {
    track_list_t m;
    if (!decode(ev, &m, d) || !tracks_hold(ev, m, d, check_track_list)) return;
    ++d->track_messages;
    std::vector<TrackSample>& out = d->robot_tracks[m.frame];
    if (!take_chunk(ev, m, m.robot_id, &d->tracks_chunks[{m.frame, m.robot_id}], out, d)) return;
    for (int k = 0; k < m.num_tracks; ++k) {
      const track_t& t = m.tracks[static_cast<std::size_t>(k)];
      out.push_back(sample_of(t, m.robot_id));
      out.back().sightings = t.sightings;
    }
  } else if (ch == channels::global_tracks(sfx)) {
    global_tracks_t m;
    if (!decode(ev, &m, d) || !tracks_hold(ev, m, d, check_global_tracks)) return;
    ++d->global_track_messages;
    std::vector<TrackSample>& out = d->global_tracks[m.frame];
    if (!take_chunk(ev, m, 0, &d->global_tracks_chunks[m.frame], out, d)) return;
    for (int k = 0; k < m.num_tracks; ++k) out.push_back(sample_of(m.tracks[static_cast<std::size_t>(k)], 0));
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
    add_log_event(ev, suffix, d);
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

AssembledRun assemble_run(LogData& d) {
  AssembledRun x;
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
  score_log_tracks(d, &x.r.metrics);
  return x;
}

void score_log_tracks(const LogData& d, RunMetrics* m) {
  TrackScorer robots, established(TrackScorer::kEstablishedSightings), fused;
  const std::vector<TrackSample> none;
  const std::vector<std::uint8_t> nothing;
  const auto at = [](const auto& by_frame, int k, const auto& otherwise) -> decltype(otherwise) {
    const auto it = by_frame.find(k);
    return it != by_frame.end() ? it->second : otherwise;
  };
  for (const auto& [k, f] : d.truth) {
    const std::vector<std::uint8_t>& present = at(d.truth_present, k, nothing);
    robots.add(f.time_s, f.true_landmarks, present, at(d.robot_tracks, k, none));
    established.add(f.time_s, f.true_landmarks, present, at(d.robot_tracks, k, none));
    fused.add(f.time_s, f.true_landmarks, present, at(d.global_tracks, k, none));
  }
  m->tracks_scored = d.track_messages > 0;
  if (m->tracks_scored) {
    m->tracks = robots.finish();
    m->tracks_established = established.finish();
  }
  m->global_tracks_scored = d.global_track_messages > 0;
  if (m->global_tracks_scored) m->global_tracks = fused.finish();
}

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

RunInfo run_facts(const RunFallbacks& a, const LogData& d, std::vector<std::string>* warnings) {
  RunInfo info;
  info.source = a.source;
  info.command_line = a.command_line;
  bool disagree = false;
  info.mode = reported_mode(d, &disagree);
  if (disagree) warnings->push_back("the robots report different modes in STATUS_ROBOT");
  if (info.mode.empty() && d.run_info) info.mode = d.run_info->mode;
  if (info.mode.empty()) info.mode = a.mode;
  if (!a.mode.empty() && info.mode != a.mode)
    warnings->push_back("--mode " + a.mode + ", but the robots report " + info.mode + ": using theirs");
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
    warnings->push_back("the command line's dynamism/speed/seed differ from the log's RUN_INFO: using the log's");
  return info;
}

std::vector<RobotFrameAccount> account_run_frames(const LogData& d, const AssembledRun& x, nlohmann::json* j) {
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

void add_log_figures(const LogData& d, const AssembledRun& x, nlohmann::json* j) {
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
      if (const std::int64_t n = counts[static_cast<std::size_t>(k)]; n > 0)
        (*j)["refused_by_nodes"][ch][to_string(static_cast<Refusal>(k))] = n;
}

void print_log_report(std::ostream& out, const LogData& d, const AssembledRun& x, const RunInfo& info,
                      const nlohmann::json& j, const std::vector<RobotFrameAccount>& accounts) {
  print_summary(out, info, x.r);
  const Quantiles lq = quantiles(x.all_latency), mq = quantiles(x.map_latency), pq = quantiles(x.all_publish_latency);
  // A replayed recording (tools/replay_team.sh, lcm-logplayer) keeps its SENSOR
  // frames' original stamps: a "latency" of minutes or years measures nothing.
  constexpr double kReplayedUs = 60e6;
  if (lq.count > 0 && lq.p50 > kReplayedUs) {
    out << "  latency: not measured (the SENSOR frames' stamps are " << static_cast<long long>(lq.p50 / 1e6)
              << " s before their poses: a replayed recording)\n";
  } else {
    out << "  latency_us (sensor -> pose): p50 " << lq.p50 << " p99 " << lq.p99 << " max " << lq.max << " ("
              << lq.count << " poses)\n"
              << "  pose publish latency_us (sensor publish -> pose publish): p50 " << pq.p50 << " p99 " << pq.p99
              << " max " << pq.max << "\n"
              << "  global map latency_us (sensor -> map including the frame): p50 " << mq.p50 << " p99 " << mq.p99
              << " max " << mq.max << "\n";
  }
  print_frames(out, accounts, j["frames_dropped"].get<long>(), j["poses_missing_from_log"].get<long>());
  for (const auto& [ch, n] : d.decode_errors) out << "  undecodable events on " << ch << ": " << n << "\n";
  for (const auto& [ch, reasons] : d.invalid)
    for (const auto& [why, n] : reasons)
      out << "  invalid messages on " << ch << " (" << why << "), not evaluated: " << n << "\n";
  if (d.auth) {
    out << "  authentication (" << d.roster << ", mission " << transport::mission_text(d.auth->mission())
              << "): " << d.auth->accepted() << " events verified, " << d.auth->refused()
              << " refused and not evaluated\n";
    for (const auto& [ch, reasons] : d.auth->refused_by_channel())
      for (const auto& [why, n] : reasons) out << "    refused on " << ch << " (" << why << "): " << n << "\n";
  }
  for (const auto& ch : d.capacity_faults)
    out << "  FAULT_CAPACITY raised by " << ch << ": a capacity was exceeded, results are not what the inputs said\n";
  if (d.bytes_skipped > 0 || !d.complete)
    out << "  damaged log: " << d.bytes_skipped << " bytes between events skipped"
              << (d.complete ? "" : ", the last event truncated") << "\n";
}

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// log_summary.hpp: the summary of a recorded LCM log.
#include "elaslam/logs/log_summary.hpp"

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <ostream>
#include <stdexcept>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/dynamic_notice_t.hpp"
#include "elaslam/global_map_t.hpp"
#include "elaslam/ground_truth_t.hpp"
#include "elaslam/landmark_event_t.hpp"
#include "elaslam/lmap_events_t.hpp"
#include "elaslam/lmap_snapshot_t.hpp"
#include "elaslam/logs/log_auth.hpp"
#include "elaslam/logs/log_reader.hpp"
#include "elaslam/node_status_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/run_info_t.hpp"
#include "elaslam/sensor_frame_t.hpp"

namespace elaslam {

std::string printable(const std::string& in) {
  std::string out;
  out.reserve(in.size());
  auto escape = [&out](unsigned char c) {
    char buf[8];
    std::snprintf(buf, sizeof buf, "\\x%02x", c);
    out += buf;
  };
  for (std::size_t i = 0; i < in.size();) {
    const auto c = static_cast<unsigned char>(in[i]);
    if (c < 0x80) {
      if (c < 0x20 || c == 0x7F)
        escape(c);
      else
        out += static_cast<char>(c);
      ++i;
      continue;
    }
    // A well-formed UTF-8 sequence (no overlong forms, no surrogates) is kept whole.
    const int len = c >= 0xC2 && c <= 0xDF ? 2 : c >= 0xE0 && c <= 0xEF ? 3 : c >= 0xF0 && c <= 0xF4 ? 4 : 0;
    bool ok = len > 0 && i + static_cast<std::size_t>(len) <= in.size();
    for (int k = 1; ok && k < len; ++k) ok = (static_cast<unsigned char>(in[i + k]) & 0xC0) == 0x80;
    if (ok && len >= 3) {
      const auto c1 = static_cast<unsigned char>(in[i + 1]);
      ok = !(c == 0xE0 && c1 < 0xA0) && !(c == 0xED && c1 >= 0xA0) && !(c == 0xF0 && c1 < 0x90) &&
           !(c == 0xF4 && c1 >= 0x90);
    }
    if (!ok) {
      escape(c);
      ++i;
      continue;
    }
    out.append(in, i, static_cast<std::size_t>(len));
    i += static_cast<std::size_t>(len);
  }
  return out;
}


std::string status_mode_name(int mode) {
  switch (mode) {
    case node_status_t::MODE_NONE: return "none";
    case node_status_t::MODE_EKF: return "ekf";
    case node_status_t::MODE_GATED: return "gated";
    case node_status_t::MODE_ELA: return "ela";
    case node_status_t::MODE_CONSENSUS: return "consensus";
    default: return "unknown(" + std::to_string(mode) + ")";
  }
}

std::string iso_utc(std::int64_t utime) {
  std::int64_t secs = utime / 1000000;
  std::int64_t us = utime % 1000000;
  if (us < 0) {
    us += 1000000;
    secs -= 1;
  }
  const std::time_t t = static_cast<std::time_t>(secs);
  std::tm tm{};
  if (!gmtime_r(&t, &tm)) return "invalid time " + std::to_string(utime) + " us";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02d.%06dZ", tm.tm_year + 1900, tm.tm_mon + 1, tm.tm_mday,
                tm.tm_hour, tm.tm_min, tm.tm_sec, static_cast<int>(us));
  return buf;
}

// ---------------------------------------------------------------------------------
// Reading a log
// ---------------------------------------------------------------------------------
namespace {



enum class Kind { kOther, kSensor, kPose, kStatusRobot, kStatus, kGroundTruth, kLmapEvent, kLmapEvents, kLmapSnapshot,
                  kGlobalMap, kDynamicNotice, kRunInfo };

struct ChannelClass {
  Kind kind = Kind::kOther;
  int robot = -1;  // for SENSOR_<r>, POSE_<r>, STATUS_ROBOT_<r>
  const char* type = "other";
};

// Channel names of channels.hpp without a suffix; anything else is "other".
ChannelClass classify(const std::string& ch) {
  if (int r = channels::robot_of(ch, channels::kSensorPrefix); r > 0) return {Kind::kSensor, r, "sensor_frame_t"};
  if (int r = channels::robot_of(ch, channels::kPosePrefix); r > 0) return {Kind::kPose, r, "pose_estimate_t"};
  if (int r = channels::robot_of(ch, channels::kStatusRobotPrefix); r > 0) return {Kind::kStatusRobot, r, "node_status_t"};
  if (int r = channels::robot_of(ch, channels::kTeamMapPrefix); r > 0) return {Kind::kOther, r, "global_map_t"};
  if (int r = channels::robot_of(ch, channels::kCandidatesPrefix); r > 0) return {Kind::kOther, r, "candidate_list_t"};
  if (int r = channels::robot_of(ch, channels::kTracksPrefix); r > 0) return {Kind::kOther, r, "track_list_t"};
  if (ch == channels::status_main() || ch == channels::status_sim()) return {Kind::kStatus, -1, "node_status_t"};
  if (ch == channels::ground_truth()) return {Kind::kGroundTruth, -1, "ground_truth_t"};
  if (ch == channels::lmap_event()) return {Kind::kLmapEvent, -1, "landmark_event_t"};
  if (ch == channels::lmap_events()) return {Kind::kLmapEvents, -1, "lmap_events_t"};
  if (ch == channels::lmap_snapshot()) return {Kind::kLmapSnapshot, -1, "lmap_snapshot_t"};
  if (ch == channels::lmap_resync()) return {Kind::kOther, -1, "resync_request_t"};
  if (ch == channels::global_map()) return {Kind::kGlobalMap, -1, "global_map_t"};
  if (ch == channels::global_moving()) return {Kind::kOther, -1, "global_map_t"};
  if (ch == channels::global_tracks()) return {Kind::kOther, -1, "global_tracks_t"};
  if (ch == channels::dynamic_notice()) return {Kind::kDynamicNotice, -1, "dynamic_notice_t"};
  if (ch == channels::run_info()) return {Kind::kRunInfo, -1, "run_info_t"};
  return {};
}

struct RobotData {
  std::vector<PoseCheckpoint> poses;
  std::vector<StatusCheckpoint> statuses;
  std::vector<int> sensor_frames;
  std::vector<int> modes;
  long pose_events = 0, pose_undecodable = 0;
  long status_events = 0, status_undecodable = 0;
  bool has_sensor_or_pose_channel = false;
};

enum class Decoded { kOk, kBad, kOtherFingerprint };

// Everything gathered in one pass. The big messages are decoded into one reused
// object each (global_map_t and lmap_snapshot_t are tens of kB).
struct Reader {
  struct Channel {
    ChannelClass cls;
    ChannelSummary sum;
  };
  std::map<std::string, Channel> channels;
  std::map<int, RobotData> robots;
  std::vector<int> truth_frames;
  std::vector<int> pose_frames;
  bool run_info_seen = false;
  run_info_t first_info{}, last_info{};
  long run_info_messages = 0;

  sensor_frame_t sensor{};
  pose_estimate_t pose{};
  node_status_t status{};
  ground_truth_t truth{};
  landmark_event_t event{};
  lmap_events_t events{};
  lmap_snapshot_t snapshot{};
  global_map_t map{};
  dynamic_notice_t notice{};
  run_info_t info{};

  // An event that does not decode either carries another type's fingerprint (the
  // first 8 bytes of every LCM message: e.g. a log recorded before a field was added)
  // or is damaged.
  template <typename Msg>
  static Decoded decode(const LogEvent& ev, Msg* m) {
    try {  // a negative count of a variable-length array makes LCM's decoder throw
      if (m->decode(ev.data.data(), 0, static_cast<int>(ev.data.size())) >= 0) return Decoded::kOk;
    } catch (const std::exception&) {
      return Decoded::kBad;
    }
    if (ev.data.size() < 8) return Decoded::kBad;
    std::uint64_t h = 0;
    for (int i = 0; i < 8; ++i) h = (h << 8) | ev.data[static_cast<std::size_t>(i)];
    return h != static_cast<std::uint64_t>(Msg::getHash()) ? Decoded::kOtherFingerprint : Decoded::kBad;
  }

  Decoded on_event(const LogEvent& ev, const ChannelClass& c) {
    switch (c.kind) {
      case Kind::kOther: return Decoded::kOk;
      case Kind::kSensor: {
        RobotData& r = robots[c.robot];
        r.has_sensor_or_pose_channel = true;
        const Decoded d = decode(ev, &sensor);
        if (d == Decoded::kOk) r.sensor_frames.push_back(sensor.frame);
        return d;
      }
      case Kind::kPose: {
        RobotData& r = robots[c.robot];
        r.has_sensor_or_pose_channel = true;
        ++r.pose_events;
        const Decoded d = decode(ev, &pose);
        if (d != Decoded::kOk) {
          ++r.pose_undecodable;
          return d;
        }
        r.poses.push_back({pose.frame, pose.frames_processed});
        pose_frames.push_back(pose.frame);
        return d;
      }
      case Kind::kStatusRobot: {
        RobotData& r = robots[c.robot];
        ++r.status_events;
        const Decoded d = decode(ev, &status);
        if (d != Decoded::kOk) {
          ++r.status_undecodable;
          return d;
        }
        r.statuses.push_back({status.frame, status.frames, status.frames_dropped});
        if (r.modes.empty() || r.modes.back() != status.mode) r.modes.push_back(status.mode);
        return d;
      }
      case Kind::kStatus: return decode(ev, &status);
      case Kind::kGroundTruth: {
        const Decoded d = decode(ev, &truth);
        if (d == Decoded::kOk) truth_frames.push_back(truth.frame);
        return d;
      }
      case Kind::kLmapEvent: return decode(ev, &event);
      case Kind::kLmapEvents: return decode(ev, &events);
      case Kind::kLmapSnapshot: return decode(ev, &snapshot);
      case Kind::kGlobalMap: return decode(ev, &map);
      case Kind::kDynamicNotice: return decode(ev, &notice);
      case Kind::kRunInfo: {
        const Decoded d = decode(ev, &info);
        if (d != Decoded::kOk) return d;
        if (!run_info_seen) first_info = info;
        last_info = info;
        run_info_seen = true;
        ++run_info_messages;
        return d;
      }
    }
    return Decoded::kOk;
  }
};

std::vector<int> robot_ids_of(const run_info_t& m) {
  std::vector<int> ids;
  const int n = contract::bounded(m.num_robots, static_cast<int>(m.robot_ids.size()));
  for (std::size_t i = 0; i < static_cast<std::size_t>(n); ++i) ids.push_back(m.robot_ids[i]);
  return ids;
}

RunInfoSummary run_info_summary(const Reader& r) {
  RunInfoSummary s;
  if (!r.run_info_seen) return s;
  const run_info_t& m = r.last_info;
  const run_info_t& f = r.first_info;
  s.present = true;
  s.messages = r.run_info_messages;
  s.varies = f.source != m.source || f.scenario != m.scenario || f.seed != m.seed || f.mode != m.mode ||
             robot_ids_of(f) != robot_ids_of(m);
  s.schema_version = m.schema_version;
  s.frame = m.frame;
  s.source = printable(m.source);
  s.version = printable(m.version);
  s.scenario = printable(m.scenario);
  s.mode = printable(m.mode);
  s.seed = m.seed;
  s.dynamism_percent = m.dynamism_percent;
  s.landmark_speed_mps = m.landmark_speed_mps;
  s.rate_hz = m.rate_hz;
  s.frames = m.frames;
  s.robot_ids = robot_ids_of(m);
  return s;
}

// The frames of the run: GROUND_TRUTH's, else every robot's SENSOR's, else POSE's.
void frames_of_run(const Reader& r, LogSummary* s) {
  std::vector<int> frames = r.truth_frames;
  s->frames_source = channels::ground_truth();
  if (frames.empty()) {
    s->frames_source = "SENSOR";
    for (const auto& [id, d] : r.robots) frames.insert(frames.end(), d.sensor_frames.begin(), d.sensor_frames.end());
  }
  if (frames.empty()) {
    s->frames_source = "POSE";
    frames = r.pose_frames;
  }
  if (frames.empty()) {
    s->frames_source.clear();
    return;
  }
  std::sort(frames.begin(), frames.end());
  frames.erase(std::unique(frames.begin(), frames.end()), frames.end());
  s->first_frame = frames.front();
  s->last_frame = frames.back();
  s->frames_logged = static_cast<int>(frames.size());
  s->frames_missing = absent_ranges(s->first_frame, s->last_frame, frames);
}


}  // namespace

LogSummary summarize_log(const std::string& path, LogAuth* auth, const std::string& roster) {
  LogSummary s;
  s.file = printable(path);
  LogReader in(path);
  s.size_bytes = in.size();
  auto reader = std::make_unique<Reader>();
  LogEvent ev;
  while (in.next(&ev)) {
    if (s.events == 0 || ev.timestamp < s.first_us) s.first_us = ev.timestamp;
    if (s.events == 0 || ev.timestamp > s.last_us) s.last_us = ev.timestamp;
    ++s.events;
    auto it = reader->channels.find(ev.channel);
    if (it == reader->channels.end()) {
      it = reader->channels.emplace(ev.channel, Reader::Channel{classify(ev.channel), {}}).first;
      it->second.sum.name = printable(ev.channel);
      it->second.sum.type = it->second.cls.type;
      it->second.sum.first_us = it->second.sum.last_us = ev.timestamp;
    }
    ChannelSummary& c = it->second.sum;
    ++c.count;
    c.bytes += static_cast<std::int64_t>(ev.data.size());
    c.first_us = std::min(c.first_us, ev.timestamp);
    c.last_us = std::max(c.last_us, ev.timestamp);
    if (auth && !auth->admit(&ev)) {
      ++c.auth_refused;
      continue;
    }
    const Decoded d = reader->on_event(ev, it->second.cls);
    if (d != Decoded::kOk) ++c.decode_errors;
    if (d == Decoded::kOtherFingerprint) ++c.fingerprint_mismatches;
  }
  if (auth) {
    s.roster = printable(roster);
    s.auth_accepted = auth->accepted();
    s.auth_refused = auth->refused();
    for (const auto& [ch, reasons] : auth->refused_by_channel())
      for (const auto& [why, n] : reasons) s.auth_refused_by[why] += n;
  }
  s.bytes_skipped = in.skipped();
  const std::int64_t pos = in.end_of_last_event();
  s.bytes_read = pos;
  s.complete = pos >= s.size_bytes;

  for (auto& [name, ch] : reader->channels) {
    ChannelSummary& c = ch.sum;
    const double span_s = (static_cast<double>(c.last_us) - static_cast<double>(c.first_us)) * 1e-6;
    c.rate_hz = c.count >= 2 && span_s > 0.0 ? static_cast<double>(c.count - 1) / span_s : 0.0;
    s.channels.push_back(c);
  }
  s.run_info = run_info_summary(*reader);
  frames_of_run(*reader, &s);

  std::vector<int> ids = s.run_info.robot_ids;
  if (ids.empty())
    for (const auto& [id, d] : reader->robots)
      if (d.has_sensor_or_pose_channel) ids.push_back(id);
  static const RobotData kNone;
  for (int id : ids) {
    const auto it = reader->robots.find(id);
    const RobotData& d = it != reader->robots.end() ? it->second : kNone;
    RobotSummary r;
    r.robot_id = id;
    r.modes = d.modes;
    r.pose_events = d.pose_events;
    r.pose_undecodable = d.pose_undecodable;
    r.status_events = d.status_events;
    r.status_undecodable = d.status_undecodable;
    r.account = account_frames(id, s.first_frame, s.last_frame, d.poses, d.statuses, d.sensor_frames);
    s.robots.push_back(std::move(r));
  }
  return s;
}

// ---------------------------------------------------------------------------------
// Output
// ---------------------------------------------------------------------------------
namespace {

constexpr std::size_t kPrintedRanges = 8;  // the text keeps it short; JSON has every range

std::string ranges_text(const std::vector<std::pair<int, int>>& ranges) {
  if (ranges.size() <= kPrintedRanges) return format_ranges(ranges);
  const std::vector<std::pair<int, int>> head(ranges.begin(), ranges.begin() + kPrintedRanges);
  return format_ranges(head) + ", ... (" + std::to_string(ranges.size() - kPrintedRanges) + " more ranges)";
}

std::int64_t frames_in(const std::vector<std::pair<int, int>>& ranges) {
  std::int64_t n = 0;
  for (const auto& [a, b] : ranges) n += static_cast<std::int64_t>(b) - a + 1;
  return n;
}

std::string missing_text(const char* what, const std::vector<std::pair<int, int>>& ranges) {
  if (ranges.empty()) return std::string(what) + " missing none";
  const std::int64_t n = frames_in(ranges);
  return std::string(what) + " missing " + ranges_text(ranges) + " (" + std::to_string(n) +
         (n == 1 ? " frame)" : " frames)");
}

std::string modes_text(const std::vector<int>& modes) {
  if (modes.empty()) return "-";
  std::string s;
  for (int m : modes) s += (s.empty() ? "" : "->") + status_mode_name(m);
  return s;
}

std::string size_text(std::int64_t bytes) {
  char buf[64];
  const double b = static_cast<double>(bytes);
  if (bytes >= (1 << 20))
    std::snprintf(buf, sizeof buf, "%.1f MiB (%lld bytes)", b / (1 << 20), static_cast<long long>(bytes));
  else if (bytes >= 1024)
    std::snprintf(buf, sizeof buf, "%.1f KiB (%lld bytes)", b / 1024, static_cast<long long>(bytes));
  else
    std::snprintf(buf, sizeof buf, "%lld bytes", static_cast<long long>(bytes));
  return buf;
}

std::string num(double v, const char* fmt = "%g") {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

void print_run_info(std::ostream& out, const RunInfoSummary& r) {
  if (!r.present) {
    out << "run info:  none in the log (recorded before RUN_INFO existed, or RUN_INFO was not recorded)\n";
    return;
  }
  std::string robots;
  for (int id : r.robot_ids) robots += " " + std::to_string(id);
  out << "run info:  source " << r.source << ", version " << r.version << "\n"
      << "           scenario " << r.scenario << ", mode " << (r.mode.empty() ? "not known to the source" : r.mode)
      << "\n"
      << "           seed " << (r.seed < 0 ? "none" : std::to_string(r.seed)) << ", dynamism "
      << (r.dynamism_percent < 0 ? "unknown" : num(r.dynamism_percent) + " %") << ", speed "
      << (r.landmark_speed_mps < 0 ? "unknown" : num(r.landmark_speed_mps) + " m/s") << ", rate "
      << num(r.rate_hz) << " Hz, " << r.frames << " frames, robots" << (robots.empty() ? " none" : robots) << "\n"
      << "           (the last of " << r.messages << " RUN_INFO, sent after frame " << r.frame << ")\n";
  if (r.varies) out << "           WARNING: RUN_INFO changed within the log (more than one run recorded?)\n";
}

void print_channels(std::ostream& out, const std::vector<ChannelSummary>& channels) {
  std::size_t w = 7;
  for (const auto& c : channels) w = std::max(w, c.name.size());
  char line[512];
  out << "channels:  " << channels.size() << "\n";
  std::snprintf(line, sizeof line, "  %-*s  %-17s %9s %12s %10s %14s\n", static_cast<int>(w), "channel", "type", "count",
                "bytes", "rate_hz", "decode_errors");
  out << line;
  for (const auto& c : channels) {
    const std::string rate = c.count >= 2 && c.rate_hz > 0.0 ? num(c.rate_hz, "%.2f") : "-";
    const std::string errors = c.type == "other" ? "-" : std::to_string(c.decode_errors);
    std::snprintf(line, sizeof line, "  %-*s  %-17s %9ld %12lld %10s %14s\n", static_cast<int>(w), c.name.c_str(),
                  c.type.c_str(), c.count, static_cast<long long>(c.bytes), rate.c_str(), errors.c_str());
    out << line;
  }
  for (const auto& c : channels)
    if (c.fingerprint_mismatches > 0)
      out << "  WARNING: " << c.fingerprint_mismatches << " of " << c.count << " " << c.name
          << " events carry another fingerprint than this build's " << c.type
          << ": recorded with another version of the type, or damaged\n";
  for (const auto& c : channels)
    if (c.auth_refused > 0)
      out << "  " << c.auth_refused << " of " << c.count << " " << c.name
          << " events refused by the team's keys (a keyed node would drop them; not decoded)\n";
}

void print_robots(std::ostream& out, const LogSummary& s) {
  out << "robots:    " << s.robots.size();
  if (s.frames_source.empty()) {
    out << " (no frame range: nothing to account for)\n";
    return;
  }
  out << " (frames " << s.first_frame << "-" << s.last_frame << ")\n";
  char line[512];
  bool any_outputs = false;
  for (const auto& r : s.robots) any_outputs = any_outputs || r.outputs_recorded();
  if (any_outputs) {
    std::snprintf(line, sizeof line, "  %5s  %-10s %6s %12s %8s %17s %9s %13s\n", "robot", "mode", "poses",
                  "not_started", "dropped", "lost_by_recorder", "restarts", "node_dropped");
    out << line;
  }
  for (const auto& r : s.robots) {
    const RobotFrameAccount& a = r.account;
    const std::string sensor =
        a.sensor_recorded ? missing_text("SENSOR", a.missing_sensor_ranges) : std::string("SENSOR not recorded");
    if (!r.outputs_recorded()) {
      std::snprintf(line, sizeof line, "  %5d  no %s or %s in the log (robot outputs not recorded); ", r.robot_id,
                    channels::pose(r.robot_id).c_str(), channels::status_robot(r.robot_id).c_str());
      out << line << sensor << "\n";
      continue;
    }
    const std::string node = a.node_reported_dropped < 0 ? "-" : std::to_string(a.node_reported_dropped);
    std::snprintf(line, sizeof line, "  %5d  %-10s %6d %12d %8d %17d %9d %13s\n", r.robot_id,
                  modes_text(r.modes).c_str(), a.poses_logged, a.not_started, a.dropped, a.missing_from_log,
                  a.restarts, node.c_str());
    out << line << "         " << missing_text("POSE", a.missing_pose_ranges) << "; " << sensor << "\n";
    if (r.pose_undecodable > 0)
      out << "         WARNING: " << r.pose_undecodable << " of " << r.pose_events << " " << channels::pose(r.robot_id)
          << " events do not decode; their frames count as without a POSE above\n";
    if (r.status_undecodable > 0)
      out << "         WARNING: " << r.status_undecodable << " of " << r.status_events << " "
          << channels::status_robot(r.robot_id) << " events do not decode\n";
  }
}

nlohmann::json ranges_json(const std::vector<std::pair<int, int>>& ranges) {
  nlohmann::json j = nlohmann::json::array();
  for (const auto& [a, b] : ranges) j.push_back({a, b});
  return j;
}

}  // namespace

void print_log_summary(std::ostream& out, const LogSummary& s) {
  out << "file:      " << s.file << "\n"
      << "size:      " << size_text(s.size_bytes) << "\n"
      << "events:    " << s.events;
  if (s.complete)
    out << ", read to the end\n";
  else
    out << " read; the read stopped at byte " << s.bytes_read << ": the last " << (s.size_bytes - s.bytes_read)
        << " bytes are not a complete event (truncated or corrupt log)\n";
  if (s.bytes_skipped > 0)
    out << "           " << s.bytes_skipped << " bytes between events skipped (corrupt data)\n";
  if (s.events > 0)
    out << "start:     " << iso_utc(s.first_us) << "\n"
        << "end:       " << iso_utc(s.last_us) << "\n"
        << "duration:  " << num(s.duration_s(), "%.3f") << " s\n";
  if (!s.roster.empty()) {
    out << "auth:      " << s.roster << ": " << s.auth_accepted << " events verified, " << s.auth_refused << " refused";
    const char* sep = " (";
    for (const auto& [why, n] : s.auth_refused_by) {
      out << sep << why << " " << n;
      sep = ", ";
    }
    out << (s.auth_refused_by.empty() ? "" : ")") << "\n";
  }
  print_run_info(out, s.run_info);
  if (s.frames_source.empty()) {
    out << "frames:    none (no GROUND_TRUTH, SENSOR or POSE in the log)\n";
  } else {
    const std::int64_t span = static_cast<std::int64_t>(s.last_frame) - s.first_frame + 1;
    out << "frames:    " << s.first_frame << "-" << s.last_frame << " from " << s.frames_source << ": "
        << s.frames_logged << " of " << span << " logged, "
        << (s.frames_missing.empty() ? std::string("none missing")
                                     : "missing " + ranges_text(s.frames_missing))
        << "\n";
  }
  print_channels(out, s.channels);
  print_robots(out, s);
}

nlohmann::json to_json(const RobotFrameAccount& a) {
  nlohmann::json j;
  j["robot_id"] = a.robot_id;
  j["frames_in_run"] = a.frames_in_run;
  j["poses_logged"] = a.poses_logged;
  j["not_started"] = a.not_started;
  j["dropped"] = a.dropped;
  j["missing_from_log"] = a.missing_from_log;
  j["restarts"] = a.restarts;
  j["missing_pose_ranges"] = ranges_json(a.missing_pose_ranges);
  j["sensor_recorded"] = a.sensor_recorded;
  j["sensors_logged"] = a.sensors_logged;
  j["missing_sensor_ranges"] = ranges_json(a.missing_sensor_ranges);
  j["node_reported_dropped"] =
      a.node_reported_dropped < 0 ? nlohmann::json(nullptr) : nlohmann::json(a.node_reported_dropped);
  return j;
}

nlohmann::json to_json(const LogSummary& s) {
  nlohmann::json j;
  j["file"] = s.file;
  j["size_bytes"] = s.size_bytes;
  j["events"] = s.events;
  j["complete"] = s.complete;
  j["bytes_read"] = s.bytes_read;
  j["bytes_skipped"] = s.bytes_skipped;
  const bool any = s.events > 0;
  j["start_utime_us"] = any ? nlohmann::json(s.first_us) : nlohmann::json(nullptr);
  j["end_utime_us"] = any ? nlohmann::json(s.last_us) : nlohmann::json(nullptr);
  j["start_utc"] = any ? nlohmann::json(iso_utc(s.first_us)) : nlohmann::json(nullptr);
  j["end_utc"] = any ? nlohmann::json(iso_utc(s.last_us)) : nlohmann::json(nullptr);
  j["duration_s"] = s.duration_s();
  j["channels"] = nlohmann::json::array();
  for (const auto& c : s.channels)
    j["channels"].push_back({{"name", c.name},
                             {"type", c.type},
                             {"count", c.count},
                             {"bytes", c.bytes},
                             {"first_utime_us", c.first_us},
                             {"last_utime_us", c.last_us},
                             {"rate_hz", c.count >= 2 && c.rate_hz > 0.0 ? nlohmann::json(c.rate_hz) : nlohmann::json(nullptr)},
                             {"decode_errors", c.type == "other" ? nlohmann::json(nullptr) : nlohmann::json(c.decode_errors)},
                             {"fingerprint_mismatches", c.fingerprint_mismatches},
                             {"auth_refused", s.roster.empty() ? nlohmann::json(nullptr) : nlohmann::json(c.auth_refused)}});
  if (s.roster.empty()) {
    j["authentication"] = nullptr;
  } else {
    j["authentication"] = {{"roster", s.roster}, {"accepted", s.auth_accepted}, {"refused", s.auth_refused},
                           {"refused_by", s.auth_refused_by}};
  }
  const RunInfoSummary& r = s.run_info;
  if (!r.present) {
    j["run_info"] = nullptr;
  } else {
    auto unknown_if_negative = [](double v) { return v < 0 ? nlohmann::json(nullptr) : nlohmann::json(v); };
    j["run_info"] = {{"messages", r.messages},
                     {"varies", r.varies},
                     {"schema_version", r.schema_version},
                     {"frame", r.frame},
                     {"source", r.source},
                     {"version", r.version},
                     {"scenario", r.scenario},
                     {"mode", r.mode},
                     {"seed", r.seed < 0 ? nlohmann::json(nullptr) : nlohmann::json(r.seed)},
                     {"dynamism_percent", unknown_if_negative(r.dynamism_percent)},
                     {"landmark_speed_mps", unknown_if_negative(r.landmark_speed_mps)},
                     {"rate_hz", r.rate_hz},
                     {"frames", r.frames},
                     {"robot_ids", r.robot_ids}};
  }
  if (s.frames_source.empty()) {
    j["frames"] = nullptr;
  } else {
    j["frames"] = {{"source", s.frames_source},
                   {"first", s.first_frame},
                   {"last", s.last_frame},
                   {"logged", s.frames_logged},
                   {"missing_ranges", ranges_json(s.frames_missing)}};
  }
  j["robots"] = nlohmann::json::array();
  for (const auto& rb : s.robots) {
    nlohmann::json jr = to_json(rb.account);
    nlohmann::json modes = nlohmann::json::array();
    for (int m : rb.modes) modes.push_back(status_mode_name(m));
    jr["modes"] = modes;
    jr["outputs_recorded"] = rb.outputs_recorded();
    jr["pose_events"] = rb.pose_events;
    jr["pose_undecodable"] = rb.pose_undecodable;
    jr["status_events"] = rb.status_events;
    jr["status_undecodable"] = rb.status_undecodable;
    j["robots"].push_back(jr);
  }
  return j;
}

}  // namespace elaslam

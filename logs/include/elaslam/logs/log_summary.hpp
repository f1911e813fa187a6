// SPDX-License-Identifier: Apache-2.0
// What a recorded LCM log holds, like `ros2 bag info`: its channels (count, bytes,
// rate, type, undecodable events), the run it recorded (RUN_INFO), the frames it
// covers, and per robot an account of every frame of the run: logged, never
// started, dropped by the robot, or processed by the robot but lost by the
// recorder. Used by `log_info` (tools/log_info.cpp); docs/tools.md.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "elaslam/logs/frame_accounting.hpp"

namespace elaslam {

class LogAuth;

// ---------------------------------------------------------------------------------
// Log summary
// ---------------------------------------------------------------------------------

struct ChannelSummary {
  std::string name;               // printable(): damaged names have \xNN escapes
  std::string type;               // e.g. "pose_estimate_t", "other" for channels not of elaslam
  long count = 0;                 // events on the channel, undecodable ones included
  std::int64_t bytes = 0;         // payload bytes (the events' data, no log framing)
  std::int64_t first_us = 0;      // [us] first / last event timestamp (log receive time)
  std::int64_t last_us = 0;
  double rate_hz = 0.0;           // (count - 1) / (last - first); 0 when count < 2 or no span
  long decode_errors = 0;         // events of an elaslam type that did not decode (0 for "other")
  long fingerprint_mismatches = 0;  // of those, events whose LCM fingerprint is another type's:
                                    // recorded with another version of the message, as a rule
  long auth_refused = 0;          // with the team key: events a keyed node would refuse (not decoded)
};

/// The last RUN_INFO that decoded (run_info_t; -1 marks "unknown" as in the message).
struct RunInfoSummary {
  bool present = false;        // false: no RUN_INFO decoded (logs older than RUN_INFO)
  long messages = 0;           // RUN_INFO messages decoded
  bool varies = false;         // source, scenario, seed, mode or robots changed within the log
  int schema_version = 0;
  int frame = -1;              // last frame published when it was sent
  std::string source, version, scenario, mode;
  std::int64_t seed = -1;
  double dynamism_percent = -1.0;
  double landmark_speed_mps = -1.0;
  double rate_hz = 0.0;
  int frames = 0;
  std::vector<int> robot_ids;
};

struct RobotSummary {
  int robot_id = 0;
  std::vector<int> modes;          // node_status_t.mode values seen on STATUS_ROBOT_<r>, in order, no repeats
  long pose_events = 0;            // events on POSE_<r>, decoded or not
  long pose_undecodable = 0;       // of those, not decoded: the account counts their frames as missing
  long status_events = 0;          // events on STATUS_ROBOT_<r>, decoded or not
  long status_undecodable = 0;
  RobotFrameAccount account;       // only meaningful when LogSummary::frames_source is not empty

  /// False for a log of the robots' inputs only (e.g. mrclam_import's, or lcm-logger
  /// with a channel filter): then the account says nothing about the robot.
  bool outputs_recorded() const { return pose_events > 0 || status_events > 0; }
};

struct LogSummary {
  std::string file;
  std::int64_t size_bytes = 0;
  long events = 0;                 // events read
  bool complete = true;            // the read reached the end of the file
  std::int64_t bytes_read = 0;     // offset where the read stopped (== size_bytes when complete)
  std::int64_t bytes_skipped = 0;  // bytes between events skipped while looking for the next one
  std::int64_t first_us = 0;       // [us] earliest / latest event timestamp (0 when no event)
  std::int64_t last_us = 0;
  std::vector<ChannelSummary> channels;  // sorted by name
  RunInfoSummary run_info;
  std::string roster;              // with the team's keys (summarize_log's auth): where the roster came from
  std::int64_t auth_accepted = 0;  // events that verified
  std::int64_t auth_refused = 0;   // events a keyed node would refuse: counted, not decoded
  std::map<std::string, std::int64_t> auth_refused_by;  // per reason (forged, replayed, ...)

  std::string frames_source;       // "GROUND_TRUTH", "SENSOR", or "" when neither is in the log
  int first_frame = 0, last_frame = -1;
  int frames_logged = 0;           // distinct frames on the frames_source channel(s)
  std::vector<std::pair<int, int>> frames_missing;  // gaps in frames_source within [first, last]
  std::vector<RobotSummary> robots;  // ids from RUN_INFO, else from SENSOR_<r> / POSE_<r> channels

  double duration_s() const {
    return events > 0 ? (static_cast<double>(last_us) - static_cast<double>(first_us)) * 1e-6 : 0.0;
  }
};

/// Reads the whole log at `path`. Throws std::runtime_error when the file cannot be
/// opened or does not start with an LCM event (an empty file is a log of no
/// events). Never throws on bad content: undecodable events are counted per
/// channel, and a truncated or corrupt tail ends the read (complete = false).
/// With `auth` (the team key: log_auth.hpp), every event is verified as a keyed node
/// does and only what verifies is decoded; refusals are counted per channel.
LogSummary summarize_log(const std::string& path, LogAuth* auth = nullptr, const std::string& roster = {});

/// Human-readable summary (what `log_info` prints).
void print_log_summary(std::ostream& out, const LogSummary& s);

/// Machine-readable summary; units in the keys (_s, _us, _hz, _bytes, ...).
nlohmann::json to_json(const LogSummary& s);
nlohmann::json to_json(const RobotFrameAccount& a);

/// "ekf", "gated", "ela", "consensus", "none", or "unknown(N)" for node_status_t.mode.
std::string status_mode_name(int mode);

/// `in` with control characters and bytes that are not well-formed UTF-8 written as
/// \xNN: every string of a summary that comes from the log (channel names, RUN_INFO
/// text) goes through it, so that printing and JSON never choke on a damaged log.
std::string printable(const std::string& in);

/// "2024-05-01T12:00:00.123456Z" for microseconds since the Unix epoch.
std::string iso_utc(std::int64_t utime);

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// A recorded run (an LCM log of the live team, made by lcm-logger) as the metrics'
// frames, with the same definitions and output files as the in-process run
// (report.hpp), plus latency and frame accounting. tools/evaluate is its program.
//
// Reading (read_log, add_log_event): the team's channels (with its suffix) are
// decoded; what does not decode, or decodes but a node would refuse (frame_data.hpp,
// check_logged), is counted per channel and not evaluated. With the team's roster
// (LogData::auth), events are verified as the nodes verify them first.
//
// Frames per robot (logs/frame_accounting.hpp, account_frames): a frame is "dropped"
// only when the robot did not process it after it had started; frames before its
// first are "not started"; a frame it processed whose POSE is not in the log is the
// recorder's loss ("missing from the log"), told apart by POSE.frames_processed.
//
// Tracks (docs/tracking.md "On the wire"): each robot's TRACKS_<r> of a frame and
// main's GLOBAL_TRACKS of a frame, every valid chunk of the publication once (a
// chunk at odds with its publication's others is counted and skipped), are scored
// against that frame's ground truth (eval/track_score.hpp) into metrics.json `tracks` and
// `global_tracks` (null when the log has none). GLOBAL_TRACKS of frame k goes out
// with the GLOBAL_MAP of k and fuses the robots' tracks that reached main by then
// (mostly those of frame k - 1): it is scored as it would be drawn at frame k.
//
// Latency: POSE_<r> receive time in the log (lcm-logger's timestamp) minus its
// source_utime (the SENSOR frame's publish time), `latency_us`; the robot's own
// publish time of the POSE (its utime) minus source_utime, `pose_publish_latency_us`
// (sensor publish to pose publish: no logger hop); global-map latency: receive time
// of the first GLOBAL_MAP whose frame is >= k minus the latest SENSOR utime of
// frame k. Both clocks are the same machine's wall clock.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "elaslam/common/limits.hpp"
#include "elaslam/eval/frame_data.hpp"
#include "elaslam/eval/report.hpp"
#include "elaslam/eval/run_result.hpp"
#include "elaslam/eval/track_score.hpp"
#include "elaslam/logs/frame_accounting.hpp"
#include "elaslam/logs/log_auth.hpp"
#include "elaslam/logs/log_reader.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/run_info_t.hpp"

namespace elaslam {

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

/// What the log holds, by frame and by robot, as read.
struct LogData {
  std::map<int, FrameData> truth;                       // frame -> truth part
  std::map<int, std::vector<std::uint8_t>> truth_present;  // frame -> present[id]: the truth lists landmark id
  // Tracks as TrackScorer's samples (TrackSample::robot: the robot id; 0 for main's
  // fused tracks): frame -> the valid chunks of each robot's TRACKS_<r>, and of
  // GLOBAL_TRACKS, each chunk once.
  std::map<int, std::vector<TrackSample>> robot_tracks, global_tracks;
  struct TrackChunks {
    std::int64_t utime = 0;  // the frame's first publication's (main may send a frame's twice)
    int num_chunks = 0;  // the publication's, from its first chunk read
    unsigned taken = 0;  // bit c: chunk c taken
  };
  std::map<std::pair<int, int>, TrackChunks> tracks_chunks;  // (frame, robot) -> its TRACKS chunks taken
  std::map<int, TrackChunks> global_tracks_chunks;           // frame -> its GLOBAL_TRACKS chunks taken
  long track_messages = 0, global_track_messages = 0;  // valid chunks read
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

/// One event of the log (already verified, when the log is): the team's channels
/// (with its suffix `sfx`) are decoded into `d` (an undecodable or refused one is
/// counted), others ignored.
void add_log_event(const LogEvent& ev, const std::string& sfx, LogData* d);

/// Every event of the log at `path` into `d` (through d->auth when set). A damaged
/// log (stray bytes, a truncated tail) is read as far as it holds whole events
/// (logs/log_reader.hpp); what was skipped is counted. False, with `*why`, when the
/// log cannot be read, holds no ground truth, or none of it verifies.
bool read_log(const std::string& path, const std::string& suffix, LogData* d, std::string* why);

struct Quantiles {
  std::int64_t p50 = 0, p99 = 0, max = 0;
  std::size_t count = 0;
};

Quantiles quantiles(const std::vector<std::int64_t>& v);
nlohmann::json to_json(const Quantiles& q);

/// The log as the metrics' frames, with the latencies and each robot's POSE
/// checkpoints (for the frame accounting) gathered on the way.
struct AssembledRun {
  RunResult r;
  std::vector<int> robot_ids;
  std::vector<std::vector<std::int64_t>> latency, publish_latency;  // [us] per robot
  std::vector<std::int64_t> all_latency, all_publish_latency, map_latency;
  std::vector<std::vector<PoseCheckpoint>> checkpoints;  // per robot
};

/// `d` (read_log's, with ground truth) as a run: frame times start at 0 at the first
/// frame; each frame's map is the first GLOBAL_MAP stamped with it, else the newest
/// older one. The logged tracks are scored (score_log_tracks).
/// The logged tracks against the truth, frame by frame (times as assemble_run makes
/// them): the robots' into m->tracks, main's fused ones into m->global_tracks, each
/// scored (tracks_scored, global_tracks_scored) when the log holds any such message.
void score_log_tracks(const LogData& d, RunMetrics* m);
AssembledRun assemble_run(LogData& d);

/// The robots' mode as they report it (STATUS_ROBOT): "" when they did not report
/// or disagree (then `*disagree`).
std::string reported_mode(const LogData& d, bool* disagree);

/// RUN_INFO as metrics.json's "run_info".
nlohmann::json run_info_json(const run_info_t& m);

/// What the command line says of the run, for logs that do not: negative numbers
/// and an empty mode are unknown.
struct RunFallbacks {
  std::string source;        // the log file
  std::string command_line;  // the evaluation's command (provenance)
  std::string mode;
  double dynamism = -1.0, speed = -1.0;
  long long seed = -1;
};

/// The run's facts: RUN_INFO first (what the source ran), then the robots' STATUS
/// (mode), then the fallbacks, then what the ground truth shows. Where the sources
/// disagree, a line saying which was used goes to `warnings`.
RunInfo run_facts(const RunFallbacks& a, const LogData& d, std::vector<std::string>* warnings);

/// Every frame of the run, per robot (logs/frame_accounting.hpp), into metrics.json
/// `j` (per robot and in total); returns the accounts.
std::vector<RobotFrameAccount> account_run_frames(const LogData& d, const AssembledRun& x, nlohmann::json* j);

/// Latency quantiles (overall and per robot) and the log's own figures (events,
/// damage, undecodable and invalid messages, authentication, capacity faults, the
/// nodes' refusals) into metrics.json `j`.
void add_log_figures(const LogData& d, const AssembledRun& x, nlohmann::json* j);

/// The evaluation's summary on `out`: print_summary's table, latency, frames and
/// what of the log was not evaluated. `j`: metrics.json with account_run_frames' totals.
void print_log_report(std::ostream& out, const LogData& d, const AssembledRun& x, const RunInfo& info,
                      const nlohmann::json& j, const std::vector<RobotFrameAccount>& accounts);

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// What the viewer draws (viewer/STATE_SCHEMA.md): the team's state as the bus tells
// it, built from RUN_INFO, POSE_<r>, GLOBAL_MAP (its chunks), DYNAMIC_NOTICE,
// STATUS_ROBOT_<r>, CANDIDATES_<r>, TRACKS_<r>, GLOBAL_TRACKS and GROUND_TRUTH, and written as one JSON document. A plain
// subscriber's state: every message is checked before it is taken (a bad one is
// counted and changes nothing), and everything kept is bounded (trails, notices,
// landmark ids below max_landmark_id, robot ids 1..kMaxRobots).
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "elaslam/candidate_list_t.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/dynamic_notice_t.hpp"
#include "elaslam/global_map_t.hpp"
#include "elaslam/global_tracks_t.hpp"
#include "elaslam/ground_truth_t.hpp"
#include "elaslam/node_status_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/run_info_t.hpp"
#include "elaslam/track_list_t.hpp"

namespace elaslam::viewer {

struct ViewLimits {
  int max_landmark_id = 256;  // landmark ids [0, max_landmark_id)
  int trail_points = 500;     // poses kept per robot trail
  int notices = 50;           // newest notices kept
  double world_bound_m = 1.0e4;
};

/// The bounds of the config's main: section the state checks messages against
/// (main.max_landmark_id, main.limits.world_bound_m). Throws config::ConfigError.
ViewLimits load_view_limits(const std::string& config_path);

/// The viewer's own counters for ViewState::to_json, as a JSON object: messages
/// received, bad ones (refused, undecodable, unauthenticated), POSEs missed in queues,
/// event streams open, states pushed per second.
std::string viewer_counters_json(long long messages, long long bad_messages, long long queue_drops, int clients,
                                 double updates_per_s);

class ViewState {
 public:
  static constexpr int kMaxRobots = contract::kMaxRobots;
  explicit ViewState(const ViewLimits& limits = {});

  // Each returns false, counts the message as bad and changes nothing when the
  // message is absurd (non-finite numbers, ids out of range, inconsistent counts).
  bool on_run_info(const run_info_t& m);
  bool on_pose(const pose_estimate_t& m);
  bool on_global_map(const global_map_t& m);
  bool on_notice(const dynamic_notice_t& m);
  bool on_status(const node_status_t& m, double now_s);
  bool on_truth(const ground_truth_t& m);
  /// A robot's candidates replace its earlier ones; a landmark that is a candidate
  /// of some robot and not static in the global map is drawn as a candidate. A
  /// robot's list older than kCandidateFrames frames is dropped (it stopped).
  bool on_candidates(const candidate_list_t& m);
  static constexpr int kCandidateFrames = 20;
  /// A robot's tracks of its moving landmarks (TRACKS_<r>) replace its earlier ones;
  /// main's fused tracks (GLOBAL_TRACKS) replace the earlier fused ones. Each comes
  /// in chunks: the chunks of the newest frame are drawn together, as they come (a
  /// lost chunk's tracks are missing for that frame only). Checked as main checks
  /// them (common/track_checks.hpp), and a chunk whose num_chunks or landmark ids
  /// are at odds with the chunks held of its frame is refused (drops, nothing
  /// changes); a list older than kCandidateFrames frames is not drawn (its sender
  /// stopped).
  bool on_tracks(const track_list_t& m);
  bool on_global_tracks(const global_tracks_t& m);

  /// The state as JSON (viewer/STATE_SCHEMA.md); `viewer_counters` is the
  /// "viewer" object (messages, drops, clients), filled by the program.
  std::string to_json(double now_s, const std::string& viewer_counters_json = "{}") const;

  int frame() const { return frame_; }
  /// Counts the messages taken: unchanged, the state to draw is too (the viewer
  /// skips rebuilding it).
  long long changes() const { return messages_ - bad_; }
  long long bad_messages() const { return bad_; }
  long long messages() const { return messages_; }

 private:
  /// The chunks held of one tracks publication.
  struct TrackChunks {
    std::int64_t utime = 0;  // the publication's (with its frame)
    int num_chunks = 0;
    unsigned received = 0;  // bit c: chunk c
  };
  /// One track as drawn: where, how fast, its model.
  struct Track {
    int id = -1;
    double x = 0, y = 0, vx = 0, vy = 0, cxx = 0, cxy = 0, cyy = 0;
    std::array<double, 3> probabilities{};
    int likeliest = 0;
    bool stopped = false, validated = false;
    int contributors = 0;  // fused tracks: bit r-1, robot r
  };
  struct Robot {
    bool has_pose = false;
    int frame = -1;
    double x = 0, y = 0, theta = 0, cxx = 0, cxy = 0, cyy = 0;
    std::deque<std::array<double, 2>> trail;
    bool has_truth = false;
    double tx = 0, ty = 0, ttheta = 0;
    std::deque<std::array<double, 2>> truth_trail;
    bool has_status = false;
    double status_s = 0;
    node_status_t status;
    int candidates_frame = -1;
    std::vector<std::array<double, 6>> candidates;  // id, x, y, cxx, cxy, cyy
    int tracks_frame = -1;
    TrackChunks tracks_chunks;
    std::vector<Track> tracks;  // the chunks held of frame tracks_frame
  };
  struct Landmark {
    bool known = false;  // a position was ever received
    bool in_map = false;  // in the latest GLOBAL_MAP chunk covering it (static or moving)
    bool moving = false;
    double x = 0, y = 0, cxx = 0, cxy = 0, cyy = 0;
    int contributors = 0;  // bit r-1: robot r
  };
  struct TruthLandmark {
    int id;
    double x, y;
    bool moving;
  };
  struct Notice {
    int frame, landmark, robot;
  };

  bool bad(const char* why);
  void see_frame(int frame);
  /// A frame from the frame source (GROUND_TRUTH, RUN_INFO): a replay started over
  /// (the source's frame far behind the header) takes the header back with it.
  void see_source_frame(int frame);
  Robot& robot(int id) { return robots_[id]; }
  void push_trail(std::deque<std::array<double, 2>>* t, double x, double y) const;
  // Parts of to_json: each robot's entry; the map's landmarks with the candidates
  // drawn in the places that are not static in the map.
  nlohmann::json robot_json(int id, const Robot& r, double now_s) const;
  static nlohmann::json track_json(const Track& t, bool fused);
  nlohmann::json landmarks_json() const;

  ViewLimits limits_;
  int frame_ = -1;
  int frames_total_ = 0;
  long long messages_ = 0, bad_ = 0;
  std::map<int, Robot> robots_;
  std::vector<Landmark> landmarks_;
  std::vector<TruthLandmark> truth_landmarks_;
  std::deque<Notice> notices_;
  std::int64_t map_version_ = -1;
  int global_tracks_frame_ = -1;
  TrackChunks global_tracks_chunks_;
  std::vector<Track> global_tracks_;  // the chunks held of frame global_tracks_frame_
  std::map<std::string, long long> bad_by_reason_;  // the "viewer" object shows it
};

}  // namespace elaslam::viewer

// SPDX-License-Identifier: Apache-2.0
#include "elaslam/viewer/view_state.hpp"

#include <cmath>
#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "elaslam/common/contract.hpp"
#include "elaslam/common/faults.hpp"
#include "elaslam/common/track_checks.hpp"

namespace elaslam::viewer {
namespace {

bool finite(double v) { return std::isfinite(v); }
bool finite_all(std::initializer_list<double> vs) {
  for (double v : vs)
    if (!std::isfinite(v)) return false;
  return true;
}

nlohmann::json trail_json(const std::deque<std::array<double, 2>>& t) {
  nlohmann::json a = nlohmann::json::array();
  for (const auto& p : t) a.push_back({p[0], p[1]});
  return a;
}

// node_status_t.fault_flags as words (the page lists them; common/faults.hpp).
nlohmann::json faults_json(std::int32_t f) {
  nlohmann::json a = nlohmann::json::array();
  for (const std::string& name : fault_names(f)) a.push_back(name);
  return a;
}

}  // namespace

ViewState::ViewState(const ViewLimits& limits)
    : limits_(limits), landmarks_(static_cast<std::size_t>(limits.max_landmark_id)) {}

bool ViewState::bad(const char* why) {
  ++bad_;
  ++bad_by_reason_[why];
  return false;
}

void ViewState::see_frame(int frame) {
  if (frame > frame_) frame_ = frame;
}

// A datagram a few frames late is not a restart; a source 10 frames (1 s at 10 Hz)
// or more behind the header is: a replay looped or a new run began.
void ViewState::see_source_frame(int frame) {
  constexpr int kRestartFrames = 10;
  if (frame >= 0 && frame <= frame_ - kRestartFrames) {
    frame_ = frame;
    for (auto& [id, r] : robots_) r.truth_trail.clear();
    return;
  }
  see_frame(frame);
}

void ViewState::push_trail(std::deque<std::array<double, 2>>* t, double x, double y) const {
  t->push_back({x, y});
  while (static_cast<int>(t->size()) > limits_.trail_points) t->pop_front();
}

bool ViewState::on_run_info(const run_info_t& m) {
  ++messages_;
  if (m.frames < 0 || m.frame < -1) return bad("RUN_INFO frames out of range");
  frames_total_ = m.frames;
  see_source_frame(m.frame);
  return true;
}

bool ViewState::on_pose(const pose_estimate_t& m) {
  ++messages_;
  const double b = limits_.world_bound_m;
  if (m.robot_id < 1 || m.robot_id > kMaxRobots || m.frame < 0) return bad("POSE robot id or frame out of range");
  if (!finite_all({m.x, m.y, m.theta, m.cov[0][0], m.cov[0][1], m.cov[1][1]})) return bad("POSE not finite");
  if (std::fabs(m.x) > b || std::fabs(m.y) > b || m.cov[0][0] < 0 || m.cov[1][1] < 0) return bad("POSE out of bounds");
  Robot& r = robot(m.robot_id);
  // A robot that restarted begins again at frame 0: its trail starts over.
  if (m.frame < r.frame) r.trail.clear();
  r.has_pose = true;
  r.frame = m.frame;
  r.x = m.x, r.y = m.y, r.theta = m.theta;
  r.cxx = m.cov[0][0], r.cxy = m.cov[0][1], r.cyy = m.cov[1][1];
  push_trail(&r.trail, m.x, m.y);
  see_frame(m.frame);
  return true;
}

bool ViewState::on_global_map(const global_map_t& m) {
  ++messages_;
  const double b = limits_.world_bound_m;
  if (m.frame < -1 || m.num_chunks < 1 || m.chunk < 0 || m.chunk >= m.num_chunks) return bad("GLOBAL_MAP frame or chunk out of range");
  if (m.id_begin < 0 || m.id_end <= m.id_begin || m.id_end > limits_.max_landmark_id) return bad("GLOBAL_MAP id range");
  if (!contract::count_fits(m.landmarks, m.num_landmarks) || !contract::count_fits(m.moving_ids, m.num_moving))
    return bad("GLOBAL_MAP counts");
  if (m.version < map_version_ - 1000) return bad("GLOBAL_MAP stale version");  // far older than what we drew
  // Only the first num_* entries: a decoder that reuses its message leaves old ones
  // behind them (LCM does not shrink an array whose count is 0).
  const auto n_lms = static_cast<std::size_t>(m.num_landmarks), n_moving = static_cast<std::size_t>(m.num_moving);
  for (std::size_t k = 0; k < n_lms; ++k) {
    const global_landmark_t& l = m.landmarks[k];
    if (l.id < m.id_begin || l.id >= m.id_end) return bad("GLOBAL_MAP landmark id outside the chunk");
    if (!finite_all({l.x, l.y, l.cov[0][0], l.cov[0][1], l.cov[1][1]})) return bad("GLOBAL_MAP landmark not finite");
    if (std::fabs(l.x) > b || std::fabs(l.y) > b || l.cov[0][0] < 0 || l.cov[1][1] < 0)
      return bad("GLOBAL_MAP landmark out of bounds");
  }
  for (std::size_t k = 0; k < n_moving; ++k)
    if (m.moving_ids[k] < m.id_begin || m.moving_ids[k] >= m.id_end) return bad("GLOBAL_MAP moving id outside the chunk");
  // The chunk stands alone for its id range: what it does not list is not in the map.
  for (int id = m.id_begin; id < m.id_end; ++id) {
    Landmark& l = landmarks_[static_cast<std::size_t>(id)];
    l.in_map = false;
    l.moving = false;
  }
  for (std::size_t k = 0; k < n_lms; ++k) {
    const global_landmark_t& g = m.landmarks[k];
    Landmark& l = landmarks_[static_cast<std::size_t>(g.id)];
    l.known = l.in_map = true;
    l.moving = g.status == global_landmark_t::MOVING;
    l.x = g.x, l.y = g.y;
    l.cxx = g.cov[0][0], l.cxy = g.cov[0][1], l.cyy = g.cov[1][1];
    l.contributors = g.contributors;
  }
  // A moving landmark has no estimate in the map: it is drawn where it was last mapped.
  for (std::size_t k = 0; k < n_moving; ++k) {
    Landmark& l = landmarks_[static_cast<std::size_t>(m.moving_ids[k])];
    l.moving = true;
    l.in_map = l.known;
  }
  if (m.version > map_version_) map_version_ = m.version;
  see_frame(m.frame);
  return true;
}

bool ViewState::on_notice(const dynamic_notice_t& m) {
  ++messages_;
  if (m.landmark_id < 0 || m.landmark_id >= limits_.max_landmark_id || m.frame < 0) return bad("DYNAMIC_NOTICE id or frame");
  if (m.detected_by < 0 || m.detected_by > kMaxRobots) return bad("DYNAMIC_NOTICE robot id");
  // The same notice repeated (main re-sends them) is listed once.
  for (const Notice& n : notices_)
    if (n.landmark == m.landmark_id && n.frame == m.frame && n.robot == m.detected_by) return true;
  notices_.push_back({m.frame, m.landmark_id, m.detected_by});
  while (static_cast<int>(notices_.size()) > limits_.notices) notices_.pop_front();
  return true;
}

bool ViewState::on_status(const node_status_t& m, double now_s) {
  ++messages_;
  if (m.node_kind != node_status_t::ROBOT || m.node_id < 1 || m.node_id > kMaxRobots) return bad("STATUS not a robot's");
  bool negative = m.frames < 0 || m.frames_dropped < 0 || m.decode_errors < 0 || m.queue_drops < 0 ||
                  m.filter_faults < 0 || m.auth_refused < 0;
  for (std::int64_t n : m.refused) negative = negative || n < 0;
  if (negative) return bad("STATUS negative counter");
  if (!finite_all({m.odom_turn_scale, m.odom_turn_scale_sigma, m.odom_speed_scale, m.odom_speed_scale_sigma,
                   m.odom_turn_bias_rad_s, m.odom_turn_bias_sigma_rad_s}))
    return bad("STATUS odometer calibration not finite");
  Robot& r = robot(m.node_id);
  r.has_status = true;
  r.status = m;
  r.status_s = now_s;
  return true;
}

bool ViewState::on_truth(const ground_truth_t& m) {
  ++messages_;
  const double b = limits_.world_bound_m;
  if (m.num_robots > contract::kMaxRobots || !contract::count_fits(m.robot_ids, m.num_robots) ||
      !contract::count_fits(m.robots, m.num_robots) || !contract::count_fits(m.landmarks, m.num_landmarks) || m.frame < 0)
    return bad("GROUND_TRUTH counts or frame");
  for (int k = 0; k < m.num_robots; ++k) {
    const pose2_t& p = m.robots[k];
    if (m.robot_ids[k] < 1 || m.robot_ids[k] > kMaxRobots || !finite_all({p.x, p.y, p.theta}))
      return bad("GROUND_TRUTH robot");
    if (std::fabs(p.x) > b || std::fabs(p.y) > b) return bad("GROUND_TRUTH robot out of bounds");
  }
  for (int k = 0; k < m.num_landmarks; ++k) {
    const landmark_truth_t& l = m.landmarks[k];
    if (!finite(l.x) || !finite(l.y) || std::fabs(l.x) > b || std::fabs(l.y) > b) return bad("GROUND_TRUTH landmark");
  }
  see_source_frame(m.frame);  // first: a replay that started over clears the old trails
  for (int k = 0; k < m.num_robots; ++k) {
    Robot& r = robot(m.robot_ids[k]);
    r.has_truth = true;
    r.tx = m.robots[k].x, r.ty = m.robots[k].y, r.ttheta = m.robots[k].theta;
    push_trail(&r.truth_trail, r.tx, r.ty);
  }
  truth_landmarks_.clear();
  for (int k = 0; k < m.num_landmarks; ++k) {
    const landmark_truth_t& l = m.landmarks[k];
    truth_landmarks_.push_back({l.id, l.x, l.y, l.moving != 0});
  }
  return true;
}

bool ViewState::on_candidates(const candidate_list_t& m) {
  ++messages_;
  const double b = limits_.world_bound_m;
  if (m.robot_id < 1 || m.robot_id > kMaxRobots || m.frame < 0) return bad("CANDIDATES robot id or frame");
  if (m.num_candidates < 0 || !contract::count_fits(m.candidates, m.num_candidates)) return bad("CANDIDATES count");
  for (int k = 0; k < m.num_candidates; ++k) {
    const landmark_estimate_t& l = m.candidates[static_cast<std::size_t>(k)];
    if (l.id < 0 || l.id >= limits_.max_landmark_id) return bad("CANDIDATES landmark id");
    if (!finite_all({l.x, l.y, l.cov[0][0], l.cov[0][1], l.cov[1][1]}) || std::fabs(l.x) > b || std::fabs(l.y) > b)
      return bad("CANDIDATES landmark out of bounds");
  }
  Robot& r = robot(m.robot_id);
  if (m.frame < r.candidates_frame && r.candidates_frame - m.frame < 1000) return true;  // older than what we have
  r.candidates_frame = m.frame;
  r.candidates.clear();
  for (int k = 0; k < m.num_candidates; ++k) {
    const landmark_estimate_t& l = m.candidates[static_cast<std::size_t>(k)];
    r.candidates.push_back({static_cast<double>(l.id), l.x, l.y, l.cov[0][0], l.cov[0][1], l.cov[1][1]});
  }
  see_frame(m.frame);
  return true;
}

namespace {

// Takes a chunk of a tracks message (TRACKS_<r>, GLOBAL_TRACKS) into `held`, the
// tracks of the publication drawn: a chunk of a newer publication starts it over
// (`held` cleared), a chunk not yet held is added. A publication is its frame and
// utime: main may send a frame's GLOBAL_TRACKS twice (a quiet period's repeated
// map), the later one newer. A chunk of an older publication, or held already, is
// ignored (*taken false). Returns the reason a chunk is refused, nothing changed:
// its num_chunks or one of its landmark ids at odds with the chunks held; else
// nullptr. A frame more than 1000 behind is a sender that started over.
struct ChunkRefusals {
  const char* num_chunks;  // num_chunks differs from the publication's
  const char* twice;       // a landmark listed in another chunk
};
template <class Msg, class Chunks, class T>
const char* place_chunk(const Msg& m, const ChunkRefusals& why, int* frame, Chunks* chunks, std::vector<T>* held,
                        bool* taken) {
  *taken = false;
  if (m.frame < *frame && *frame - m.frame < 1000) return nullptr;
  if (m.frame == *frame && m.utime < chunks->utime) return nullptr;
  if (m.frame != *frame || m.utime != chunks->utime) {
    *frame = m.frame;
    chunks->utime = m.utime;
    chunks->num_chunks = m.num_chunks;
    chunks->received = 0;
    held->clear();
  } else {
    if (m.num_chunks != chunks->num_chunks) return why.num_chunks;
    if ((chunks->received >> m.chunk) & 1u) return nullptr;
    for (int k = 0; k < m.num_tracks; ++k)
      for (const T& t : *held)
        if (t.id == m.tracks[static_cast<std::size_t>(k)].id) return why.twice;
  }
  chunks->received |= 1u << m.chunk;
  *taken = true;
  return nullptr;
}

/// What the viewer holds a message's values to: main's world bound, the contract's
/// defaults otherwise.
MessageLimits message_limits(const ViewLimits& v) {
  MessageLimits l;
  l.world_bound = v.world_bound_m;
  return l;
}

}  // namespace

bool ViewState::on_tracks(const track_list_t& m) {
  ++messages_;
  Refusal reason = Refusal::kMalformed;
  if (!check_track_list(m, message_limits(limits_), limits_.max_landmark_id, &reason).empty()) return bad("TRACKS invalid");
  Robot& r = robot(m.robot_id);
  // The chunks of the robot's newest frame, drawn as they come.
  static constexpr ChunkRefusals kWhy{"TRACKS num_chunks differs from its frame's other chunks",
                                     "TRACKS landmark id in two chunks"};
  bool taken = false;
  if (const char* why = place_chunk(m, kWhy, &r.tracks_frame, &r.tracks_chunks, &r.tracks, &taken)) return bad(why);
  if (!taken) return true;
  for (int k = 0; k < m.num_tracks; ++k) {
    const track_t& t = m.tracks[static_cast<std::size_t>(k)];
    r.tracks.push_back({t.id, t.x, t.y, t.vx, t.vy, t.cov[0], t.cov[1], t.cov[4],
                        {t.probabilities[0], t.probabilities[1], t.probabilities[2]}, t.likeliest, t.stopped != 0,
                        t.validated != 0, 1 << (m.robot_id - 1)});
  }
  see_frame(m.frame);
  return true;
}

bool ViewState::on_global_tracks(const global_tracks_t& m) {
  ++messages_;
  Refusal reason = Refusal::kMalformed;
  if (!check_global_tracks(m, message_limits(limits_), limits_.max_landmark_id, &reason).empty()) return bad("GLOBAL_TRACKS invalid");
  static constexpr ChunkRefusals kWhy{"GLOBAL_TRACKS num_chunks differs from its frame's other chunks",
                                     "GLOBAL_TRACKS landmark id in two chunks"};
  bool taken = false;
  if (const char* why = place_chunk(m, kWhy, &global_tracks_frame_, &global_tracks_chunks_, &global_tracks_, &taken))
    return bad(why);
  if (!taken) return true;
  for (int k = 0; k < m.num_tracks; ++k) {
    const global_track_t& t = m.tracks[static_cast<std::size_t>(k)];
    global_tracks_.push_back({t.id, t.x, t.y, t.vx, t.vy, t.cov[0], t.cov[1], t.cov[4],
                              {t.probabilities[0], t.probabilities[1], t.probabilities[2]}, t.likeliest,
                              t.stopped != 0, false, t.contributors});
  }
  see_frame(m.frame);
  return true;
}

nlohmann::json ViewState::track_json(const Track& t, bool fused) {
  static const char* const kModels[] = {"static", "bounded", "constant_velocity"};
  nlohmann::json o = {{"id", t.id},
                      {"x", t.x},
                      {"y", t.y},
                      {"vx", t.vx},
                      {"vy", t.vy},
                      {"cov", {t.cxx, t.cxy, t.cyy}},
                      {"model", kModels[t.likeliest]},
                      {"probabilities", {t.probabilities[0], t.probabilities[1], t.probabilities[2]}},
                      {"stopped", t.stopped}};
  if (fused) {
    nlohmann::json by = nlohmann::json::array();
    for (int r = 0; r < kMaxRobots; ++r)
      if (t.contributors & (1 << r)) by.push_back(r + 1);
    o["contributors"] = std::move(by);
  } else {
    o["validated"] = t.validated;
  }
  return o;
}

nlohmann::json ViewState::robot_json(int id, const Robot& r, double now_s) const {
  nlohmann::json o;
  o["id"] = id;
  o["frame"] = r.frame;
  if (r.has_pose) {
    o["x"] = r.x, o["y"] = r.y, o["theta"] = r.theta;
    o["cov"] = {r.cxx, r.cxy, r.cyy};
  } else {
    o["x"] = o["y"] = o["theta"] = o["cov"] = nullptr;
  }
  o["trail"] = trail_json(r.trail);
  if (r.has_truth) {
    o["truth"] = {{"x", r.tx}, {"y", r.ty}, {"theta", r.ttheta}};
  } else {
    o["truth"] = nullptr;
  }
  o["truth_trail"] = trail_json(r.truth_trail);
  nlohmann::json tracks = nlohmann::json::array();
  if (r.tracks_frame >= 0 && frame_ - r.tracks_frame <= kCandidateFrames)
    for (const Track& t : r.tracks) tracks.push_back(track_json(t, false));
  o["tracks"] = std::move(tracks);
  if (!r.has_status) {
    o["health"] = nullptr;
    return o;
  }
  const node_status_t& s = r.status;
  // Counters are >= 0 (on_status); their sum saturates (a forged STATUS may say 2^63 - 1).
  std::int64_t refused = s.auth_refused;
  for (std::int64_t n : s.refused) refused = n > INT64_MAX - refused ? INT64_MAX : refused + n;
  o["health"] = {{"frames", s.frames},
                 {"frames_dropped", s.frames_dropped},
                 {"refused", refused},
                 {"decode_errors", s.decode_errors},
                 {"faults", faults_json(s.fault_flags)},
                 {"queue_drops", s.queue_drops},
                 {"filter_faults", s.filter_faults},
                 {"latency_p50_us", s.processing_us_p50},
                 {"latency_p99_us", s.processing_us_p99},
                 {"status_age_s", now_s - r.status_s},
                 {"odometry", {{"turn_scale", s.odom_turn_scale},
                               {"turn_scale_sigma", s.odom_turn_scale_sigma},
                               {"speed_scale", s.odom_speed_scale},
                               {"speed_scale_sigma", s.odom_speed_scale_sigma},
                               {"turn_bias_rad_s", s.odom_turn_bias_rad_s},
                               {"turn_bias_sigma_rad_s", s.odom_turn_bias_sigma_rad_s}}}};
  return o;
}

// Candidates: not static in the map (new, or back after moving: the candidate
// replaces the moving entry), seen by a robot lately; the first robot's is drawn.
nlohmann::json ViewState::landmarks_json() const {
  struct Drawn {
    int robot;
    const std::array<double, 6>* c;  // id, x, y, cxx, cxy, cyy
  };
  std::vector<Drawn> candidates;
  std::vector<bool> taken(landmarks_.size(), false);
  for (std::size_t id = 0; id < landmarks_.size(); ++id) taken[id] = landmarks_[id].in_map && !landmarks_[id].moving;
  for (const auto& [rid, r] : robots_) {
    if (r.candidates_frame < 0 || frame_ - r.candidates_frame > kCandidateFrames) continue;
    for (const auto& c : r.candidates) {
      const auto id = static_cast<std::size_t>(c[0]);
      if (taken[id]) continue;
      taken[id] = true;
      candidates.push_back({rid, &c});
    }
  }
  nlohmann::json lms = nlohmann::json::array();
  for (int id = 0; id < static_cast<int>(landmarks_.size()); ++id) {
    const Landmark& l = landmarks_[static_cast<std::size_t>(id)];
    // In the map, unless a robot's candidate took its place.
    if (!l.in_map || (l.moving && taken[static_cast<std::size_t>(id)])) continue;
    nlohmann::json by = nlohmann::json::array();
    for (int r = 0; r < 16; ++r)
      if (l.contributors & (1 << r)) by.push_back(r + 1);
    lms.push_back({{"id", id},
                   {"x", l.x},
                   {"y", l.y},
                   {"cov", {l.cxx, l.cxy, l.cyy}},
                   {"status", l.moving ? "moving" : "static"},
                   {"contributors", std::move(by)}});
  }
  for (const Drawn& d : candidates) {
    const auto& c = *d.c;
    lms.push_back({{"id", static_cast<int>(c[0])},
                   {"x", c[1]},
                   {"y", c[2]},
                   {"cov", {c[3], c[4], c[5]}},
                   {"status", "candidate"},
                   {"contributors", {d.robot}}});
  }
  return lms;
}

std::string ViewState::to_json(double now_s, const std::string& viewer_counters_json) const {
  nlohmann::json j;
  j["frame"] = frame_;
  j["frames_total"] = frames_total_;
  j["world"] = nullptr;
  nlohmann::json robots = nlohmann::json::array();
  for (const auto& [id, r] : robots_)
    if (r.has_pose || r.has_status || r.has_truth) robots.push_back(robot_json(id, r, now_s));
  j["robots"] = std::move(robots);
  j["landmarks"] = landmarks_json();
  nlohmann::json fused = nlohmann::json::array();
  if (global_tracks_frame_ >= 0 && frame_ - global_tracks_frame_ <= kCandidateFrames)
    for (const Track& t : global_tracks_) fused.push_back(track_json(t, true));
  j["global_tracks"] = std::move(fused);
  nlohmann::json truth = nlohmann::json::array();
  for (const TruthLandmark& t : truth_landmarks_)
    truth.push_back({{"id", t.id}, {"x", t.x}, {"y", t.y}, {"moving", t.moving}});
  j["truth_landmarks"] = std::move(truth);
  nlohmann::json notices = nlohmann::json::array();
  for (const Notice& n : notices_) notices.push_back({{"frame", n.frame}, {"landmark", n.landmark}, {"robot", n.robot}});
  j["notices"] = std::move(notices);
  j["viewer"] = nlohmann::json::parse(viewer_counters_json, nullptr, false);
  j["viewer"]["bad_by_reason"] = bad_by_reason_;
  return j.dump();
}

}  // namespace elaslam::viewer

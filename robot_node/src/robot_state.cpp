// SPDX-License-Identifier: Apache-2.0
#include "elaslam/robot_node/robot_state.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <utility>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <nlohmann/json.hpp>

#include "elaslam/common/contract.hpp"

namespace elaslam {

using json = nlohmann::json;

namespace {

// Anything beyond these is a corrupt file, not a robot's state.
// Positions and covariances: limits.* of the configuration (common/limits.hpp), the
// same bounds a message must meet. Beyond these, a corrupt file.
constexpr double kMaxVariance = 1e12;     // [m^2], [rad^2] (a structural bound; limits.cov_ceiling_m2 is tighter)
constexpr double kMaxWhitened = 1e12;     // drift and innovation sums (whitened, unitless)
constexpr double kAngleSlack = 1e-9;      // [rad] on [-pi, pi]
constexpr double kMaxCount = 1e15;        // seq and counters
constexpr double kMaxIncarnation = 1e18;  // [us] wall clock at a fresh start
constexpr double kPsdTolerance = 1e-9;    // LDLT pivots >= -tol * max(1, max diag(P))
constexpr int kMaxFrame = std::numeric_limits<int>::max();
constexpr int kMinReportedFrame = -1000000;  // LMapEntry::reported_frame's "never"
constexpr std::size_t kMaxHistoryOps = 1000000;  // robot.history.ops (a ring holds far fewer)
// The odometer's calibration states (StateLayout::kTurnScale..kTurnBias): a scale
// outside these, or a bias beyond this, is no odometer's.
constexpr double kMinScale = 0.01, kMaxScale = 100.0;
constexpr double kMaxTurnBias = 100.0;  // [rad/s]
constexpr double kMaxStepSeconds = 1e6;  // [s] a history operation's dt
constexpr double kMaxUtime = 1e18;       // [us]

struct StateError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

[[noreturn]] void fail(const std::string& where, const std::string& what) { throw StateError(where + ": " + what); }

std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

const json& need(const json& o, const std::string& where, const char* key) {
  if (!o.is_object()) fail(where, "not an object");
  const auto it = o.find(key);
  if (it == o.end()) fail(where + "." + key, "missing");
  return *it;
}

double real(const json& v, const std::string& where, double lo, double hi) {
  if (!v.is_number()) fail(where, v.is_null() ? "null (a NaN or infinity when saved?)" : "not a number");
  const double d = v.get<double>();
  if (!std::isfinite(d)) fail(where, "not finite");
  if (d < lo || d > hi) fail(where, num(d) + " outside [" + num(lo) + ", " + num(hi) + "]");
  return d;
}

std::int64_t whole(const json& v, const std::string& where, double lo, double hi) {
  if (!v.is_number_integer()) fail(where, "not an integer");
  const double d = v.is_number_unsigned() ? static_cast<double>(v.get<std::uint64_t>()) : static_cast<double>(v.get<std::int64_t>());
  if (d < lo || d > hi) fail(where, num(d) + " outside [" + num(lo) + ", " + num(hi) + "]");
  return v.get<std::int64_t>();
}

bool boolean(const json& v, const std::string& where) {
  if (!v.is_boolean()) fail(where, "not true or false");
  return v.get<bool>();
}

const json& array(const json& v, const std::string& where, std::size_t min_n, std::size_t max_n) {
  if (!v.is_array()) fail(where, "not an array");
  if (v.size() < min_n || v.size() > max_n)
    fail(where, std::to_string(v.size()) + " elements, expected " +
                    (min_n == max_n ? std::to_string(min_n) : std::to_string(min_n) + " to " + std::to_string(max_n)));
  return v;
}

Eigen::Vector2d vec2(const json& v, const std::string& where, double bound) {
  const json& a = array(v, where, 2, 2);
  return {real(a[0], where + "[0]", -bound, bound), real(a[1], where + "[1]", -bound, bound)};
}

// A 2x2 symmetric positive semi-definite matrix, row-major: finite, variances in
// [0, kMaxVariance], symmetric and PSD within rounding.
Eigen::Matrix2d psd2(const json& v, const std::string& where) {
  const json& a = array(v, where, 4, 4);
  Eigen::Matrix2d C;
  for (int k = 0; k < 4; ++k) C(k / 2, k % 2) = real(a[static_cast<std::size_t>(k)], where + "[" + std::to_string(k) + "]", -kMaxVariance, kMaxVariance);
  if (C(0, 0) < 0.0 || C(1, 1) < 0.0) fail(where, "negative variance");
  const double scale = std::max(C(0, 0) + C(1, 1), 1e-300);
  if (std::fabs(C(0, 1) - C(1, 0)) > 1e-6 * scale) fail(where, "not symmetric");
  if (C(0, 0) * C(1, 1) - C(0, 1) * C(1, 0) < -1e-9 * scale * scale) fail(where, "not positive semi-definite");
  return C;
}

// A 2x2 covariance: psd2, and unless all zero (never set), within limits.cov_* like
// a message's.
Eigen::Matrix2d cov2(const json& v, const std::string& where, const MessageLimits& lim) {
  const Eigen::Matrix2d C = psd2(v, where);
  if (!C.isZero(0.0))
    if (const std::string bad = check_cov2(C, lim, "covariance"); !bad.empty()) fail(where, bad);
  return C;
}

json to_json(const Eigen::Vector2d& v) { return json::array({v.x(), v.y()}); }
json to_json(const Eigen::Matrix2d& C) { return json::array({C(0, 0), C(0, 1), C(1, 0), C(1, 1)}); }

// The counters by name (one table for saving and loading).
const std::pair<const char*, std::int64_t RobotNodeCounters::*> kCounters[] = {
    {"frames", &RobotNodeCounters::frames},
    {"frames_gap", &RobotNodeCounters::frames_gap},
    {"frames_duplicate", &RobotNodeCounters::frames_duplicate},
    {"frames_out_of_order", &RobotNodeCounters::frames_out_of_order},
    {"rejected_inputs", &RobotNodeCounters::rejected_inputs},
    {"decode_errors", &RobotNodeCounters::decode_errors},
    {"queue_drops", &RobotNodeCounters::queue_drops},
    {"filter_faults", &RobotNodeCounters::filter_faults},
    {"events_sent", &RobotNodeCounters::events_sent},
    {"notices_applied", &RobotNodeCounters::notices_applied},
    {"notices_ignored", &RobotNodeCounters::notices_ignored},
    {"notices_deferred", &RobotNodeCounters::notices_deferred},
};

// LMapEntry's fields by kind, with their lower bounds (upper: kMaxFrame).
struct IntField {
  const char* name;
  int LMapEntry::*field;
  int lo;
};
const IntField kEntryInts[] = {
    {"last_seen_frame", &LMapEntry::last_seen_frame, -1},
    {"consistent_sightings", &LMapEntry::consistent_sightings, 0},
    {"outside_streak", &LMapEntry::outside_streak, 0},
    {"missing_frames", &LMapEntry::missing_frames, 0},
    {"status_frame", &LMapEntry::status_frame, -1},
    {"reported_frame", &LMapEntry::reported_frame, kMinReportedFrame},
    {"moved_frame", &LMapEntry::moved_frame, -1},
    {"moving_frame", &LMapEntry::moving_frame, -1},
    {"times_moving", &LMapEntry::times_moving, 0},
    {"innovations", &LMapEntry::innovations, 0},
};
const std::pair<const char*, bool LMapEntry::*> kEntryBools[] = {
    {"was_moving", &LMapEntry::was_moving},
    {"reported_moving", &LMapEntry::reported_moving},
};
struct VecField {
  const char* name;
  Eigen::Vector2d LMapEntry::*field;
  double bound;  // 0: limits.world_bound_m
};
const VecField kEntryVecs[] = {
    {"position", &LMapEntry::position, 0.0},
    {"innovation_sum", &LMapEntry::innovation_sum, kMaxWhitened},
    {"drift", &LMapEntry::drift, kMaxWhitened},
};

bool is_default(const LMapEntry& e) {
  const LMapEntry d;
  for (const auto& f : kEntryInts)
    if (e.*f.field != d.*f.field) return false;
  for (const auto& f : kEntryBools)
    if (e.*f.second != d.*f.second) return false;
  for (const auto& f : kEntryVecs)
    if (e.*f.field != d.*f.field) return false;
  return e.status == d.status && e.cov == d.cov && e.checked == d.checked;
}

LandmarkStatus parse_status(const json& v, const std::string& where) {
  if (v.is_string())
    for (LandmarkStatus s : {LandmarkStatus::kUnknown, LandmarkStatus::kCandidate, LandmarkStatus::kStatic,
                             LandmarkStatus::kMoving})
      if (v.get<std::string>() == to_string(s)) return s;
  fail(where, "not one of unknown, candidate, static, moving");
}

}  // namespace

// Friend of Robot, its FilterPair and RobotNode: the only code that reads and writes their private state for the file.
struct RobotStateAccess {
  static json save(const RobotNode& n);
  static void load(const json& state, RobotNode* scratch);

 private:
  static json save_node(const RobotNode& n);
  static json save_filter(const EkfSlam& f);
  static json save_history(const FilterHistory& h);
  static void load_history(const json& h, const std::string& key, const EkfSlam& current, const Robot& r,
                           FilterHistory* out);
  static FilterHistory::Op parse_op(const json& entry, const std::string& where, int first_frame, const Robot& r);
  static void check_replay(const FilterHistory& h, const std::string& key, std::size_t parsed, const EkfSlam& current,
                           const Robot& r);
  static json save_lmap(const LMap& m);
  static void check_header(const json& s, const RobotNode& n);
  static void load_node(const json& s, RobotNode* n);
  static void load_robot(const json& s, Robot* r, int node_last_frame);
  static void parse_filter(const json& f, const std::string& key, const Robot& r, Eigen::VectorXd* x,
                           Eigen::MatrixXd* P, std::vector<int>* slot_ids);
  static void load_filter(const json& s, Robot* r);
  static void load_histories(const json& s, Robot* r);
  static void load_lmap(const json& s, Robot* r);
  static void check_consistency(const Robot& r);
};

json RobotStateAccess::save_node(const RobotNode& n) {
  json counters = json::object();
  for (const auto& c : kCounters) counters[c.first] = n.counters_.*c.second;
  counters["refused"] = n.counters_.refused.n;  // per reason: their sum is rejected_inputs
  const DeferredInputs& d = n.deferred_;
  json held = json::array();
  for (const MovingReport& m : d.held_)
    held.push_back({{"frame", m.frame}, {"landmark_id", m.landmark_id}, {"detected_by", m.detected_by}});
  json had = json::array();  // [id, frame] of the newest report had per landmark (GLOBAL_MAP repair)
  for (std::size_t id = 0; id < d.report_frame_.size(); ++id)
    if (d.report_frame_[id] >= 0) had.push_back({static_cast<int>(id), d.report_frame_[id]});
  json out = {{"last_frame", n.last_frame()}, {"seq", n.messages_.seq_}, {"counters", counters}, {"held_notices", held},
              {"notice_frames", had}};
  // The last frames of the faults STATUS shows for kAlertFrames: optional keys
  // (absent in older files, whose resumed node showed neither).
  if (n.inconsistent_frame_ >= 0) out["inconsistent_frame"] = n.inconsistent_frame_;
  if (n.full_frame_ >= 0) out["full_frame"] = n.full_frame_;
  // The newest team map taken and its estimates still held for a later frame
  // (robot.team_map.fuse): optional, absent in older files.
  if (n.options_.team_map_fuse) {
    json pending = json::array();
    for (std::size_t id = 0; id < d.team_pending_.size(); ++id) {
      const auto& p = d.team_pending_[id];
      if (p.valid)
        pending.push_back({{"id", static_cast<int>(id)}, {"frame", p.frame}, {"position", to_json(p.position)},
                           {"cov", to_json(p.cov)}});
    }
    out["team_map"] = {{"incarnation", d.team_map_incarnation_}, {"version", d.team_map_version_}, {"pending", std::move(pending)}};
  }
  return out;
}

json RobotStateAccess::save_filter(const EkfSlam& f) {
  json ids = json::array();
  for (int slot = 0; slot < f.num_landmarks(); ++slot) ids.push_back(f.id_at(slot));
  json mean = json::array();
  for (Eigen::Index i = 0; i < f.mean().size(); ++i) mean.push_back(f.mean()(i));
  const auto P = f.covariance();
  json lower = json::array();  // row-major lower triangle
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    for (Eigen::Index j = 0; j <= i; ++j) lower.push_back(P(i, j));
  return {{"slot_ids", ids}, {"mean", mean}, {"cov_lower", lower}};
}

// The filter history (robot.ela.candidate_history_frames): the lagged filter and the
// operations since, each [kind, frame, id, values...] with the values its kind uses.
json RobotStateAccess::save_history(const FilterHistory& h) {
  json ops = json::array();
  for (int k = 0; k < h.held(); ++k) {
    const FilterHistory::Op& op = h.op(k);
    json j = json::array({FilterHistory::to_string(op.kind), op.frame, op.id});
    switch (op.kind) {
      case FilterHistory::Kind::kPredict:
        j.push_back(json::array({op.increment.x, op.increment.y, op.increment.theta}));
        j.push_back(json::array({op.U(0, 0), op.U(0, 1), op.U(0, 2), op.U(1, 0), op.U(1, 1), op.U(1, 2), op.U(2, 0),
                                 op.U(2, 1), op.U(2, 2)}));
        j.push_back(op.dt);
        break;
      case FilterHistory::Kind::kUpdate:
      case FilterHistory::Kind::kLandmarkOnly:
      case FilterHistory::Kind::kAdd: j.push_back(json::array({op.z.range, op.z.bearing})); break;
      case FilterHistory::Kind::kPosition:
      case FilterHistory::Kind::kHeldPosition:
      case FilterHistory::Kind::kMove:
        j.push_back(to_json(op.p));
        j.push_back(to_json(op.R));
        break;
      case FilterHistory::Kind::kRemove: break;
    }
    ops.push_back(std::move(j));
  }
  return {{"lagged", save_filter(*h.lagged())}, {"ops", std::move(ops)}};
}

json RobotStateAccess::save_lmap(const LMap& m) {
  json entries = json::array();
  for (int id = 0; id < m.size(); ++id) {
    const LMapEntry& e = m[id];
    if (is_default(e)) continue;
    json j = {{"id", id}, {"status", to_string(e.status)}, {"cov", to_json(e.cov)}};
    for (const auto& f : kEntryInts) j[f.name] = e.*f.field;
    for (const auto& f : kEntryBools) j[f.first] = e.*f.second;
    if (e.archived) j["archived"] = true;  // absent: false (and in files of older builds)
    if (e.checked) j["checked"] = true;    // absent: false (and in older files)
    for (const auto& f : kEntryVecs) j[f.name] = to_json(e.*f.field);
    entries.push_back(std::move(j));
  }
  return entries;
}

json RobotStateAccess::save(const RobotNode& n) {
  const Robot& r = n.robot_;
  const RobotOptions& o = r.options();
  json robot = {{"initialised", r.initialised_},
                {"last_frame", r.last_frame_},
                {"last_odometer", json::array({r.last_odometer_.x, r.last_odometer_.y, r.last_odometer_.theta})},
                {"last_utime", r.last_utime_}};
  // What the robot saw lately of its own trouble (a lost robot: Robot::apply_team_map)
  // and the consistency monitor's window: optional keys (absent in older files: the
  // window starts empty).
  if (r.trouble_frame_ >= 0) robot["trouble_frame"] = r.trouble_frame_;
  json window = json::array();
  for (const auto& [nis, dof] : r.monitor_.window()) window.push_back(json::array({nis, dof}));
  if (!window.empty()) robot["consistency_window"] = std::move(window);
  // The aided filter and what the team channel fused into it (robot.team_map.fuse):
  // optional, absent in older files.
  if (r.filters_.aided_) {
    json channel = json::array();
    for (int id = 0; id < r.team_.max_landmark_id(); ++id)
      if (r.team_.fused_information(id).any())
        channel.push_back({{"id", id},
                           {"epoch", r.team_.epoch(id)},
                           {"Y", to_json(r.team_.fused_information(id))},
                           {"y", to_json(r.team_.fused_vector(id))}});
    robot["aided"] = {{"filter", save_filter(*r.filters_.aided_)}, {"channel", std::move(channel)}};
    if (r.filters_.aided_history_.enabled()) robot["aided"]["history"] = save_history(r.filters_.aided_history_);
  }
  // The filter history (robot.ela.candidate_history_frames): optional, absent in files
  // of older versions (the history then starts over from the filter).
  if (r.filters_.own_history_.enabled()) robot["history"] = save_history(r.filters_.own_history_);
  return {{"robot_id", n.robot_id_},
          {"mode", to_string(o.mode)},
          {"capacity", o.ekf.capacity},
          {"max_landmark_id", o.ekf.max_landmark_id},
          {"incarnation", n.incarnation()},
          {"node", save_node(n)},
          {"robot", robot},
          {"filter", save_filter(r.filters_.own_)},
          {"lmap", save_lmap(r.lmap_)}};
}

// A state from another robot, capacity or mode is not this node's: refused.
void RobotStateAccess::check_header(const json& s, const RobotNode& n) {
  const RobotOptions& o = n.options_;
  const std::int64_t id = whole(need(s, "state", "robot_id"), "state.robot_id", 1, contract::kMaxRobots);
  if (id != n.robot_id_)
    fail("state.robot_id", std::to_string(id) + " is not this robot's (" + std::to_string(n.robot_id_) + ")");
  const json& mode = need(s, "state", "mode");
  if (!mode.is_string() || mode.get<std::string>() != to_string(o.mode))
    fail("state.mode", mode.dump() + " is not the configured mode \"" + to_string(o.mode) + "\"");
  for (const auto& [key, want] : {std::pair<const char*, int>{"capacity", o.ekf.capacity},
                                  std::pair<const char*, int>{"max_landmark_id", o.ekf.max_landmark_id}}) {
    const std::int64_t got = whole(need(s, "state", key), std::string("state.") + key, 0, kMaxFrame);
    if (got != want)
      fail(std::string("state.") + key, std::to_string(got) + " is not the configured " + std::to_string(want));
  }
}

void RobotStateAccess::load_node(const json& s, RobotNode* n) {
  const json& node = need(s, "state", "node");
  n->messages_.incarnation_ = whole(need(s, "state", "incarnation"), "state.incarnation", 0, kMaxIncarnation);
  const int last_frame = static_cast<int>(whole(need(node, "node", "last_frame"), "node.last_frame", -1, kMaxFrame));
  n->admission_.last_frame_ = last_frame;
  n->messages_.seq_ = whole(need(node, "node", "seq"), "node.seq", 0, kMaxCount);
  DeferredInputs& d = n->deferred_;
  const json& counters = need(node, "node", "counters");
  for (const auto& c : kCounters)
    n->counters_.*c.second = whole(need(counters, "node.counters", c.first), std::string("node.counters.") + c.first, 0, kMaxCount);
  // Optional (absent in older files, whose refusals then count from 0):
  // rejected_inputs per reason, which must add up to it.
  if (counters.contains("refused")) {
    const json& by = array(counters.at("refused"), "node.counters.refused", kNumRefusals, kNumRefusals);
    std::int64_t sum = 0;
    for (std::size_t k = 0; k < by.size(); ++k) {
      n->counters_.refused.n[k] = whole(by[k], "node.counters.refused[" + std::to_string(k) + "]", 0, kMaxCount);
      sum += n->counters_.refused.n[k];
    }
    if (sum != n->counters_.rejected_inputs) fail("node.counters.refused", "does not add up to rejected_inputs");
  }
  // A held report's utime and seq, written by older files, are not needed: ignored.
  const json& held = array(need(node, "node", "held_notices"), "node.held_notices", 0, d.held_.capacity());
  for (std::size_t k = 0; k < held.size(); ++k) {
    const std::string w = "node.held_notices[" + std::to_string(k) + "]";
    MovingReport m;
    m.frame = static_cast<int>(whole(need(held[k], w, "frame"), w + ".frame", last_frame + 1.0,
                                     static_cast<double>(last_frame) + n->options_.max_frame_gap));
    m.landmark_id = static_cast<int>(whole(need(held[k], w, "landmark_id"), w + ".landmark_id", 0, n->options_.ekf.max_landmark_id - 1));
    m.detected_by = static_cast<int>(whole(need(held[k], w, "detected_by"), w + ".detected_by", 1, contract::kMaxRobots));
    d.held_.push_back(m);
  }
  const json& had = array(need(node, "node", "notice_frames"), "node.notice_frames", 0, d.report_frame_.size());
  for (std::size_t k = 0; k < had.size(); ++k) {
    const std::string w = "node.notice_frames[" + std::to_string(k) + "]";
    const json& pair = array(had[k], w, 2, 2);
    const auto id = static_cast<std::size_t>(whole(pair[0], w + "[0]", 0, n->options_.ekf.max_landmark_id - 1));
    d.report_frame_[id] = static_cast<int>(whole(pair[1], w + "[1]", 0, kMaxFrame));
  }
  for (const auto& [key, frame] : {std::pair<const char*, int*>{"inconsistent_frame", &n->inconsistent_frame_},
                                   std::pair<const char*, int*>{"full_frame", &n->full_frame_}}) {
    *frame = -1;
    if (node.contains(key))
      *frame = static_cast<int>(whole(node.at(key), std::string("node.") + key, 0, std::max(last_frame, 0)));
  }
  if (n->options_.team_map_fuse && node.contains("team_map")) {
    const json& t = node.at("team_map");
    d.team_map_incarnation_ = whole(need(t, "node.team_map", "incarnation"), "node.team_map.incarnation", 0, kMaxIncarnation);
    d.team_map_version_ = whole(need(t, "node.team_map", "version"), "node.team_map.version", -1, kMaxCount);
    const json& pending = array(need(t, "node.team_map", "pending"), "node.team_map.pending", 0, d.team_pending_.size());
    for (std::size_t k = 0; k < pending.size(); ++k) {
      const std::string w = "node.team_map.pending[" + std::to_string(k) + "]";
      const json& e = pending[k];
      const auto id = static_cast<std::size_t>(whole(need(e, w, "id"), w + ".id", 0, n->options_.ekf.max_landmark_id - 1));
      auto& p = d.team_pending_[id];
      if (p.valid) fail(w + ".id", std::to_string(id) + " appears twice");
      // A team map's estimates are applied after the robot's frame that follows the
      // map's: those held are of this frame or a later one.
      p.frame = static_cast<int>(whole(need(e, w, "frame"), w + ".frame", std::max(last_frame, 0),
                                       std::max(last_frame, 0) + n->options_.max_frame_gap));
      p.position = vec2(need(e, w, "position"), w + ".position", n->options_.limits.world_bound);
      p.cov = cov2(need(e, w, "cov"), w + ".cov", n->options_.limits);
      p.valid = true;
      ++d.team_pending_count_;
    }
  }
}

void RobotStateAccess::load_robot(const json& s, Robot* r, int node_last_frame) {
  const json& robot = need(s, "state", "robot");
  r->initialised_ = boolean(need(robot, "robot", "initialised"), "robot.initialised");
  r->last_frame_ = static_cast<int>(whole(need(robot, "robot", "last_frame"), "robot.last_frame", -1, kMaxFrame));
  if (r->last_frame_ != node_last_frame)
    fail("robot.last_frame", std::to_string(r->last_frame_) + " differs from node.last_frame " + std::to_string(node_last_frame));
  const json& odo = array(need(robot, "robot", "last_odometer"), "robot.last_odometer", 3, 3);
  const double bound = r->options_.limits.world_bound;
  r->last_odometer_.x = real(odo[0], "robot.last_odometer[0]", -bound, bound);
  r->last_odometer_.y = real(odo[1], "robot.last_odometer[1]", -bound, bound);
  r->last_odometer_.theta = real(odo[2], "robot.last_odometer[2]", -kPi - kAngleSlack, kPi + kAngleSlack);
  r->last_utime_ = whole(need(robot, "robot", "last_utime"), "robot.last_utime", -kMaxUtime, kMaxUtime);
  r->trouble_frame_ = -1;
  if (robot.contains("trouble_frame"))
    r->trouble_frame_ = static_cast<int>(whole(robot.at("trouble_frame"), "robot.trouble_frame", -1, r->last_frame_));
  std::vector<std::pair<double, int>> window;
  if (robot.contains("consistency_window")) {
    const json& w = array(robot.at("consistency_window"), "robot.consistency_window", 0,
                          static_cast<std::size_t>(r->monitor_.window_frames()));
    for (std::size_t k = 0; k < w.size(); ++k) {
      const std::string where = "robot.consistency_window[" + std::to_string(k) + "]";
      const json& e = array(w[k], where, 2, 2);
      const double nis = real(e[0], where + "[0] (NIS)", 0.0, kMaxVariance);
      const auto dof = static_cast<int>(whole(e[1], where + "[1] (dof)", 0, 2.0 * r->options_.max_observations));
      if (dof % 2 != 0) fail(where + "[1] (dof)", "odd: 2 per correction");
      window.emplace_back(nis, dof);
    }
  }
  r->monitor_.restore(window);
}

// A filter saved by save_filter under `key` ("filter", or "robot.aided.filter"):
// its slot ids, mean and covariance, each checked.
void RobotStateAccess::parse_filter(const json& f, const std::string& key, const Robot& r, Eigen::VectorXd* x_out,
                                    Eigen::MatrixXd* P_out, std::vector<int>* ids_out) {
  const EkfOptions& o = r.options_.ekf;
  const MessageLimits& lim = r.options_.limits;
  const json& ids = array(need(f, key, "slot_ids"), key + ".slot_ids", 0, static_cast<std::size_t>(o.capacity));
  std::vector<int> slot_ids;
  for (std::size_t k = 0; k < ids.size(); ++k)
    slot_ids.push_back(static_cast<int>(whole(ids[k], key + ".slot_ids[" + std::to_string(k) + "]", 0, o.max_landmark_id - 1)));
  const Eigen::Index dim = StateLayout::dim(static_cast<int>(slot_ids.size()));
  const auto n_mean = static_cast<std::size_t>(dim), n_lower = static_cast<std::size_t>(dim * (dim + 1) / 2);
  const json& mean = array(need(f, key, "mean"), key + ".mean", n_mean, n_mean);
  Eigen::VectorXd x(dim);
  for (Eigen::Index i = 0; i < dim; ++i) {
    double lo = -lim.world_bound, hi = lim.world_bound;  // positions
    if (i == StateLayout::kTheta) lo = -kPi - kAngleSlack, hi = kPi + kAngleSlack;
    if (i == StateLayout::kTurnScale || i == StateLayout::kSpeedScale) lo = kMinScale, hi = kMaxScale;
    if (i == StateLayout::kTurnBias) lo = -kMaxTurnBias, hi = kMaxTurnBias;
    x(i) = real(mean[static_cast<std::size_t>(i)], key + ".mean[" + std::to_string(i) + "]", lo, hi);
  }
  const json& lower = array(need(f, key, "cov_lower"), key + ".cov_lower", n_lower, n_lower);
  Eigen::MatrixXd P(dim, dim);
  std::size_t k = 0;
  for (Eigen::Index i = 0; i < dim; ++i)
    for (Eigen::Index j = 0; j <= i; ++j, ++k) {
      const std::string w = key + ".cov_lower[" + std::to_string(k) + "] (P(" + std::to_string(i) + "," + std::to_string(j) + "))";
      P(i, j) = P(j, i) = real(lower[k], w, -kMaxVariance, kMaxVariance);
      if (i == j && P(i, i) < 0.0) fail(w, "negative variance " + num(P(i, i)));
      if (i == j && P(i, i) > lim.cov_ceiling) fail(w, "variance " + num(P(i, i)) + " above limits.cov_ceiling_m2 " + num(lim.cov_ceiling));
    }
  // Calibration states frozen by this node's configuration: exactly its constants,
  // uncorrelated with anything (a file saved with them estimated is another filter).
  if (!o.calibration.estimated()) {
    const OdometryCalibration& c = o.calibration.prior;
    const Eigen::Vector3d want(c.turn_scale, c.speed_scale, c.turn_bias);
    const auto C = StateLayout::kCalibration, nc = StateLayout::kCalibrationDim;
    if (x.segment(C, nc) != want || !P.middleRows(C, nc).isZero(0.0))
      fail(key + ".mean[" + std::to_string(C) + ".." + std::to_string(C + nc - 1) + "]",
           "the odometer's calibration states differ from robot.odometry_calibration's frozen constants (a file "
           "saved with them estimated)");
  }
  // Each landmark's own 2x2 block: what its snapshot would carry, so the same bounds.
  for (std::size_t slot = 0; slot < slot_ids.size(); ++slot) {
    const Eigen::Index o2 = StateLayout::landmark_offset(static_cast<int>(slot));
    const Eigen::Matrix2d block = P.block<2, 2>(o2, o2);
    if (const std::string bad = check_cov2(block, lim, "covariance"); !bad.empty())
      fail(key + ".cov_lower (landmark " + std::to_string(slot_ids[slot]) + ")", bad);
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(P);
  const double tol = kPsdTolerance * std::max(1.0, P.diagonal().maxCoeff());
  if (ldlt.info() != Eigen::Success || (ldlt.vectorD().array() < -tol).any())
    fail(key + ".cov_lower", "the covariance is not positive semi-definite (smallest LDLT pivot " +
                                 num(ldlt.vectorD().minCoeff()) + ")");
  *x_out = std::move(x);
  *P_out = std::move(P);
  *ids_out = std::move(slot_ids);
}

void RobotStateAccess::load_filter(const json& s, Robot* r) {
  Eigen::VectorXd x;
  Eigen::MatrixXd P;
  std::vector<int> slot_ids;
  parse_filter(need(s, "state", "filter"), "filter", *r, &x, &P, &slot_ids);
  if (r->filters_.own_.restore(x, P, slot_ids) != EkfStatus::kOk) fail("filter.slot_ids", "a landmark id appears twice");
  r->team_.clear();
  if (!r->filters_.aided_) return;  // (a file of a node with robot.team_map.fuse on: its aided filter is left out)
  const json& robot = need(s, "state", "robot");
  if (!robot.contains("aided")) {
    // Absent in older files (or of a node with the team map off):
    // the aided filter restarts as the own filter, the team's information to be
    // fused again from the next team map.
    r->filters_.aided_->restore(x, P, slot_ids);
    return;
  }
  const json& aided = robot.at("aided");
  parse_filter(need(aided, "robot.aided", "filter"), "robot.aided.filter", *r, &x, &P, &slot_ids);
  for (std::size_t k = 0; k < slot_ids.size(); ++k)
    if (!r->filters_.own_.has_landmark(slot_ids[k]))  // the aided filter mirrors the own filter's landmarks
      fail("robot.aided.filter.slot_ids[" + std::to_string(k) + "]",
           "landmark " + std::to_string(slot_ids[k]) + " is not in the own filter");
  if (r->filters_.aided_->restore(x, P, slot_ids) != EkfStatus::kOk) fail("robot.aided.filter.slot_ids", "a landmark id appears twice");
  // The team channel: per landmark, the epoch and the information fused (Y:
  // symmetric, positive semi-definite; y). It outlives the landmark's stay in the
  // aided filter (team_aid.hpp), so any id.
  const json& channel = array(need(aided, "robot.aided", "channel"), "robot.aided.channel", 0,
                              static_cast<std::size_t>(r->options_.ekf.max_landmark_id));
  for (std::size_t k = 0; k < channel.size(); ++k) {
    const std::string w = "robot.aided.channel[" + std::to_string(k) + "]";
    const json& c = channel[k];
    const int id = static_cast<int>(whole(need(c, w, "id"), w + ".id", 0, r->options_.ekf.max_landmark_id - 1));
    if (r->team_.epoch(id) >= 0 || r->team_.fused_information(id).any()) fail(w + ".id", std::to_string(id) + " appears twice");
    const int epoch = static_cast<int>(whole(need(c, w, "epoch"), w + ".epoch", -1, kMaxCount));
    const json& yy = array(need(c, w, "Y"), w + ".Y", 4, 4);
    Eigen::Matrix2d Y;
    for (int i = 0; i < 4; ++i) Y(i / 2, i % 2) = real(yy[static_cast<std::size_t>(i)], w + ".Y[" + std::to_string(i) + "]", -kMaxVariance, kMaxVariance);
    // (Sums of V diag(lambda) V^T: symmetric up to rounding, kept as they were.)
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig;
    eig.computeDirect(0.5 * (Y + Y.transpose()));
    const double scale = std::max(1.0, Y.cwiseAbs().maxCoeff());
    if (std::abs(Y(0, 1) - Y(1, 0)) > kPsdTolerance * scale || eig.eigenvalues()(0) < -kPsdTolerance * scale)
      fail(w + ".Y", "not a symmetric positive semi-definite information matrix");
    const json& yv = array(need(c, w, "y"), w + ".y", 2, 2);
    const Eigen::Vector2d y(real(yv[0], w + ".y[0]", -kMaxVariance, kMaxVariance),
                            real(yv[1], w + ".y[1]", -kMaxVariance, kMaxVariance));
    r->team_.restore(id, epoch, Y, y);
  }
}

// A history saved by save_history under `key`: its lagged filter and its operations,
// each checked; replayed on the lagged filter they must give the saved filter
// `current` (else the file is inconsistent).
void RobotStateAccess::load_history(const json& h, const std::string& key, const EkfSlam& current, const Robot& r,
                                    FilterHistory* out) {
  Eigen::VectorXd x;
  Eigen::MatrixXd P;
  std::vector<int> slot_ids;
  parse_filter(need(h, key, "lagged"), key + ".lagged", r, &x, &P, &slot_ids);
  // Any number (a file saved with a longer window than this node's: the excess goes
  // into the lagged filter), within a structural bound.
  const json& ops = array(need(h, key, "ops"), key + ".ops", 0, kMaxHistoryOps);
  std::vector<FilterHistory::Op> parsed;
  int previous = 0;  // frames in order, none after the robot's last
  for (std::size_t k = 0; k < ops.size(); ++k) {
    parsed.push_back(parse_op(ops[k], key + ".ops[" + std::to_string(k) + "]", previous, r));
    previous = parsed.back().frame;
  }
  if (out->restore(x, P, slot_ids, parsed) != EkfStatus::kOk) fail(key + ".lagged.slot_ids", "a landmark id appears twice");
  check_replay(*out, key, parsed.size(), current, r);
}

// One operation of a saved history, [kind, frame, id, values...], its frame at least
// `first_frame` and at most the robot's last.
FilterHistory::Op RobotStateAccess::parse_op(const json& entry, const std::string& w, int first_frame, const Robot& r) {
  const double bound = r.options_.limits.world_bound;
  const int max_id = r.options_.ekf.max_landmark_id - 1;
  const json& j = array(entry, w, 3, 6);
  FilterHistory::Op op;
  const json& kind = j[0];
  bool known = false;
  for (const auto kd : {FilterHistory::Kind::kPredict, FilterHistory::Kind::kUpdate, FilterHistory::Kind::kLandmarkOnly,
                        FilterHistory::Kind::kPosition, FilterHistory::Kind::kAdd, FilterHistory::Kind::kRemove,
                        FilterHistory::Kind::kHeldPosition, FilterHistory::Kind::kMove})
    if (kind.is_string() && kind.get<std::string>() == FilterHistory::to_string(kd)) op.kind = kd, known = true;
  if (!known) fail(w + "[0] (kind)", kind.dump() + " is not an operation");
  op.frame = static_cast<int>(whole(j[1], w + "[1] (frame)", first_frame, r.last_frame_));
  const bool predict = op.kind == FilterHistory::Kind::kPredict;
  op.id = static_cast<int>(whole(j[2], w + "[2] (id)", predict ? -1 : 0, predict ? -1 : max_id));
  const std::size_t values = predict                                       ? 3
                             : op.kind == FilterHistory::Kind::kPosition || op.kind == FilterHistory::Kind::kHeldPosition ||
                                       op.kind == FilterHistory::Kind::kMove
                                   ? 2
                             : op.kind == FilterHistory::Kind::kRemove   ? 0
                                                                         : 1;
  if (j.size() != 3 + values) fail(w, "has " + std::to_string(j.size()) + " entries, a " + FilterHistory::to_string(op.kind) + " has " + std::to_string(3 + values));
  switch (op.kind) {
    case FilterHistory::Kind::kPredict: {
      const json& u = array(j[3], w + "[3] (increment)", 3, 3);
      op.increment = {real(u[0], w + "[3][0]", -bound, bound), real(u[1], w + "[3][1]", -bound, bound),
                      real(u[2], w + "[3][2]", -kPi - kAngleSlack, kPi + kAngleSlack)};
      const json& U = array(j[4], w + "[4] (U)", 9, 9);
      for (int e = 0; e < 9; ++e)
        op.U(e / 3, e % 3) = real(U[static_cast<std::size_t>(e)], w + "[4][" + std::to_string(e) + "]", -kMaxVariance, kMaxVariance);
      const double scale = std::max(op.U.trace(), 1e-300);
      if ((op.U.diagonal().array() < 0.0).any()) fail(w + "[4] (U)", "negative variance");
      if ((op.U - op.U.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) fail(w + "[4] (U)", "not symmetric");
      op.dt = real(j[5], w + "[5] (dt)", 0.0, kMaxStepSeconds);
      break;
    }
    case FilterHistory::Kind::kUpdate:
    case FilterHistory::Kind::kLandmarkOnly:
    case FilterHistory::Kind::kAdd: {
      const json& z = array(j[3], w + "[3] (range, bearing)", 2, 2);
      op.z = {real(z[0], w + "[3][0] (range)", 1e-9, bound), real(z[1], w + "[3][1] (bearing)", -kPi - kAngleSlack, kPi + kAngleSlack)};
      break;
    }
    case FilterHistory::Kind::kPosition:
    case FilterHistory::Kind::kHeldPosition: {
      op.p = vec2(j[3], w + "[3] (position)", bound);
      const json& R = array(j[4], w + "[4] (R)", 4, 4);
      for (int e = 0; e < 4; ++e)
        op.R(e / 2, e % 2) = real(R[static_cast<std::size_t>(e)], w + "[4][" + std::to_string(e) + "]", -kMaxVariance, kMaxVariance);
      if (!(op.R(0, 0) > 0.0) || !(op.R.determinant() > 0.0) || std::fabs(op.R(0, 1) - op.R(1, 0)) > 1e-9 * op.R.trace())
        fail(w + "[4] (R)", "not symmetric positive definite");
      break;
    }
    case FilterHistory::Kind::kMove:
      op.p = vec2(j[3], w + "[3] (displacement)", bound);
      op.R = psd2(j[4], w + "[4] (Q)");  // a process noise: no floor, unlike a covariance
      break;
    case FilterHistory::Kind::kRemove: break;
  }
  return op;
}

// The lagged filter and the operations held must give the saved filter (restore has
// put those beyond the ring into the lagged filter already); `parsed`: the
// operations the file listed.
void RobotStateAccess::check_replay(const FilterHistory& h, const std::string& key, std::size_t parsed,
                                    const EkfSlam& current, const Robot& r) {
  EkfSlam replay(r.options_.ekf);
  replay.assign(*h.lagged());
  const std::size_t first_held = parsed - static_cast<std::size_t>(h.held());
  for (int k = 0; k < h.held(); ++k)
    if (!FilterHistory::apply(h.op(k), &replay))
      fail(key + ".ops[" + std::to_string(first_held + static_cast<std::size_t>(k)) + "]", "the lagged filter refuses it");
  bool same = replay.num_landmarks() == current.num_landmarks();
  for (int slot = 0; same && slot < current.num_landmarks(); ++slot) same = replay.id_at(slot) == current.id_at(slot);
  if (same) {
    const double scale = std::max(1.0, current.covariance().cwiseAbs().maxCoeff());
    same = (replay.mean() - current.mean()).cwiseAbs().maxCoeff() <= 1e-6 * std::max(1.0, current.mean().cwiseAbs().maxCoeff()) &&
           (replay.covariance() - current.covariance()).cwiseAbs().maxCoeff() <= 1e-6 * scale;
  }
  if (!same) fail(key, "its lagged filter and operations do not give the saved filter");
}

void RobotStateAccess::load_histories(const json& s, Robot* r) {
  r->filters_.restart_history();
  const json& robot = need(s, "state", "robot");
  if (r->filters_.own_history_.enabled() && robot.contains("history"))
    load_history(robot.at("history"), "robot.history", r->filters_.own_, *r, &r->filters_.own_history_);
  if (r->filters_.aided_ && r->filters_.aided_history_.enabled() && robot.contains("aided") && robot.at("aided").contains("history"))
    load_history(robot.at("aided").at("history"), "robot.aided.history", *r->filters_.aided_, *r, &r->filters_.aided_history_);
}

void RobotStateAccess::load_lmap(const json& s, Robot* r) {
  const json& entries = array(need(s, "state", "lmap"), "lmap", 0, static_cast<std::size_t>(r->lmap_.size()));
  std::vector<std::uint8_t> seen(static_cast<std::size_t>(r->lmap_.size()), 0);
  for (std::size_t k = 0; k < entries.size(); ++k) {
    const std::string w = "lmap[" + std::to_string(k) + "]";
    const json& j = entries[k];
    const int id = static_cast<int>(whole(need(j, w, "id"), w + ".id", 0, r->lmap_.size() - 1));
    if (seen[static_cast<std::size_t>(id)]++) fail(w + ".id", std::to_string(id) + " appears twice");
    LMapEntry e;
    e.status = parse_status(need(j, w, "status"), w + ".status");
    e.cov = cov2(need(j, w, "cov"), w + ".cov", r->options_.limits);
    for (const auto& f : kEntryInts) e.*f.field = static_cast<int>(whole(need(j, w, f.name), w + "." + f.name, f.lo, kMaxFrame));
    for (const auto& f : kEntryBools) e.*f.second = boolean(need(j, w, f.first), w + "." + f.first);
    if (j.contains("archived")) e.archived = boolean(j["archived"], w + ".archived");
    if (j.contains("checked")) e.checked = boolean(j["checked"], w + ".checked");
    for (const auto& f : kEntryVecs)
      e.*f.field = vec2(need(j, w, f.name), w + "." + f.name, f.bound > 0.0 ? f.bound : r->options_.limits.world_bound);
    r->lmap_.restore(id, e);
  }
}

// The filter holds exactly the STATIC landmarks that are not archived and (some)
// candidates: what Robot keeps true.
void RobotStateAccess::check_consistency(const Robot& r) {
  for (int slot = 0; slot < r.filters_.own_.num_landmarks(); ++slot) {
    const int id = r.filters_.own_.id_at(slot);
    const LandmarkStatus st = r.lmap_[id].status;
    if (st != LandmarkStatus::kStatic && st != LandmarkStatus::kCandidate)
      fail("filter.slot_ids[" + std::to_string(slot) + "]",
           "landmark " + std::to_string(id) + " is in the filter but " + to_string(st) + " in the L-map");
  }
  for (int id = 0; id < r.lmap_.size(); ++id) {
    const LMapEntry& e = r.lmap_[id];
    if (e.archived && (e.status != LandmarkStatus::kStatic || r.filters_.own_.has_landmark(id)))
      fail("lmap", "landmark " + std::to_string(id) + " is archived but " +
                       (r.filters_.own_.has_landmark(id) ? std::string("in the filter") : "not static"));
    if (e.status == LandmarkStatus::kStatic && !e.archived && !r.filters_.own_.has_landmark(id))
      fail("lmap", "landmark " + std::to_string(id) + " is static but neither in the filter nor archived");
  }
}

void RobotStateAccess::load(const json& s, RobotNode* scratch) {
  check_header(s, *scratch);
  load_node(s, scratch);
  load_robot(s, &scratch->robot_, scratch->last_frame());
  load_filter(s, &scratch->robot_);
  load_histories(s, &scratch->robot_);
  load_lmap(s, &scratch->robot_);
  check_consistency(scratch->robot_);
}

std::string robot_state_checksum(const std::string& state_dump) {
  std::uint64_t h = 14695981039346656037ull;  // FNV-1a 64
  for (unsigned char c : state_dump) {
    h ^= c;
    h *= 1099511628211ull;
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

std::string save_robot_state(const RobotNode& node, std::uint64_t mission) {
  const std::string state = RobotStateAccess::save(node).dump();
  // The state is dumped once and spliced in, so the checksum covers exactly these bytes' values.
  json head = {{"format", kRobotStateFormat}, {"version", kRobotStateVersion}, {"fnv1a64", robot_state_checksum(state)}};
  if (mission != 0) {
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(mission));
    head["mission"] = hex;
  }
  std::string text = head.dump();
  text.pop_back();  // '}'
  return text + ",\"state\":" + state + "}\n";
}

bool load_robot_state(const std::string& text, RobotNode* node, std::string* why, std::uint64_t mission) {
  try {
    const json doc = json::parse(text);
    if (mission != 0) {  // with the team's keys: only a state of this mission
      char hex[17];
      std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(mission));
      const auto m = doc.find("mission");
      if (m == doc.end() || !m->is_string() || m->get<std::string>() != hex)
        fail("mission", (m == doc.end() ? std::string("none") : m->dump()) + " is not this mission's \"" + hex +
                            "\" (a state of another mission: a new mission starts fresh)");
    }
    const json& format = need(doc, "file", "format");
    if (!format.is_string() || format.get<std::string>() != kRobotStateFormat)
      fail("format", format.dump() + " is not \"" + kRobotStateFormat + "\" (not a robot state file)");
    const std::int64_t version = whole(need(doc, "file", "version"), "version", 0, 1e9);
    if (version != kRobotStateVersion)
      fail("version", std::to_string(version) + " is not the supported " + std::to_string(kRobotStateVersion));
    const json& state = need(doc, "file", "state");
    const json& sum = need(doc, "file", "fnv1a64");
    if (!sum.is_string() || sum.get<std::string>() != robot_state_checksum(state.dump()))
      fail("fnv1a64", "checksum mismatch: the file was altered or damaged");
    RobotNode scratch(node->robot().options(), node->robot_id());
    RobotStateAccess::load(state, &scratch);
    *node = std::move(scratch);
    return true;
  } catch (const json::parse_error& e) {
    if (why) *why = std::string("not valid JSON (truncated or damaged?): ") + e.what();
  } catch (const std::exception& e) {
    if (why) *why = e.what();
  }
  return false;
}

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
#include "elaslam/main_robot/map_state.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

#include <nlohmann/json.hpp>

#include "elaslam/common/atomic_file.hpp"
#include "elaslam/common/contract.hpp"

namespace elaslam {

// ---- the body: GlobalMap's JSON document -----------------------------------------

std::string GlobalMap::to_json() const {
  using nlohmann::json;
  json j;
  j["format"] = "elaslam.global_map.v1";  // the body's schema (the file's format and version: the seal's header)
  j["version"] = version_;
  j["newest_frame"] = newest_frame_;
  j["max_landmark_id"] = max_landmark_id();
  json streams = json::array();
  for (const auto& s : streams_) {
    json st = {{"last_seq", s.last_seq}, {"last_frame", s.last_frame},
               {"snapshot_seq", s.snapshot_seq}, {"snapshot_frame", s.snapshot_frame}};
    if (s.incarnation != 0) st["incarnation"] = s.incarnation;  // 0: none seen yet
    if (s.gap_pending) st["repair_seq"] = s.repair_seq;  // a gap not repaired yet: repaired after a restart too
    streams.push_back(std::move(st));
  }
  j["robots"] = streams;
  json lms = json::array();
  for (int id = 0; id < max_landmark_id(); ++id) {
    const GlobalEntry& g = entries_[static_cast<std::size_t>(id)];
    if (g.status == GlobalStatus::kAbsent) continue;
    json est = json::array();
    for (int r = 0; r < kMaxTeamRobots; ++r) {
      const RobotEstimate& e = g.by_robot[static_cast<std::size_t>(r)];
      if (!e.valid) continue;
      est.push_back({{"robot", r + 1}, {"frame", e.frame}, {"x", e.position.x()}, {"y", e.position.y()},
                     {"cov", {e.cov(0, 0), e.cov(0, 1), e.cov(1, 0), e.cov(1, 1)}}});
    }
    json l = {{"id", id}, {"status", static_cast<int>(g.status)}, {"status_frame", g.status_frame},
              {"moving_by", g.moving_by}, {"estimates", est}};
    // The fused estimate of a static landmark: the one it keeps when no robot holds
    // it any more (a robot that restarted fresh dropped it from its snapshots).
    if (g.status == GlobalStatus::kStatic)
      l["fused"] = {{"x", g.fused.x()}, {"y", g.fused.y()},
                    {"cov", {g.fused_cov(0, 0), g.fused_cov(0, 1), g.fused_cov(1, 0), g.fused_cov(1, 1)}}};
    if (g.moving_unconfirmed) l["moving_unconfirmed"] = true;
    if (g.history_unknown) l["history_unknown"] = true;
    lms.push_back(std::move(l));
  }
  j["landmarks"] = lms;
  return j.dump(1);
}

namespace {

using nlohmann::json;

constexpr std::int64_t kIntMax = std::numeric_limits<int>::max();
constexpr std::int64_t kInt64Max = std::numeric_limits<std::int64_t>::max();

[[noreturn]] void refuse(const std::string& what) { throw std::runtime_error(what); }

// An integer field within [lo, hi] (a float, a huge value or a string is refused:
// nlohmann's get<int> would convert or wrap silently).
std::int64_t integer(const json& o, const char* key, std::int64_t lo, std::int64_t hi) {
  const json& v = o.at(key);
  if (!v.is_number_integer() || (v.is_number_unsigned() && v.get<std::uint64_t>() > static_cast<std::uint64_t>(hi)))
    refuse(std::string(key) + " is not an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "] (got " + v.dump() + ")");
  const std::int64_t x = v.get<std::int64_t>();
  if (x < lo || x > hi)
    refuse(contract::got(std::string(key) + " not in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]", x));
  return x;
}

// A frame: [0, INT32_MAX]; with `none`, also -1 ("none yet").
int frame(const json& o, const char* key, bool none = false) { return static_cast<int>(integer(o, key, none ? -1 : 0, kIntMax)); }

const json& array_at(const json& o, const char* key) {
  const json& v = o.at(key);
  if (!v.is_array()) refuse(std::string(key) + " is not an array");
  return v;
}

// A 2x2 covariance saved as 4 numbers, row by row, under "cov" (checked by the caller).
Eigen::Matrix2d cov2(const json& o, const char* what) {
  const auto c = o.at("cov").get<std::vector<double>>();
  if (c.size() != 4) refuse(std::string(what) + ": expected 4 numbers");
  Eigen::Matrix2d C;
  C << c[0], c[1], c[2], c[3];
  return C;
}

// One robot's record: its stream as the file has it (message bounds; the file's own:
// map_state_out_of_bounds). Keys that older files lack are optional.
void parse_robot(const json& r, RobotStream* s) {
  s->last_seq = integer(r, "last_seq", 0, kMaxSeq);
  s->last_frame = frame(r, "last_frame", /*none=*/true);
  s->incarnation_frame = s->last_frame;  // its events' (POSEs' not kept)
  if (r.contains("incarnation")) s->incarnation = integer(r, "incarnation", 1, kInt64Max);  // absent: none seen
  if (r.contains("snapshot_seq")) {
    s->snapshot_seq = integer(r, "snapshot_seq", 0, kMaxSeq);
    s->snapshot_frame = frame(r, "snapshot_frame", /*none=*/true);
  }
  // A pending gap repair starts over: every id must be covered again by a chunk as new as repair_seq.
  if (r.contains("repair_seq")) s->restart_repair(integer(r, "repair_seq", 0, kMaxSeq));
}

// A position and covariance checked as a message's.
void check_estimate(const Eigen::Vector2d& p, const Eigen::Matrix2d& C, const MessageLimits& lim,
                    const std::string& where, const char* position, const char* cov) {
  std::string bad = check_position(p.x(), p.y(), lim, position);
  if (bad.empty()) bad = check_cov2(C, lim, cov);
  if (!bad.empty()) refuse(where + ": " + bad);
}

// Landmark `id`'s record but its fused estimate: status, robots' estimates, flags.
void parse_landmark(const json& l, int id, const MessageLimits& lim, GlobalEntry* g) {
  const std::string where = "landmark " + std::to_string(id);
  const int status = static_cast<int>(integer(l, "status", 0, 100));
  if (status < 1 || status > 2) refuse(where + ": status " + std::to_string(status));
  g->status = static_cast<GlobalStatus>(status);
  g->status_frame = frame(l, "status_frame");
  g->moving_by = static_cast<int>(integer(l, "moving_by", 0, kMaxTeamRobots));
  for (const json& e : array_at(l, "estimates")) {
    const int r = static_cast<int>(integer(e, "robot", 0, 100));
    if (r < 1 || r > kMaxTeamRobots) refuse(where + ": estimate robot " + std::to_string(r));
    const std::string by = where + " robot " + std::to_string(r);
    if (!lim.in_team(r)) refuse(by + ": robot not in limits.team " + team_text(lim.team_mask));
    RobotEstimate& est = g->by_robot[static_cast<std::size_t>(r - 1)];
    if (est.valid) refuse(by + ": listed twice (refused, not merged)");
    est.valid = true;
    est.frame = frame(e, "frame");
    est.position = {e.at("x").get<double>(), e.at("y").get<double>()};
    est.cov = cov2(e, "cov");
    check_estimate(est.position, est.cov, lim, by, "position", "cov");
  }
  // Optional (older files lack them).
  const auto flag = [&](const char* key) {
    if (!l.contains(key)) return false;
    if (!l.at(key).is_boolean()) refuse(where + ": " + key + " is not a boolean");
    return l.at(key).get<bool>();
  };
  g->moving_unconfirmed = g->status == GlobalStatus::kMoving && flag("moving_unconfirmed");
  g->history_unknown = flag("history_unknown");
}

}  // namespace

bool GlobalMap::from_json(std::string_view text, std::string* why) {
  GlobalMap loaded(options_);
  try {
    const json j = json::parse(text.begin(), text.end());
    if (!j.is_object() || j.at("format") != "elaslam.global_map.v1") refuse("unknown format");
    loaded.version_ = integer(j, "version", 0, kMaxSeq);
    loaded.newest_frame_ = frame(j, "newest_frame", /*none=*/true);
    const json& rs = array_at(j, "robots");
    // One entry per robot id 1..kMaxTeamRobots; a file of a build with fewer robot
    // ids (an older build had 8) holds fewer, and the rest start fresh.
    if (rs.empty() || rs.size() > static_cast<std::size_t>(kMaxTeamRobots))
      refuse("robots: expected 1 to " + std::to_string(kMaxTeamRobots) + " entries");
    for (std::size_t r = 0; r < rs.size(); ++r) {
      try {
        parse_robot(rs[r], &loaded.streams_[r]);
      } catch (const std::exception& e) {
        refuse("robots[" + std::to_string(r) + "]." + e.what());
      }
    }
    std::vector<std::uint8_t> seen(entries_.size(), 0);
    for (const json& l : array_at(j, "landmarks")) {
      const int id = static_cast<int>(integer(l, "id", -1, kIntMax));
      if (id < 0 || id >= max_landmark_id()) refuse("landmark id " + std::to_string(id) + " out of range");
      if (seen[static_cast<std::size_t>(id)]++) refuse("landmark id " + std::to_string(id) + " listed twice (refused, not merged)");
      GlobalEntry& g = loaded.entries_[static_cast<std::size_t>(id)];
      parse_landmark(l, id, options_.limits, &g);
      // A static landmark no robot holds comes back at its saved fused estimate, or not at all.
      if (g.status != GlobalStatus::kStatic || loaded.fuse(g)) continue;
      if (!l.contains("fused")) {
        g = GlobalEntry{};  // no estimate and no position: as if never mapped
        continue;
      }
      const json& f = l.at("fused");
      g.fused = {f.at("x").get<double>(), f.at("y").get<double>()};
      g.fused_cov = cov2(f, "fused cov");
      check_estimate(g.fused, g.fused_cov, options_.limits, "landmark " + std::to_string(id), "fused position", "fused cov");
    }
  } catch (const std::exception& ex) {
    if (why) *why = ex.what();
    return false;
  }
  *this = std::move(loaded);
  return true;
}

// ---- the file ----------------------------------------------------------------------

std::size_t max_map_state_bytes(const GlobalMapOptions& o) {
  return static_cast<std::size_t>(o.max_landmark_id) * kMaxLandmarkRecordBytes +
         static_cast<std::size_t>(kMaxTeamRobots) * kMaxRobotRecordBytes + kMaxMapStateFixedBytes +
         sealed_state_overhead(kMapStateFormat);
}

std::string map_state_out_of_bounds(const GlobalMap& map) {
  const auto beyond = [](int r, const char* field, std::int64_t v, const char* bound) {
    return "robot " + std::to_string(r) + "'s " + field + " " + std::to_string(v) + " is beyond " + bound;
  };
  for (int r = 1; r <= kMaxTeamRobots; ++r) {
    const RobotStream& s = map.stream(r);
    if (s.last_seq > kMaxStateSeq) return beyond(r, "seq", s.last_seq, "2^40");
    if (s.snapshot_seq > kMaxStateSeq) return beyond(r, "snapshot seq", s.snapshot_seq, "2^40");
    if (s.gap_pending && s.repair_seq > kMaxStateSeq) return beyond(r, "repair seq", s.repair_seq, "2^40");
    if (s.incarnation > kMaxStateIncarnation) return beyond(r, "incarnation", s.incarnation, "2^62");
  }
  return "";
}

bool seal_map_state(const GlobalMap& map, const StateKey* key, std::string* text, std::string* why) {
  if (std::string bad = map_state_out_of_bounds(map); !bad.empty()) {
    if (why) *why = bad + " (docs/security.md, main_robot's state file): a file the loader would refuse is not written";
    return false;
  }
  std::string sealed = seal_state(kMapStateFormat, kMapStateVersion, map.to_json(), key);
  if (const std::size_t bound = max_map_state_bytes(map.options()); sealed.size() > bound) {
    if (why) *why = "the state is " + std::to_string(sealed.size()) + " bytes, beyond the " + std::to_string(bound) +
                    " the loader accepts (kMaxLandmarkRecordBytes too small: a bug)";
    return false;
  }
  *text = std::move(sealed);
  return true;
}

bool open_map_state(std::string_view text, const StateKey* key, GlobalMap* map, std::string* why) {
  std::string_view body;
  if (!open_state(text, kMapStateFormat, kMapStateVersion, key, &body, why)) return false;
  GlobalMap loaded(map->options());
  if (!loaded.from_json(body, why)) return false;
  if (std::string bad = map_state_out_of_bounds(loaded); !bad.empty()) {
    if (why) *why = bad;
    return false;
  }
  *map = std::move(loaded);
  return true;
}

bool save_map_state(const std::string& path, const GlobalMap& map, const StateKey* key, std::string* why) {
  std::string text;
  return seal_map_state(map, key, &text, why) && files::write_atomic(path, text, why);
}

const char* to_string(MapStateOutcome o) {
  switch (o) {
    case MapStateOutcome::kResumed: return "resumed";
    case MapStateOutcome::kMissing: return "missing";
    case MapStateOutcome::kFreshAfterDamage: return "fresh_after_damage";
  }
  return "?";
}

namespace {

// The refused file out of the way, kept for a post-mortem. rename(2) replaces an
// existing PATH.corrupt atomically and never follows a symbolic link at either name.
void move_aside(const std::string& path, MapStateLoad* r) {
  const std::string aside = path + ".corrupt";
  if (std::rename(path.c_str(), aside.c_str()) == 0) {
    r->aside = aside;
    r->line += "; moved aside to " + aside + ", starting with an empty map";
    return;
  }
  r->why_kept = "cannot rename it to " + aside + ": " + std::strerror(errno);
  r->line += "; " + r->why_kept + " (the next save replaces it), starting with an empty map";
}

}  // namespace

MapStateLoad load_map_state(const std::string& path, const StateKey* key, GlobalMap* map) {
  MapStateLoad r;
  std::string text;
  bool missing = false;
  const std::size_t bound = max_map_state_bytes(map->options());
  if (!files::read_all(path, &text, &r.why, &missing, bound)) {
    if (missing) {
      r.why.clear();
      r.line = "no state file " + path + " yet: starting with an empty map";
      return r;
    }
  } else if (open_map_state(text, key, map, &r.why)) {
    r.outcome = MapStateOutcome::kResumed;
    r.line = "resumed from " + path + " (version " + std::to_string(map->version()) + ", " +
             std::to_string(map->count(GlobalStatus::kStatic)) + " static, " +
             std::to_string(map->count(GlobalStatus::kMoving)) + " moving" + (key ? ", keyed" : "") + ")";
    return r;
  }
  r.outcome = MapStateOutcome::kFreshAfterDamage;
  r.line = "state file " + path + " refused: " + r.why;
  move_aside(path, &r);
  return r;
}

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
#include "elaslam/common/limits.hpp"

#include <Eigen/LU>

#include <cmath>
#include <numeric>
#include <sstream>

#include "elaslam/common/config.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/common/cov.hpp"

#include <yaml-cpp/yaml.h>

namespace elaslam {

static_assert(MessageLimits::kRobotIds == contract::kMaxRobots, "limits.team's ids are the messages' robot ids");

const char* to_string(Refusal r) {
  switch (r) {
    case Refusal::kMalformed: return "malformed";
    case Refusal::kImplausible: return "implausible";
    case Refusal::kOutsideTeam: return "outside_team";
    case Refusal::kSeqWindow: return "seq_window";
    case Refusal::kFrameWindow: return "frame_window";
    case Refusal::kStale: return "stale";
    case Refusal::kDuplicateId: return "duplicate_id";
    case Refusal::kOdometry: return "odometry";
  }
  return "?";
}

std::int64_t RefusalCounts::total() const { return std::accumulate(n.begin(), n.end(), std::int64_t{0}); }

bool RefusalCounts::count(Refusal r, const std::string& problem, std::int64_t* rejected, std::string* why) {
  add(r);
  ++*rejected;
  if (why) *why = problem;
  return false;
}

bool parse_team(const std::string& text, int* mask, std::string* why) {
  int bits = 0;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const auto b = item.find_first_not_of(" \t"), e = item.find_last_not_of(" \t");
    const std::string t = b == std::string::npos ? "" : item.substr(b, e - b + 1);
    const bool digits = !t.empty() && t.size() <= 2 && t.find_first_not_of("0123456789") == std::string::npos && t[0] != '0';
    const int id = digits ? std::stoi(t) : 0;
    if (id < 1 || id > contract::kMaxRobots) {
      *why = "'" + t + "' is not a robot id in [1, " + std::to_string(contract::kMaxRobots) + "]";
      return false;
    }
    const int bit = 1 << (id - 1);
    if (bits & bit) {
      *why = "robot " + t + " given twice";
      return false;
    }
    bits |= bit;
  }
  if (bits == 0) {
    *why = "no robots given (expected e.g. 1,2,3)";
    return false;
  }
  *mask = bits;
  return true;
}

std::string team_text(int mask) {
  std::string s;
  for (int r = 1; r <= contract::kMaxRobots; ++r)
    if ((mask >> (r - 1)) & 1) s += (s.empty() ? "" : ",") + std::to_string(r);
  return s;
}

void parse(config::Reader& r, MessageLimits* o) {
  r.section(
      "limits",
      [&](config::Reader& l) {
        l.read_optional("world_bound_m", &o->world_bound, 1.0, 1e7);
        l.read_optional("cov_floor_m2", &o->cov_floor, 1e-30, 1.0);
        l.read_optional("cov_ceiling_m2", &o->cov_ceiling, 1e-6, 1e12);
        std::string team = team_text(o->team_mask);
        l.read_optional("team", &team);
        std::string why;
        if (!parse_team(team, &o->team_mask, &why)) l.fail("team", why);
        if (o->cov_floor >= o->cov_ceiling) l.fail("cov_floor_m2", "must be smaller than cov_ceiling_m2");
      },
      /*optional=*/true);
}

std::vector<std::string> check_shared_config(const std::string& path) {
  std::vector<std::string> problems;
  try {
    const YAML::Node root = YAML::LoadFile(path);
    const YAML::Node robot = root["robot"], main = root["main"];
    if (!robot || !main) return problems;
    const YAML::Node rid = robot["filter"] ? robot["filter"]["max_landmark_id"] : YAML::Node();
    const YAML::Node mid = main["max_landmark_id"];
    if (rid && mid && rid.IsScalar() && mid.IsScalar() && mid.as<long long>() < rid.as<long long>())
      problems.push_back("main.max_landmark_id (" + mid.as<std::string>() + ") is smaller than robot.filter.max_landmark_id (" +
                         rid.as<std::string>() + "): main_robot would refuse every event about the ids between");
    // The simulator's fullest frame must fit the robots' (a section may leave either
    // out: contract::kMaxObsPerFrame).
    const YAML::Node scenario = root["scenario"];
    const YAML::Node sim_obs = scenario && scenario["sensor"] ? scenario["sensor"]["max_observations"] : YAML::Node();
    const YAML::Node rob_obs = robot["filter"] ? robot["filter"]["max_observations"] : YAML::Node();
    const auto count = [](const YAML::Node& n) {
      return n && n.IsScalar() ? n.as<long long>() : static_cast<long long>(contract::kMaxObsPerFrame);
    };
    if ((sim_obs || rob_obs) && count(sim_obs) > count(rob_obs))
      problems.push_back("scenario.sensor.max_observations (" + std::to_string(count(sim_obs)) +
                         ") exceeds robot.filter.max_observations (" + std::to_string(count(rob_obs)) +
                         "): the robots would refuse the simulator's fullest frames");
    const auto team = [](const YAML::Node& section) {
      int mask = MessageLimits::kAllRobots;
      std::string why;
      if (section["limits"] && section["limits"]["team"]) parse_team(section["limits"]["team"].as<std::string>(), &mask, &why);
      return mask;
    };
    const YAML::Node fuse = robot["team_map"] ? robot["team_map"]["fuse"] : YAML::Node();
    const YAML::Node period = main["team_map_period_frames"];
    if (fuse && fuse.IsScalar() && fuse.as<std::string>() == "true" &&
        !(period && period.IsScalar() && period.as<long long>() > 0))
      problems.push_back("robot.team_map.fuse is on but main.team_map_period_frames is " +
                         (period && period.IsScalar() ? period.as<std::string>() : std::string("absent (0)")) +
                         ": main_robot would never send the robots the team map");
    if (team(robot) != team(main))
      problems.push_back("robot.limits.team (" + team_text(team(robot)) + ") and main.limits.team (" + team_text(team(main)) +
                         ") differ: one side would refuse the other's robots");
  } catch (const std::exception&) {
    // Unreadable or malformed: the section parse reports it with its line.
  }
  return problems;
}

namespace {

std::string num(double v) {
  std::ostringstream os;
  os.precision(17);
  os << v;
  return os.str();
}

}  // namespace

std::string check_position(double x, double y, const MessageLimits& l, const char* field) {
  if (!std::isfinite(x) || !std::isfinite(y)) return std::string(field) + " is not finite (got " + num(x) + ", " + num(y) + ")";
  if (std::fabs(x) > l.world_bound || std::fabs(y) > l.world_bound)
    return std::string(field) + " beyond limits.world_bound_m " + num(l.world_bound) + " m (got " + num(x) + ", " + num(y) + ")";
  return "";
}

std::string check_cov2(const Eigen::Matrix2d& c, const MessageLimits& l, const char* field) {
  if (!c.allFinite()) return std::string(field) + " is not finite";
  const double a = c(0, 0), d = c(1, 1), b = 0.5 * (c(0, 1) + c(1, 0));
  const double scale = std::max(std::fabs(a), std::fabs(d));
  if (std::fabs(c(0, 1) - c(1, 0)) > 1e-6 * scale + 1e-300)
    return std::string(field) + " is not symmetric (got " + num(c(0, 1)) + " and " + num(c(1, 0)) + ")";
  // Eigenvalues of the symmetric 2x2 [a b; b d].
  const double mean = 0.5 * (a + d), r = std::hypot(0.5 * (a - d), b);
  const double lo = mean - r, hi = mean + r;
  if (!(lo >= l.cov_floor))
    return std::string(field) + " has an eigenvalue below limits.cov_floor_m2 " + num(l.cov_floor) + " m^2 (got " + num(lo) +
           "): not positive definite or absurdly certain";
  if (!(hi <= l.cov_ceiling))
    return std::string(field) + " has an eigenvalue above limits.cov_ceiling_m2 " + num(l.cov_ceiling) + " m^2 (got " + num(hi) + ")";
  return "";
}

std::string check_cov2(const double (&c)[2][2], const MessageLimits& l, const char* field) {
  return check_cov2(read_cov(c), l, field);
}

std::string check_pose(const pose_estimate_t& p, const MessageLimits& l, Refusal* reason) {
  *reason = Refusal::kMalformed;
  if (p.frame < 0) return contract::got("frame is negative", p.frame);
  if (p.incarnation < 0) return contract::got("incarnation is negative", p.incarnation);
  if (!std::isfinite(p.nis) || p.nis < 0.0) return "nis is negative or not finite (got " + num(p.nis) + ")";
  if (p.nis_dof < 0 || p.nis_dof > 2 * contract::kMaxObsPerFrameLimit || p.nis_dof % 2 != 0)
    return contract::got("nis_dof is not an even number in [0, 2 x " + std::to_string(contract::kMaxObsPerFrameLimit) + "]",
                         p.nis_dof);
  *reason = Refusal::kImplausible;
  if (std::string e = check_position(p.x, p.y, l, "position"); !e.empty()) return e;
  if (!std::isfinite(p.theta)) return "theta is not finite";
  return check_pose_cov(p.cov, l, "cov");
}

std::string check_global_map(const global_map_t& m, const MessageLimits& l, int max_moving_id, Refusal* reason) {
  *reason = Refusal::kMalformed;
  if (m.num_moving < 0 || !contract::count_fits(m.moving_ids, m.num_moving) ||
      !contract::count_fits(m.moving_frames, m.num_moving) || !contract::count_fits(m.moving_by, m.num_moving))
    return contract::got("num_moving does not match the moving arrays", m.num_moving);
  if (!contract::count_fits(m.landmarks, m.num_landmarks)) return contract::got("num_landmarks does not match the array", m.num_landmarks);
  if (m.frame < -1) return contract::got("frame below -1", m.frame);
  int previous = -1;
  for (int k = 0; k < m.num_landmarks; ++k) {
    const global_landmark_t& g = m.landmarks[static_cast<std::size_t>(k)];
    *reason = Refusal::kMalformed;
    if (g.id < 0) return contract::got("landmark id is negative", g.id);
    if (g.id == previous) return *reason = Refusal::kDuplicateId, contract::got("landmark id listed twice", g.id);
    if (g.id < previous) return contract::got("landmark ids not ascending, id", g.id);
    previous = g.id;
    *reason = Refusal::kImplausible;
    if (std::string p = check_position(g.x, g.y, l, "position"); !p.empty()) return "landmark " + std::to_string(g.id) + " " + p;
    if (std::string p = check_cov2(g.cov, l, "cov"); !p.empty()) return "landmark " + std::to_string(g.id) + " " + p;
  }
  previous = -1;
  for (int k = 0; k < m.num_moving; ++k) {
    const auto i = static_cast<std::size_t>(k);
    const int id = m.moving_ids[i], by = m.moving_by[i];
    *reason = Refusal::kMalformed;
    if (id < 0 || id >= max_moving_id) return contract::got("moving id outside [0, max_landmark_id)", id);
    if (id == previous) return *reason = Refusal::kDuplicateId, contract::got("moving id listed twice", id);
    if (id < previous) return contract::got("moving ids not ascending, id", id);
    previous = id;
    if (by < 0 || by > contract::kMaxRobots) return contract::got(contract::outside("moving_by", 0, contract::kMaxRobots), by);
    if (by > 0 && !l.in_team(by))
      return *reason = Refusal::kOutsideTeam, contract::got("moving_by not in limits.team " + team_text(l.team_mask), by);
    if (m.moving_frames[i] < 0) return contract::got("moving frame is negative", m.moving_frames[i]);
  }
  return "";
}

std::string check_pose_cov(const double (&c)[3][3], const MessageLimits& l, const char* field) {
  Eigen::Matrix3d m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m(i, j) = c[i][j];
  if (!m.allFinite()) return std::string(field) + " is not finite";
  const double scale = m.diagonal().cwiseAbs().maxCoeff();
  if ((m - m.transpose()).cwiseAbs().maxCoeff() > 1e-6 * scale + 1e-300) return std::string(field) + " is not symmetric";
  for (int i = 0; i < 3; ++i)
    if (m(i, i) < 0.0 || m(i, i) > l.cov_ceiling)
      return std::string(field) + " variance " + std::to_string(i) + " not in [0, limits.cov_ceiling_m2 " + num(l.cov_ceiling) +
             "] (got " + num(m(i, i)) + ")";
  // Positive semi-definite within rounding: every 2x2 minor and the determinant.
  const double tol = 1e-9 * scale * scale;
  for (int i = 0; i < 3; ++i)
    for (int j = i + 1; j < 3; ++j)
      if (m(i, i) * m(j, j) - m(i, j) * m(i, j) < -tol) return std::string(field) + " is not positive semi-definite";
  if (m.determinant() < -tol * scale) return std::string(field) + " is not positive semi-definite (got determinant " + num(m.determinant()) + ")";
  return "";
}

JumpGuard::Verdict JumpGuard::check(std::int64_t last, std::int64_t next, std::int64_t window, bool strictly_after) {
  // Callers bound both values (frames: int32; seq: [0, kMaxSeq]): no overflow here.
  if (next - last <= window) {
    if (pending_ >= 0 && pending_ <= next) pending_ = -1;  // the stream has caught up with it
    return Verdict::kInWindow;
  }
  if (pending_ >= 0 && (strictly_after ? next > pending_ : next >= pending_) && next - pending_ <= window) {
    pending_ = -1;
    return Verdict::kConfirmed;
  }
  pending_ = next;
  return Verdict::kHeld;
}

}  // namespace elaslam

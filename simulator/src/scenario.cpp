// SPDX-License-Identifier: Apache-2.0
#include "elaslam/simulator/scenario.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <utility>
#include <sstream>

#include "elaslam/common/contract.hpp"
#include "elaslam/common/geometry.hpp"
#include "elaslam/simulator/layout.hpp"
#include "elaslam/simulator/motion.hpp"

namespace elaslam::sim {
namespace {

constexpr double kBig = 1e6;  // [m] generous bound for coordinates and lengths

// OdometerError's bounds: MRCLAM's odometers turn 0.87-0.95 of what they report;
// beyond a factor of 2 either way an odometer is broken, not miscalibrated. A turn
// rate bias of 0.5 rad/s (29 deg/s) is far beyond any working one.
constexpr double kScaleMin = 0.5, kScaleMax = 2.0;
constexpr double kTurnBiasMaxRadS = 0.5;
// At most 180 degrees of turn in a frame: beyond it the increment between two
// odometer readings is ambiguous (angles wrap).
constexpr double kMaxTurnPerFrameRad = kPi;

std::string num(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

void parse_sensor(config::Reader& r, SensorOptions* s) {
  r.read("fov_diameter_m", &s->fov_diameter_m, 1e-3, kBig);
  r.read("min_range_m", &s->min_range_m, 0.0, kBig);
  r.read("range_sigma_m", &s->range_sigma_m, 0.0, 100.0);
  r.read("bearing_sigma_deg", &s->bearing_sigma_deg, 0.0, 90.0);
  r.read("detection_probability", &s->detection_probability, 0.0, 1.0);
  r.read_optional("max_observations", &s->max_observations, 1, contract::kMaxObsPerFrameLimit);
}

// The systematic odometer error's keys (scenario.odometry: every robot's default;
// scenario.robots[i].odometry: that robot's), each optional: *e keeps the default.
void parse_odometer_error(config::Reader& r, OdometerError* e) {
  r.read_optional("turn_scale", &e->turn_scale, kScaleMin, kScaleMax);
  r.read_optional("speed_scale", &e->speed_scale, kScaleMin, kScaleMax);
  r.read_optional("turn_bias_rad_s", &e->turn_bias_rad_s, -kTurnBiasMaxRadS, kTurnBiasMaxRadS);
}

void parse_odometry(config::Reader& r, OdometryOptions* o, OdometerError* every_robot) {
  r.read("var_trans_per_m", &o->var_trans_per_m, 0.0, 10.0);
  r.read("var_rot_per_rad", &o->var_rot_per_rad, 0.0, 10.0);
  r.read("var_rot_per_m", &o->var_rot_per_m, 0.0, 10.0);
  parse_odometer_error(r, every_robot);
}

// The keys of the chosen layout are required; the others are optional (checked
// when present) so that a file can keep them for switching layouts.
void parse_landmarks(config::Reader& r, LandmarkOptions* l) {
  std::string layout = "grid";
  r.read_enum("layout", &layout, {"grid", "cloister", "random"});
  l->layout = layout == "cloister" ? Layout::kCloister : layout == "random" ? Layout::kRandom : Layout::kGrid;
  r.read("count", &l->count, 1, contract::kMaxWorldLandmarks);
  auto want = [&](Layout which, const char* key) { return l->layout == which || r.has(key); };
  if (want(Layout::kGrid, "grid_columns")) r.read("grid_columns", &l->grid_columns, 1, 256);
  if (want(Layout::kGrid, "grid_rows")) r.read("grid_rows", &l->grid_rows, 1, 256);
  if (want(Layout::kCloister, "cloister_rings")) r.read("cloister_rings", &l->cloister_rings, 1, 64);
  if (want(Layout::kCloister, "cloister_inner_half_width_m"))
    r.read("cloister_inner_half_width_m", &l->cloister_inner_half_width_m, 1e-3, kBig);
  if (want(Layout::kCloister, "cloister_outer_half_width_m"))
    r.read("cloister_outer_half_width_m", &l->cloister_outer_half_width_m, 1e-3, kBig);
  if (want(Layout::kRandom, "min_spacing_m")) r.read("min_spacing_m", &l->min_spacing_m, 0.0, kBig);
  r.section(
      "empty_region",
      [&](config::Reader& s) {
        EmptyRegion& e = l->empty_region;
        e.enabled = true;
        s.read("x_min_m", &e.x_min_m, -kBig, kBig);
        s.read("x_max_m", &e.x_max_m, -kBig, kBig);
        s.read("y_min_m", &e.y_min_m, -kBig, kBig);
        s.read("y_max_m", &e.y_max_m, -kBig, kBig);
      },
      /*optional=*/true);
}

void parse_robot(config::Reader& r, RobotPathOptions* p, const OdometerError& every_robot) {
  r.read("id", &p->id, 1, contract::kMaxRobots);
  std::vector<double> c{p->center_x_m, p->center_y_m};
  r.read_vector("center_m", &c, 2, -kBig, kBig);
  p->center_x_m = c[0];
  p->center_y_m = c[1];
  r.read("radius_m", &p->radius_m, 1e-3, kBig);
  r.read("start_angle_deg", &p->start_angle_deg, -360.0, 360.0);
  std::string dir = "ccw";
  r.read_enum("direction", &dir, {"ccw", "cw"});
  p->ccw = dir == "ccw";
  r.read("speed_mps", &p->speed_mps, 0.0, 1000.0);
  r.section(
      "spin",
      [&](config::Reader& s) {
        s.read("start_s", &p->spin.start_s, 0.0, kBig);
        s.read("duration_s", &p->spin.duration_s, 1e-3, kBig);
        s.read("turn_deg", &p->spin.turn_deg, -3600.0, 3600.0);
      },
      /*optional=*/true);
  p->odometer = every_robot;
  r.section("odometry", [&](config::Reader& s) { parse_odometer_error(s, &p->odometer); }, /*optional=*/true);
}

// The kinds a moving landmark can take, as the configuration spells them.
constexpr MotionKind kMoverKinds[] = {MotionKind::kOscillating, MotionKind::kConstantVelocity,
                                      MotionKind::kStopAndGo};
// A stop-and-go stretch's bounds [s] as read; check_scenario wants a frame at least.
constexpr double kStretchMinS = 1e-3;

void parse_movers(config::Reader& r, MoverOptions* m) {
  std::vector<std::string> names;
  r.read_enum_list("kinds", &names, {"oscillating", "constant_velocity", "stop_and_go"}, 1, limits::kMaxMoverKinds);
  if (!names.empty()) {  // empty: the list was bad, reported already
    m->kinds.clear();
    for (const std::string& name : names)
      for (MotionKind k : kMoverKinds)
        if (name == motion_kind_name(k)) m->kinds.push_back(k);
  }
  r.section(
      "stop_and_go",
      [&](config::Reader& s) {
        s.read_optional("move_s", &m->stop_and_go.move_s, kStretchMinS, kBig);
        s.read_optional("stop_s", &m->stop_and_go.stop_s, kStretchMinS, kBig);
      },
      /*optional=*/true);
}

// round(duration x rate), saturated so that a huge product stays an int (checked).
int stretch_frames(double duration_s, double rate_hz) {
  const double f = std::round(duration_s * rate_hz);
  return f >= 0.0 && f <= static_cast<double>(limits::kFramesMax) ? static_cast<int>(f) : limits::kFramesMax + 1;
}

void check_movers(const ScenarioOptions& o, std::vector<Problem>* out) {
  const MoverOptions& m = o.movers;
  if (m.kinds.empty() || m.kinds.size() > limits::kMaxMoverKinds)
    out->push_back({"movers.kinds", "must list 1 to " + std::to_string(limits::kMaxMoverKinds) + " kinds"});
  for (std::size_t i = 0; i < m.kinds.size(); ++i)
    if (m.kinds[i] == MotionKind::kStatic)
      out->push_back({"movers.kinds[" + std::to_string(i) + "]",
                      "static is not a mover kind: expected oscillating, constant_velocity or stop_and_go (the "
                      "static landmarks are the ones dynamism_percent leaves out)"});
  const std::pair<const char*, double> stretches[] = {{"move_s", m.stop_and_go.move_s},
                                                      {"stop_s", m.stop_and_go.stop_s}};
  for (const auto& [key, seconds] : stretches) {
    const std::string path = std::string("movers.stop_and_go.") + key;
    if (!(seconds > 0.0 && seconds <= kBig)) {
      out->push_back({path, "must be in (0, " + num(kBig) + "] s, got " + num(seconds)});
      continue;
    }
    if (!m.uses(MotionKind::kStopAndGo)) continue;  // kept for switching kinds: not turned into frames
    const int frames = stretch_frames(seconds, o.rate_hz);
    if (frames < 1)
      out->push_back({path, num(seconds) + " s is less than one frame at " + num(o.rate_hz) +
                                " Hz: make it at least 1 / rate_hz = " + num(1.0 / o.rate_hz) + " s"});
    else if (frames > limits::kFramesMax)
      out->push_back({path, num(seconds) + " s is more than " + std::to_string(limits::kFramesMax) + " frames at " +
                                num(o.rate_hz) + " Hz"});
  }
}

bool has_spin(const RobotPathOptions& p) { return p.spin.duration_s > 0.0; }

// Is every point of the part of the semicircle the robot drives inside the world?
// Sampled every 0.5 degrees of arc plus the end point (error < 1e-5 x radius).
bool path_inside(const ScenarioOptions& o, const RobotPathOptions& p, std::string* where) {
  if (!(p.radius_m > 0.0 && p.speed_mps >= 0.0)) return true;  // out of range: reported by parse
  const double t_end = (o.frames - 1) / o.rate_hz;
  const double arc_end = std::min(p.speed_mps * drive_time(p, t_end), kPi * p.radius_m);
  const int n = static_cast<int>(std::ceil(arc_end / p.radius_m / deg2rad(0.5))) + 1;
  for (int i = 0; i <= n; ++i) {
    const double s = arc_end * i / n;
    double t = p.speed_mps > 0.0 ? s / p.speed_mps : 0.0;
    if (has_spin(p) && t > p.spin.start_s) t += p.spin.duration_s;  // the arc after the turn in place
    const Pose2 T = path_pose(p, t);
    if (T.x < o.world.x_min_m || T.x > o.world.x_max_m || T.y < o.world.y_min_m || T.y > o.world.y_max_m) {
      *where = "(" + num(T.x) + ", " + num(T.y) + ")";
      return false;
    }
  }
  return true;
}

// The odometer error within its bounds (code-built options reach here unchecked),
// and the largest turn it can report in a frame below 180 degrees.
void check_odometer(const ScenarioOptions& o, const RobotPathOptions& p, const std::string& key,
                    std::vector<Problem>* out) {
  const OdometerError& e = p.odometer;
  const std::size_t problems_before = out->size();
  const std::string scales = "[" + num(kScaleMin) + ", " + num(kScaleMax) + "]";
  if (!(e.turn_scale >= kScaleMin && e.turn_scale <= kScaleMax))
    out->push_back({key + ".odometry.turn_scale", "must be in " + scales + ", got " + num(e.turn_scale)});
  if (!(e.speed_scale >= kScaleMin && e.speed_scale <= kScaleMax))
    out->push_back({key + ".odometry.speed_scale", "must be in " + scales + ", got " + num(e.speed_scale)});
  if (!(std::abs(e.turn_bias_rad_s) <= kTurnBiasMaxRadS))
    out->push_back({key + ".odometry.turn_bias_rad_s",
                    "must be in [" + num(-kTurnBiasMaxRadS) + ", " + num(kTurnBiasMaxRadS) + "] rad/s, got " +
                        num(e.turn_bias_rad_s)});
  if (has_spin(p) && !(p.spin.start_s >= 0.0))
    out->push_back({key + ".spin.start_s", "must be >= 0, got " + num(p.spin.start_s)});
  // The bound below needs sane values (a bad radius or speed is reported by parse).
  if (out->size() > problems_before || !(p.radius_m > 0.0 && p.speed_mps >= 0.0)) return;
  // Upper bound of the true turn in a frame (driving and turning in place may share
  // one), then what the odometer reports of it.
  const double dt = o.dt_s();
  const double turn = p.speed_mps * dt / p.radius_m +
                      (has_spin(p) ? std::abs(deg2rad(p.spin.turn_deg)) * dt / p.spin.duration_s : 0.0);
  const double reported = (turn + std::abs(e.turn_bias_rad_s) * dt) / e.turn_scale;
  if (!(reported < kMaxTurnPerFrameRad))
    out->push_back({key, "its odometer would report up to " + num(rad2deg(reported)) +
                             " deg of turn in a frame, which must stay below 180 deg (angles wrap): raise rate_hz, "
                             "slow the spin (spin.duration_s) or lower odometry.turn_bias_rad_s"});
}

void check_robots(const ScenarioOptions& o, std::vector<Problem>* out) {
  std::set<int> ids;
  const double D = o.sensor.fov_diameter_m;
  for (std::size_t i = 0; i < o.robots.size(); ++i) {
    const RobotPathOptions& p = o.robots[i];
    const std::string key = "robots[" + std::to_string(i) + "]";
    if (p.id < 1 || p.id > contract::kMaxRobots)
      out->push_back({key + ".id", "must be in [1, " + std::to_string(contract::kMaxRobots) + "]"});
    if (!ids.insert(p.id).second) out->push_back({key + ".id", "duplicate robot id " + std::to_string(p.id)});
    const double step = p.speed_mps / o.rate_hz;
    if (step >= D)
      out->push_back({key + ".speed_mps", "the robot moves " + num(step) + " m per frame at " + num(o.rate_hz) +
                                              " Hz, which must stay below the sensor's diameter D = " + num(D) +
                                              " m (paper eq 14): lower the speed or raise rate_hz"});
    std::string where;
    if (!path_inside(o, p, &where))
      out->push_back({key, "the path leaves the world at " + where + ": move center_m or shrink radius_m" +
                               (has_spin(p) ? " or change spin (the rest of the path turns with it)" : "")});
    check_odometer(o, p, key, out);
  }
}

}  // namespace

int ScenarioOptions::moving_count(int num_landmarks) const {
  return static_cast<int>(std::lround(dynamism_percent * num_landmarks / 100.0));
}

int ScenarioOptions::stop_and_go_move_frames() const { return stretch_frames(movers.stop_and_go.move_s, rate_hz); }
int ScenarioOptions::stop_and_go_stop_frames() const { return stretch_frames(movers.stop_and_go.stop_s, rate_hz); }

bool MoverOptions::uses(MotionKind k) const { return std::find(kinds.begin(), kinds.end(), k) != kinds.end(); }

const char* motion_kind_name(MotionKind k) {
  switch (k) {
    case MotionKind::kStatic: return "static";
    case MotionKind::kOscillating: return "oscillating";
    case MotionKind::kConstantVelocity: return "constant_velocity";
    case MotionKind::kStopAndGo: return "stop_and_go";
  }
  return "?";
}

const char* layout_name(Layout l) {
  switch (l) {
    case Layout::kGrid: return "grid";
    case Layout::kCloister: return "cloister";
    case Layout::kRandom: return "random";
  }
  return "?";
}

std::vector<Problem> check_scenario(const ScenarioOptions& o) {
  std::vector<Problem> out;
  const WorldBounds& w = o.world;
  if (!(w.x_min_m < w.x_max_m)) out.push_back({"world.x_max_m", "must be greater than world.x_min_m"});
  if (!(w.y_min_m < w.y_max_m)) out.push_back({"world.y_max_m", "must be greater than world.y_min_m"});
  if (!out.empty()) return out;  // everything below needs a world
  if (o.frames < 1) out.push_back({"frames", "must be at least 1"});
  if (o.reversal_period_frames < 1) out.push_back({"reversal_period_frames", "must be at least 1"});
  const SensorOptions& s = o.sensor;
  if (!(s.fov_diameter_m > 0.0) || !(s.range_sigma_m >= 0.0) || !(s.bearing_sigma_deg >= 0.0) ||
      !(s.detection_probability >= 0.0 && s.detection_probability <= 1.0))
    out.push_back({"sensor", "needs D > 0, sigmas >= 0 and a detection probability in [0, 1]"});
  const OdometryOptions& od = o.odometry;
  if (!(od.var_trans_per_m >= 0.0 && od.var_rot_per_rad >= 0.0 && od.var_rot_per_m >= 0.0))
    out.push_back({"odometry", "variances must be >= 0"});
  // Written so that nan fails every test (overrides reach here without the reader's checks).
  if (!(o.rate_hz >= limits::kRateMinHz && o.rate_hz <= limits::kRateMaxHz))
    out.push_back({"rate_hz", "must be in [" + num(limits::kRateMinHz) + ", " + num(limits::kRateMaxHz) + "] Hz, got " +
                                  num(o.rate_hz)});
  if (!(o.rate_hz > 0.0) || !(s.fov_diameter_m > 0.0)) return out;  // the checks below divide by them
  if (o.sensor.min_range_m >= o.sensor.max_range_m())
    out.push_back({"sensor.min_range_m", "must be below the sensor range D/2 = " + num(o.sensor.max_range_m()) + " m"});
  const double lm_step = o.landmark_speed_mps / o.rate_hz;
  const double min_side = std::min(w.x_max_m - w.x_min_m, w.y_max_m - w.y_min_m);
  if (!(o.landmark_speed_mps >= 0.0 && o.landmark_speed_mps <= limits::kLandmarkSpeedMaxMps))
    out.push_back({"landmark_speed_mps", "must be in [0, " + num(limits::kLandmarkSpeedMaxMps) + "] m/s, got " +
                                             num(o.landmark_speed_mps)});
  else if (lm_step >= o.sensor.fov_diameter_m || lm_step >= min_side)
    out.push_back({"landmark_speed_mps", "moving landmarks would move " + num(lm_step) +
                                             " m per frame, which must stay below D = " +
                                             num(o.sensor.fov_diameter_m) +
                                             " m (paper section 3.2) and below the world's size"});
  if (!(o.dynamism_percent >= 0.0 && o.dynamism_percent <= limits::kDynamismMaxPercent))
    out.push_back({"dynamism_percent", "must be in [0, 100], got " + num(o.dynamism_percent)});
  check_movers(o, &out);
  if (o.robots.empty() || o.robots.size() > static_cast<std::size_t>(contract::kMaxRobots))
    out.push_back({"robots", "need 1 to " + std::to_string(contract::kMaxRobots) + " robots"});
  check_robots(o, &out);
  const EmptyRegion& e = o.landmarks.empty_region;
  if (e.enabled) {
    if (!(e.x_min_m < e.x_max_m))
      out.push_back({"landmarks.empty_region.x_max_m", "must be greater than landmarks.empty_region.x_min_m"});
    if (!(e.y_min_m < e.y_max_m))
      out.push_back({"landmarks.empty_region.y_max_m", "must be greater than landmarks.empty_region.y_min_m"});
    if (!(e.x_min_m < w.x_max_m && e.x_max_m > w.x_min_m && e.y_min_m < w.y_max_m && e.y_max_m > w.y_min_m))
      out.push_back({"landmarks.empty_region", "lies outside the world: it would leave nothing out"});
  }
  std::vector<Eigen::Vector2d> layout;
  std::string why;
  if (!generate_layout(o, &layout, &why)) out.push_back({"landmarks", why});
  return out;
}

void parse(config::Reader& r, ScenarioOptions* o) {
  r.section("world", [&](config::Reader& s) {
    s.read("x_min_m", &o->world.x_min_m, -kBig, kBig);
    s.read("x_max_m", &o->world.x_max_m, -kBig, kBig);
    s.read("y_min_m", &o->world.y_min_m, -kBig, kBig);
    s.read("y_max_m", &o->world.y_max_m, -kBig, kBig);
  });
  r.read("frames", &o->frames, 1, limits::kFramesMax);
  r.read("rate_hz", &o->rate_hz, limits::kRateMinHz, limits::kRateMaxHz);
  r.read("seed", &o->seed, 0, limits::kSeedMax);
  r.section("sensor", [&](config::Reader& s) { parse_sensor(s, &o->sensor); });
  OdometerError every_robot;  // scenario.odometry's default for robots[i].odometry
  r.section("odometry", [&](config::Reader& s) { parse_odometry(s, &o->odometry, &every_robot); });
  r.section("landmarks", [&](config::Reader& s) { parse_landmarks(s, &o->landmarks); });
  r.read("dynamism_percent", &o->dynamism_percent, 0.0, limits::kDynamismMaxPercent);
  r.read("landmark_speed_mps", &o->landmark_speed_mps, 0.0, limits::kLandmarkSpeedMaxMps);
  r.read("reversal_period_frames", &o->reversal_period_frames, 1, 100000000);
  r.section("movers", [&](config::Reader& s) { parse_movers(s, &o->movers); }, /*optional=*/true);
  o->robots.clear();
  r.list(
      "robots",
      [&](config::Reader& s, std::size_t) {
        o->robots.emplace_back();
        parse_robot(s, &o->robots.back(), every_robot);
      },
      1, static_cast<std::size_t>(contract::kMaxRobots));
  if (o->robots.empty()) return;  // the list itself was bad: reported already
  for (const Problem& p : check_scenario(*o)) r.fail(p.key, p.what);
}

namespace {
ScenarioOptions load(config::Document& doc, std::string* effective_yaml = nullptr) {
  ScenarioOptions o;
  doc.allow_sections();
  doc.section("scenario", [&](config::Reader& r) { parse(r, &o); });
  doc.finish();
  if (effective_yaml) *effective_yaml = doc.effective_yaml();
  return o;
}
}  // namespace

ScenarioOptions load_scenario_text(const std::string& text, const std::string& source) {
  config::Document doc = config::Document::from_string(text, source);
  return load(doc);
}

ScenarioOptions load_scenario(const std::string& path, std::string* effective_yaml) {
  config::Document doc = config::Document::from_file(path);
  return load(doc, effective_yaml);
}

namespace {
// " 12 oscillating, 12 constant_velocity (kinds in turn over the moving ids)": the
// j-th moving landmark takes kinds[j % K], so entry t of the list gets m / K
// movers, one more when t < m % K.
std::string describe_movers(const ScenarioOptions& o, int moving) {
  const std::vector<MotionKind>& kinds = o.movers.kinds;
  if (kinds.empty()) return " none listed";
  const int k = static_cast<int>(kinds.size());
  std::ostringstream os;
  bool first = true;
  for (MotionKind kind : kMoverKinds) {
    int count = 0;
    for (int t = 0; t < k; ++t)
      if (kinds[static_cast<std::size_t>(t)] == kind) count += moving / k + (t < moving % k ? 1 : 0);
    if (!o.movers.uses(kind)) continue;
    os << (first ? " " : ", ") << count << " " << motion_kind_name(kind);
    first = false;
  }
  if (k > 1) {
    os << " (kinds [";
    for (int t = 0; t < k; ++t) os << (t ? ", " : "") << motion_kind_name(kinds[static_cast<std::size_t>(t)]);
    os << "] in turn over the moving ids)";
  }
  return os.str();
}
}  // namespace

std::string describe(const ScenarioOptions& o) {
  std::vector<Eigen::Vector2d> layout;
  std::string why;
  const int n = generate_layout(o, &layout, &why) ? static_cast<int>(layout.size()) : o.landmarks.count;
  std::ostringstream os;
  os << "scenario: world [" << o.world.x_min_m << ", " << o.world.x_max_m << "] x [" << o.world.y_min_m << ", "
     << o.world.y_max_m << "] m, " << o.frames << " frames at " << o.rate_hz << " Hz, seed " << o.seed << "\n"
     << "  sensor: D = " << o.sensor.fov_diameter_m << " m, sigma range " << o.sensor.range_sigma_m
     << " m, sigma bearing " << o.sensor.bearing_sigma_deg << " deg, p_detect " << o.sensor.detection_probability
     << "\n"
     << "  odometry: var_trans " << o.odometry.var_trans_per_m << " m^2/m, var_rot " << o.odometry.var_rot_per_rad
     << " rad^2/rad + " << o.odometry.var_rot_per_m << " rad^2/m\n"
     << "  landmarks: " << n << " (" << layout_name(o.landmarks.layout) << "), dynamism "
     << o.dynamism_percent << " % (" << o.moving_count(n) << " moving) at " << o.landmark_speed_mps
     << " m/s, reversal every " << o.reversal_period_frames << " frames\n";
  os << "  movers:" << describe_movers(o, o.moving_count(n)) << "\n";
  if (o.movers.uses(MotionKind::kStopAndGo))
    os << "    stop_and_go: moving " << o.movers.stop_and_go.move_s << " s (" << o.stop_and_go_move_frames()
       << " frames), standing still " << o.movers.stop_and_go.stop_s << " s (" << o.stop_and_go_stop_frames()
       << " frames), each from its own random point of the cycle\n";
  const EmptyRegion& e = o.landmarks.empty_region;
  if (e.enabled)
    os << "  empty region: [" << e.x_min_m << ", " << e.x_max_m << "] x [" << e.y_min_m << ", " << e.y_max_m
       << "] m (" << o.landmarks.count - n << " of the layout's " << o.landmarks.count << " landmarks left out)\n";
  for (const auto& p : o.robots) {
    os << "  robot " << p.id << ": centre (" << p.center_x_m << ", " << p.center_y_m << ") m, radius "
       << p.radius_m << " m, start " << p.start_angle_deg << " deg, " << (p.ccw ? "ccw" : "cw") << ", "
       << p.speed_mps << " m/s\n";
    if (has_spin(p))
      os << "    spin: " << p.spin.turn_deg << " deg in place from " << p.spin.start_s << " s for "
         << p.spin.duration_s << " s\n";
    if (!p.odometer.none())
      os << "    odometer: turn scale " << p.odometer.turn_scale << ", speed scale " << p.odometer.speed_scale
         << ", turn bias " << p.odometer.turn_bias_rad_s << " rad/s (true = scale x reported + bias x dt)\n";
  }
  return os.str();
}

}  // namespace elaslam::sim

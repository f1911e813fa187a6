// SPDX-License-Identifier: Apache-2.0
#include "elaslam/dataset/mrclam.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>

#include "elaslam/common/cli.hpp"
#include "elaslam/common/contract.hpp"

namespace elaslam::mrclam {
namespace {

// ---- text files ------------------------------------------------------------------

std::string read_file(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw DatasetError(path + ": cannot open the file (missing from the dataset directory?)");
  std::string text;
  char buf[1 << 16];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) text.append(buf, n);
  std::fclose(f);
  return text;
}

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// Calls fn(line_number, values) for every data line, after checking the column
/// count and that every value is a finite number.
template <typename Fn>
void for_each_row(const std::string& path, std::size_t columns, Fn fn) {
  const std::string text = read_file(path);
  std::vector<double> values(columns);
  std::vector<std::string> tokens;
  const char* p = text.c_str();
  const char* const end = p + text.size();
  int line = 0;
  while (p < end) {
    ++line;
    const char* eol = static_cast<const char*>(std::memchr(p, '\n', static_cast<std::size_t>(end - p)));
    if (!eol) eol = end;
    const char* q = p;
    while (q < eol && is_blank(*q)) ++q;
    if (q < eol && *q != '#') {
      tokens.clear();
      while (q < eol) {
        const char* b = q;
        while (q < eol && !is_blank(*q)) ++q;
        tokens.emplace_back(b, q);
        while (q < eol && is_blank(*q)) ++q;
      }
      const std::string where = path + ":" + std::to_string(line) + ": ";
      if (tokens.size() != columns)
        throw DatasetError(where + "wrong column count: expected " + std::to_string(columns) + ", got " +
                           std::to_string(tokens.size()));
      for (std::size_t i = 0; i < columns; ++i) {
        const char* s = tokens[i].c_str();
        char* e = nullptr;
        const double v = std::strtod(s, &e);
        if (e == s || *e != '\0')
          throw DatasetError(where + "column " + std::to_string(i + 1) + " ('" + tokens[i] + "') is not a number");
        if (!std::isfinite(v))
          throw DatasetError(where + "column " + std::to_string(i + 1) + " ('" + tokens[i] + "') is not finite");
        values[i] = v;
      }
      fn(line, where, values);
    }
    p = eol + 1;
  }
}

int as_int(double v, const std::string& where, const char* what) {
  if (v != std::floor(v) || std::fabs(v) > 1e9)
    throw DatasetError(where + what + " must be an integer, got " + std::to_string(v));
  return static_cast<int>(v);
}

/// Seconds (file) -> microseconds; the files have ms resolution, so this is exact.
std::int64_t to_utime(double t, const std::string& where) {
  if (std::fabs(t) > 9.0e12) throw DatasetError(where + "time out of range");
  return std::llround(t * 1e6);
}

std::int64_t checked_time(double t, std::int64_t* last, const std::string& where) {
  const std::int64_t u = to_utime(t, where);
  if (u < *last) {
    std::ostringstream os;
    os.precision(16);
    os << where << "time goes backwards: " << t << " s after " << static_cast<double>(*last) * 1e-6
       << " s on an earlier line (times must be non-decreasing)";
    throw DatasetError(os.str());
  }
  *last = u;
  return u;
}

/// wrap_angle, but values already in [-pi, pi) stay bit-identical to the file.
double wrap_if_needed(double a) { return (a >= -kPi && a < kPi) ? a : wrap_angle(a); }

double seconds(std::int64_t du) { return static_cast<double>(du) * 1e-6; }

std::string robot_file(const std::string& dir, int id, const char* kind) {
  return dir + "/Robot" + std::to_string(id) + "_" + kind + ".dat";
}

RobotSeries load_robot(const std::string& dir, int id) {
  RobotSeries s;
  s.id = id;
  std::int64_t last = INT64_MIN;
  const std::string odo = robot_file(dir, id, "Odometry");
  for_each_row(odo, 3, [&](int, const std::string& where, const std::vector<double>& v) {
    s.odometry.push_back({checked_time(v[0], &last, where), v[1], v[2]});
  });
  if (s.odometry.empty()) throw DatasetError(odo + ": no data lines");
  last = INT64_MIN;
  const std::string gt = robot_file(dir, id, "Groundtruth");
  for_each_row(gt, 4, [&](int, const std::string& where, const std::vector<double>& v) {
    s.ground_truth.push_back({checked_time(v[0], &last, where), Pose2{v[1], v[2], wrap_if_needed(v[3])}});
  });
  if (s.ground_truth.empty()) throw DatasetError(gt + ": no data lines");
  last = INT64_MIN;
  for_each_row(robot_file(dir, id, "Measurement"), 4, [&](int, const std::string& where, const std::vector<double>& v) {
    const std::int64_t u = checked_time(v[0], &last, where);
    s.measurements.push_back({u, as_int(v[1], where, "the barcode (column 2)"), v[2], v[3]});
  });
  return s;
}


}  // namespace

int run_step(const char* program, const std::function<int()>& step) {
  try {
    return step();
  } catch (const DatasetError& e) {
    std::fprintf(stderr, "%s: %s\n", program, e.what());
    return cli::kExitFailure;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "%s: %s\n", program, e.what());
    return cli::kExitBadInput;
  }
}

// ---- options -------------------------------------------------------------------------

bool parse_robot_list(const std::string& text, std::vector<int>* out, std::string* why) {
  std::vector<int> ids;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const auto b = item.find_first_not_of(" \t"), e = item.find_last_not_of(" \t");
    if (b == std::string::npos) {
      *why = "empty item in '" + text + "' (expected e.g. 1,2,3,4,5)";
      return false;
    }
    const std::string t = item.substr(b, e - b + 1);
    char* end = nullptr;
    const long v = std::strtol(t.c_str(), &end, 10);
    if (*end != '\0' || v < 1 || v > kMaxRobotSubject) {
      *why = "'" + t + "' is not a robot (MRCLAM robots are subjects 1 to " + std::to_string(kMaxRobotSubject) + ")";
      return false;
    }
    if (std::find(ids.begin(), ids.end(), static_cast<int>(v)) != ids.end()) {
      *why = "robot " + t + " given twice";
      return false;
    }
    ids.push_back(static_cast<int>(v));
  }
  if (ids.empty()) {
    *why = "no robots given (expected e.g. 1,2,3,4,5)";
    return false;
  }
  *out = ids;
  return true;
}

void parse(config::Reader& r, Options* o) {
  r.read("rate_hz", &o->rate_hz, limits::kRateMinHz, limits::kRateMaxHz);
  std::string robots;
  for (int id : o->robots) robots += (robots.empty() ? "" : ",") + std::to_string(id);
  r.read("robots", &robots);
  std::string why;
  if (!parse_robot_list(robots, &o->robots, &why)) r.fail("robots", why);
  r.read("with_robot_barcodes", &o->with_robot_barcodes);
  r.read("start_s", &o->start_s, 0.0, limits::kStartMaxS);
  r.read("duration_s", &o->duration_s, 0.0, limits::kDurationMaxS);
  r.read("odom_var_trans_per_m", &o->odom_var_trans_per_m, 0.0, 100.0);
  r.read("odom_var_rot_per_rad", &o->odom_var_rot_per_rad, 0.0, 100.0);
  r.read("odom_var_rot_per_m", &o->odom_var_rot_per_m, 0.0, 100.0);
  r.read_optional("motion_compensation", &o->motion_compensation);
  r.read_optional("odometry_delay_s", &o->odometry_delay_s, 0.0, 5.0);
  r.read_optional("range_scale_k0", &o->range_scale_k0, -0.5, 0.5);
  r.read_optional("range_scale_k1", &o->range_scale_k1, -2.0, 2.0);
}

Options load_options(const std::string& yaml_path, std::string* effective_yaml) {
  config::Document doc = config::Document::from_file(yaml_path);
  Options o = config::read_component<Options>(doc, "dataset");
  if (effective_yaml) *effective_yaml = doc.effective_yaml();
  return o;
}

// ---- dataset -------------------------------------------------------------------------

Dataset Dataset::load(const std::string& dir, const std::vector<int>& robots) {
  Dataset d;
  d.dir_ = dir;
  const std::string bpath = dir + "/Barcodes.dat";
  for_each_row(bpath, 2, [&](int, const std::string& where, const std::vector<double>& v) {
    const int subject = as_int(v[0], where, "the subject (column 1)");
    const int barcode = as_int(v[1], where, "the barcode (column 2)");
    if (subject < 1 || barcode < 1) throw DatasetError(where + "subject and barcode must be positive");
    for (const auto& sb : d.barcodes_)
      if (sb.first == subject || sb.second == barcode)
        throw DatasetError(where + "subject " + std::to_string(subject) + " or barcode " + std::to_string(barcode) +
                           " already listed");
    d.barcodes_.emplace_back(subject, barcode);
  });
  const std::string lpath = dir + "/Landmark_Groundtruth.dat";
  for_each_row(lpath, 5, [&](int, const std::string& where, const std::vector<double>& v) {
    const int subject = as_int(v[0], where, "the subject (column 1)");
    if (subject < kFirstLandmarkSubject)
      throw DatasetError(where + "landmark subject " + std::to_string(subject) + " is a robot's number (1-5)");
    d.landmarks_.push_back({subject, v[1], v[2], v[3], v[4]});
  });
  for (int id : robots) {
    if (id < 1 || id > kMaxRobotSubject)
      throw DatasetError(dir + ": robot " + std::to_string(id) + " does not exist (MRCLAM robots are 1 to 5)");
    if (d.has_robot(id)) throw DatasetError(dir + ": robot " + std::to_string(id) + " selected twice");
    d.robots_.push_back(load_robot(dir, id));
  }
  return d;
}

int Dataset::subject_of_barcode(int barcode) const {
  for (const auto& sb : barcodes_)
    if (sb.second == barcode) return sb.first;
  return 0;
}

int Dataset::barcode_of_subject(int subject) const {
  for (const auto& sb : barcodes_)
    if (sb.first == subject) return sb.second;
  return 0;
}

bool Dataset::has_robot(int id) const {
  return std::any_of(robots_.begin(), robots_.end(), [id](const RobotSeries& s) { return s.id == id; });
}

const RobotSeries& Dataset::robot(int id) const {
  for (const auto& s : robots_)
    if (s.id == id) return s;
  throw std::out_of_range("mrclam: robot " + std::to_string(id) + " was not loaded");
}

// ---- motion --------------------------------------------------------------------------

Pose2 integrate(const Pose2& p, double v, double w, double dt) {
  const double dth = w * dt;
  if (std::fabs(dth) < 1e-9) {
    // Straight (the arc formula divides by w); second-order term keeps it smooth.
    const double th = p.theta + 0.5 * dth;
    return {p.x + v * dt * std::cos(th), p.y + v * dt * std::sin(th), wrap_angle(p.theta + dth)};
  }
  const double r = v / w;
  return {p.x + r * (std::sin(p.theta + dth) - std::sin(p.theta)),
          p.y - r * (std::cos(p.theta + dth) - std::cos(p.theta)), wrap_angle(p.theta + dth)};
}

bool interpolate(const std::vector<PoseSample>& gt, std::int64_t utime, Pose2* out, std::size_t* hint) {
  if (gt.empty() || utime < gt.front().utime || utime > gt.back().utime) return false;
  std::size_t i = hint ? std::min(*hint, gt.size() - 1) : 0;
  if (gt[i].utime > utime) i = 0;
  // Linear scan from the hint when close, else binary search.
  if (i + 8 < gt.size() && gt[i + 8].utime <= utime) {
    i = static_cast<std::size_t>(std::upper_bound(gt.begin() + static_cast<std::ptrdiff_t>(i), gt.end(), utime,
                                                  [](std::int64_t u, const PoseSample& s) { return u < s.utime; }) -
                                 gt.begin()) - 1;
  } else {
    while (i + 1 < gt.size() && gt[i + 1].utime <= utime) ++i;
  }
  if (hint) *hint = i;
  if (i + 1 >= gt.size() || gt[i].utime == utime) {
    *out = gt[i].pose;
    return true;
  }
  const PoseSample& a = gt[i];
  const PoseSample& b = gt[i + 1];
  const double f = static_cast<double>(utime - a.utime) / static_cast<double>(b.utime - a.utime);
  out->x = a.pose.x + f * (b.pose.x - a.pose.x);
  out->y = a.pose.y + f * (b.pose.y - a.pose.y);
  out->theta = wrap_angle(a.pose.theta + f * wrap_angle(b.pose.theta - a.pose.theta));
  return true;
}

OdometryIntegrator::OdometryIntegrator(const std::vector<Command>& cmds, std::int64_t start_utime,
                                       const Pose2& start)
    : cmds_(&cmds), now_(start_utime), pose_(start) {
  while (next_ < cmds.size() && cmds[next_].utime <= now_) ++next_;
}

Pose2 OdometryIntegrator::advance_to(std::int64_t utime) {
  const auto& c = *cmds_;
  while (now_ < utime) {
    // The command in force: the last one at or before now_ (none yet: standing still).
    const std::int64_t until = next_ < c.size() ? std::min(utime, c[next_].utime) : utime;
    if (next_ > 0) {
      const Command& cmd = c[next_ - 1];
      const double dt = seconds(until - now_);
      pose_ = integrate(pose_, cmd.v, cmd.w, dt);
      distance_ += std::fabs(cmd.v) * dt;
    }
    now_ = until;
    while (next_ < c.size() && c[next_].utime <= now_) ++next_;
  }
  return pose_;
}

// ---- frames --------------------------------------------------------------------------

FrameSource::FrameSource(const Dataset& d, const Options& o) : options_(o), landmarks_(d.landmarks()) {
  if (!(std::isfinite(o.rate_hz) && o.rate_hz > 0.0))
    throw std::invalid_argument("mrclam: rate_hz must be > 0, got " + std::to_string(o.rate_hz));
  if (o.robots.empty()) throw std::invalid_argument("mrclam: robots is empty");
  if (o.robots.size() > static_cast<std::size_t>(contract::kMaxRobots))
    throw std::invalid_argument("mrclam: robots: more than " + std::to_string(contract::kMaxRobots));
  for (std::size_t i = 0; i < o.robots.size(); ++i) {
    if (!d.has_robot(o.robots[i]))
      throw std::invalid_argument("mrclam: robots: robot " + std::to_string(o.robots[i]) +
                                  " is not loaded in the Dataset");
    if (std::count(o.robots.begin(), o.robots.end(), o.robots[i]) > 1)
      throw std::invalid_argument("mrclam: robots: robot " + std::to_string(o.robots[i]) + " given twice");
  }
  if (!(std::isfinite(o.start_s) && o.start_s >= 0.0))
    throw std::invalid_argument("mrclam: start_s must be >= 0, got " + std::to_string(o.start_s));
  if (!(std::isfinite(o.duration_s) && o.duration_s >= 0.0))
    throw std::invalid_argument("mrclam: duration_s must be >= 0, got " + std::to_string(o.duration_s));
  for (double v : {o.odom_var_trans_per_m, o.odom_var_rot_per_rad, o.odom_var_rot_per_m})
    if (!(std::isfinite(v) && v >= 0.0))
      throw std::invalid_argument("mrclam: odom_var_* must be finite and >= 0, got " + std::to_string(v));
  if (landmarks_.size() + o.robots.size() > static_cast<std::size_t>(contract::kMaxWorldLandmarks))
    throw std::invalid_argument("mrclam: more landmarks than ground_truth_t holds (" +
                                std::to_string(contract::kMaxWorldLandmarks) + ")");

  compute_frame_times(d);
  per_robot_.resize(o.robots.size());
  stats_.robots.resize(o.robots.size());
  for (std::size_t i = 0; i < o.robots.size(); ++i)
    compute_robot(d, d.robot(o.robots[i]), &per_robot_[i], &stats_.robots[i]);
  stats_.frames = num_frames_;
  stats_.start_time = seconds(frame_utimes_.front());
  stats_.end_time = seconds(frame_utimes_.back());
}

void FrameSource::compute_frame_times(const Dataset& d) {
  t0_utime_ = INT64_MIN;
  end_utime_ = INT64_MAX;
  for (int id : options_.robots) {
    const RobotSeries& s = d.robot(id);
    t0_utime_ = std::max({t0_utime_, s.odometry.front().utime, s.ground_truth.front().utime});
    end_utime_ = std::min({end_utime_, s.odometry.back().utime, s.ground_truth.back().utime});
  }
  const std::int64_t first = t0_utime_ + std::llround(options_.start_s * 1e6);
  if (first > end_utime_ || end_utime_ < t0_utime_) {
    std::ostringstream os;
    os << "mrclam: start_s = " << options_.start_s << " s is past the common end of the selected robots ("
       << seconds(end_utime_ - t0_utime_) << " s after the common start)";
    throw std::invalid_argument(os.str());
  }
  // Frames while t_k <= end, and k / rate < duration when duration > 0.
  const double span_s = seconds(end_utime_ - t0_utime_) - options_.start_s;
  long n = static_cast<long>(std::floor(span_s * options_.rate_hz + 1e-9)) + 1;
  if (options_.duration_s > 0.0)
    n = std::min(n, static_cast<long>(std::ceil(options_.duration_s * options_.rate_hz - 1e-9)));
  frame_utimes_.clear();
  for (long k = 0; k < n; ++k) {
    const std::int64_t u =
        t0_utime_ + std::llround((options_.start_s + static_cast<double>(k) / options_.rate_hz) * 1e6);
    if (u > end_utime_) break;  // rounding guard
    frame_utimes_.push_back(u);
  }
  num_frames_ = static_cast<int>(frame_utimes_.size());
  if (num_frames_ == 0) throw std::invalid_argument("mrclam: duration_s gives no frame");
}

void FrameSource::compute_robot(const Dataset& d, const RobotSeries& s, PerRobot* out, RobotStats* st) {
  const std::size_t n = frame_utimes_.size();
  st->id = s.id;
  // 1. Ground truth and odometer at every frame.
  out->truth.resize(n);
  out->odometer.resize(n);
  std::size_t hint = 0;
  for (std::size_t k = 0; k < n; ++k) interpolate(s.ground_truth, frame_utimes_[k], &out->truth[k], &hint);
  std::vector<Command> delayed;
  const std::int64_t delay_us = std::llround(options_.odometry_delay_s * 1e6);
  if (delay_us > 0) {
    delayed = s.odometry;
    for (Command& c : delayed) c.utime += delay_us;
  }
  const std::vector<Command>& commands = delay_us > 0 ? delayed : s.odometry;
  OdometryIntegrator odo(commands, frame_utimes_[0], out->truth[0]);
  for (std::size_t k = 0; k < n; ++k) out->odometer[k] = odo.advance_to(frame_utimes_[k]);
  // 2. Odometry gaps; 3. the observations of every frame.
  count_odometry_gaps(s, st);
  bin_observations(d, s, commands, out, st);
}

// Odometry gaps over half a second overlapping [t_0, t_last].
void FrameSource::count_odometry_gaps(const RobotSeries& s, RobotStats* st) const {
  for (std::size_t i = 0; i + 1 < s.odometry.size(); ++i) {
    const std::int64_t a = s.odometry[i].utime, b = s.odometry[i + 1].utime;
    if (b <= frame_utimes_.front() || a >= frame_utimes_.back()) continue;
    const double gap = seconds(b - a);
    if (gap > 0.5) {
      ++st->odometry_gaps;
      st->max_odometry_gap_s = std::max(st->max_odometry_gap_s, gap);
    }
  }
}

// Observations binned into frames by time (t_{k-1}, t_k], filtered (misreads, the
// robot's own barcode, other robots' unless kept), de-duplicated per frame (the
// later reading wins), range-calibrated, and, with motion compensation, moved to
// where the robot is at t_k.
void FrameSource::bin_observations(const Dataset& d, const RobotSeries& s, const std::vector<Command>& commands,
                                   PerRobot* out, RobotStats* st) const {
  const std::size_t n = frame_utimes_.size();
  const std::int64_t period_us = std::llround(1e6 / options_.rate_hz);
  const int own_barcode = d.barcode_of_subject(s.id);
  out->obs_begin.assign(n + 1, 0);
  out->obs.clear();
  std::size_t m = 0;
  const auto& ms = s.measurements;
  const std::int64_t lower = frame_utimes_[0] - period_us;
  while (m < ms.size() && ms[m].utime <= lower) ++m;
  // Relative motion for the compensation: dead reckoning from `lower` (the start
  // pose does not matter, only motion between two times).
  OdometryIntegrator rel(commands, lower, Pose2{});
  std::vector<Pose2> taken_at;  // pose at each kept measurement of the frame
  for (std::size_t k = 0; k < n; ++k) {
    const auto begin = static_cast<int>(out->obs.size());
    out->obs_begin[k] = begin;
    taken_at.clear();
    for (; m < ms.size() && ms[m].utime <= frame_utimes_[k]; ++m) {
      const Measurement& z = ms[m];
      const Pose2 pose_m = options_.motion_compensation ? rel.advance_to(z.utime) : Pose2{};
      ++st->measurements;
      const int subject = d.subject_of_barcode(z.barcode);
      if (subject == 0 || z.barcode == own_barcode || !(z.range > 0.0)) {
        ++st->misreads;
        continue;
      }
      if (subject <= kMaxRobotSubject) {
        ++st->robot_barcodes;
        if (!options_.with_robot_barcodes) continue;
      }
      for (auto it = out->obs.begin() + begin; it != out->obs.end(); ++it)
        if (it->subject == subject) {
          taken_at.erase(taken_at.begin() + (it - (out->obs.begin() + begin)));
          out->obs.erase(it);
          ++st->duplicates;
          break;
        }
      const double bearing = wrap_if_needed(z.bearing);
      const double scale = 1.0 + options_.range_scale_k0 + options_.range_scale_k1 * bearing * bearing;
      out->obs.push_back({subject, scale > 0.1 ? z.range / scale : z.range, bearing});
      taken_at.push_back(pose_m);
    }
    if (options_.motion_compensation) {
      const Pose2 pose_k = rel.advance_to(frame_utimes_[k]);
      for (std::size_t j = 0; j < taken_at.size(); ++j) {
        Obs& o = out->obs[static_cast<std::size_t>(begin) + j];
        const Eigen::Vector2d p_m(o.range * std::cos(o.bearing), o.range * std::sin(o.bearing));
        const Eigen::Vector2d p_k = transform_from(between(pose_k, taken_at[j]), p_m);
        if (!(p_k.norm() > 1e-6)) continue;  // at the sensor: keep the reading as taken
        o.range = p_k.norm();
        o.bearing = wrap_angle(std::atan2(p_k.y(), p_k.x()));
      }
    }
    // Distinct subjects per frame <= number of subjects (20) < 64: never truncated.
    const int count = static_cast<int>(out->obs.size()) - begin;
    if (count > contract::kMaxObsPerFrame) out->obs.resize(static_cast<std::size_t>(begin + contract::kMaxObsPerFrame));
  }
  out->obs_begin[n] = static_cast<int>(out->obs.size());
  st->used = static_cast<long>(out->obs.size());
}

std::int64_t FrameSource::frame_utime(int k) const {
  if (k < 0 || k >= num_frames_) throw std::out_of_range("mrclam: frame " + std::to_string(k) + " out of range");
  return frame_utimes_[static_cast<std::size_t>(k)];
}

const Pose2& FrameSource::odometer(int i, int k) const {
  return per_robot_.at(static_cast<std::size_t>(i)).odometer.at(static_cast<std::size_t>(k));
}

const Pose2& FrameSource::true_pose(int i, int k) const {
  return per_robot_.at(static_cast<std::size_t>(i)).truth.at(static_cast<std::size_t>(k));
}

void FrameSource::frame(int k, ground_truth_t* gt, std::vector<sensor_frame_t>* sensors) const {
  const std::int64_t utime = frame_utime(k);
  const auto kk = static_cast<std::size_t>(k);
  const std::size_t nr = per_robot_.size();
  if (gt) {
    gt->utime = utime;
    gt->frame = k;
    const int nl = static_cast<int>(landmarks_.size() + (options_.with_robot_barcodes ? nr : 0));
    contract::set_count(&gt->robot_ids, &gt->num_robots, static_cast<int>(nr));  // <= kMaxRobots (constructor)
    contract::set_count(&gt->robots, &gt->num_robots, static_cast<int>(nr));
    contract::set_count(&gt->landmarks, &gt->num_landmarks, nl);  // <= kMaxWorldLandmarks (constructor)
    for (std::size_t i = 0; i < nr; ++i) {
      const Pose2& T = per_robot_[i].truth[kk];
      gt->robot_ids[i] = static_cast<std::int16_t>(options_.robots[i]);
      gt->robots[i].x = T.x;
      gt->robots[i].y = T.y;
      gt->robots[i].theta = T.theta;
    }
    std::size_t l = 0;
    for (const LandmarkTruth& lm : landmarks_) gt->landmarks[l++] = {lm.subject, lm.x, lm.y, false};
    if (options_.with_robot_barcodes)
      for (std::size_t i = 0; i < nr; ++i)
        gt->landmarks[l++] = {options_.robots[i], per_robot_[i].truth[kk].x, per_robot_[i].truth[kk].y, true};
  }
  if (sensors) {
    sensors->resize(nr);
    for (std::size_t i = 0; i < nr; ++i) {
      const PerRobot& r = per_robot_[i];
      sensor_frame_t& m = (*sensors)[i];
      m = sensor_frame_t{};
      m.utime = utime;
      m.frame = k;
      m.robot_id = static_cast<std::int16_t>(options_.robots[i]);
      m.odom_x = r.odometer[kk].x;
      m.odom_y = r.odometer[kk].y;
      m.odom_theta = r.odometer[kk].theta;
      m.odom_var_trans_per_m = options_.odom_var_trans_per_m;
      m.odom_var_rot_per_rad = options_.odom_var_rot_per_rad;
      m.odom_var_rot_per_m = options_.odom_var_rot_per_m;
      const int b = r.obs_begin[kk], e = r.obs_begin[kk + 1];
      contract::set_count(&m.obs, &m.num_obs, e - b);
      for (int j = b; j < e; ++j) {
        const Obs& z = r.obs[static_cast<std::size_t>(j)];
        range_bearing_t& o = m.obs[static_cast<std::size_t>(j - b)];
        o.landmark_id = z.subject;
        o.range = z.range;
        o.bearing = z.bearing;
      }
    }
  }
}

OdometryFit fit_odometry(const FrameSource& src, int i, int first, int last, int window) {
  OdometryFit f;
  const int end = last < 0 ? src.num_frames() - 1 : std::min(last, src.num_frames() - 1);
  const int w = std::max(window, 1);
  const double dt = w * src.dt_s();
  double tr = 0.0, rr = 0.0;                               // translations: sum t.r, |r|^2
  double a00 = 0.0, a01 = 0.0, a11 = 0.0, y0 = 0.0, y1 = 0.0;  // headings: normal equations in (s_w, b)
  for (int k = std::max(first, 0) + w; k <= end; k += w) {
    const Pose2 r = between(src.odometer(i, k - w), src.odometer(i, k));
    const Pose2 t = between(src.true_pose(i, k - w), src.true_pose(i, k));
    tr += t.x * r.x + t.y * r.y;
    rr += r.x * r.x + r.y * r.y;
    a00 += r.theta * r.theta, a01 += r.theta * dt, a11 += dt * dt;
    y0 += t.theta * r.theta, y1 += t.theta * dt;
    f.reported_m += std::hypot(r.x, r.y);
    f.reported_rad += std::fabs(r.theta);
    ++f.steps;
  }
  if (rr > 0.0) f.speed_scale = tr / rr;
  if (a00 > 0.0) f.turn_scale_without_bias = y0 / a00;
  const double det = a00 * a11 - a01 * a01;
  if (det > 1e-12 * a00 * a11) {
    f.turn_scale = (y0 * a11 - y1 * a01) / det;
    f.turn_bias_rad_s = (a00 * y1 - a01 * y0) / det;
  } else {
    f.turn_scale = f.turn_scale_without_bias;
  }
  return f;
}

}  // namespace elaslam::mrclam

// SPDX-License-Identifier: Apache-2.0
// What a message (or a state file) may say and still be believed: the
// plausibility bounds every receiver applies after the contract's structural checks
// (contract.hpp), and the reasons a message is refused, counted per reason in
// STATUS (node_status_t.refused). One options struct, `limits:` in the robot and
// main sections of the config (docs/security.md, config/paper.yaml).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "elaslam/global_map_t.hpp"
#include "elaslam/pose_estimate_t.hpp"

namespace elaslam {

namespace config {
class Reader;
}

/// Why a message was refused; the index into node_status_t.refused (same order as
/// its REFUSED_* constants).
enum class Refusal : int {
  kMalformed = 0,    // the contract: counts, ids, kinds, finite numbers, ranges
  kImplausible = 1,  // decodes and is well formed but absurd: covariance or position out of bounds
  kOutsideTeam = 2,  // from (or about) a robot id that is not in limits.team
  kSeqWindow = 3,    // a seq jump not (yet) confirmed, or outside the window
  kFrameWindow = 4,  // a frame jump not (yet) confirmed, or outside the window
  kStale = 5,        // older than what was applied (an older snapshot, an older incarnation)
  kDuplicateId = 6,  // one landmark id twice in one message
  kOdometry = 7,     // an odometer increment the robot cannot have driven in the frames elapsed
};
constexpr int kNumRefusals = 8;
const char* to_string(Refusal r);

/// Refusals counted per reason.
struct RefusalCounts {
  std::array<std::int64_t, kNumRefusals> n{};
  void add(Refusal r) { ++n[static_cast<std::size_t>(r)]; }
  std::int64_t operator[](Refusal r) const { return n[static_cast<std::size_t>(r)]; }
  std::int64_t total() const;
  /// A refused input: counted here and in *rejected (a node's count of every input it
  /// refused), *why (when given) set to `problem`. False: what a handler returns for it.
  bool count(Refusal r, const std::string& problem, std::int64_t* rejected, std::string* why);
};

struct MessageLimits {
  /// [m] |x| and |y| of every position a message or state file carries (landmarks,
  /// robot poses, odometer readings). A bound on corruption, not the mission area.
  double world_bound = 1e4;
  /// [m^2] eigenvalues of a landmark's 2x2 position covariance must lie in
  /// [cov_floor, cov_ceiling]: below the floor a landmark would be pinned (a zero
  /// or denormal covariance outweighs every other robot's estimate, and 1e-320
  /// inverts to infinity); above the ceiling it says nothing. The same ceiling
  /// bounds the variances of a robot's 3x3 pose covariance (no floor there: a
  /// known start may be exact).
  double cov_floor = 1e-8;
  double cov_ceiling = 1e4;
  /// Bit r-1 set when robot r is in the team (limits.team, "1,2,3"; absent: every
  /// id 1..contract::kMaxRobots).
  static constexpr int kRobotIds = 16;  // = contract::kMaxRobots (limits.cpp checks)
  static constexpr int kAllRobots = (1 << kRobotIds) - 1;
  int team_mask = kAllRobots;

  bool in_team(int robot_id) const {
    return robot_id >= 1 && robot_id <= kRobotIds && ((team_mask >> (robot_id - 1)) & 1);
  }
};

/// Read the optional `limits:` map of a robot or main section.
void parse(config::Reader& r, MessageLimits* o);
/// "1,2,3" -> bits; false with `why` when not a list of distinct ids in
/// [1, contract::kMaxRobots].
bool parse_team(const std::string& text, int* mask, std::string* why);
std::string team_text(int mask);

/// What one config file's sections must agree on, whoever reads it (robot_node and
/// main_robot each parse their own section; a mismatch only shows at run time):
/// main.max_landmark_id at least robot.filter.max_landmark_id (else main refuses
/// every event about the ids between), and the two limits.team equal. Missing keys
/// are not checked (their own parse reports them). The problems, one per line.
std::vector<std::string> check_shared_config(const std::string& path);

/// The checks, each "" when fine, else the problem naming `field` and the value.
std::string check_position(double x, double y, const MessageLimits& l, const char* field);
std::string check_cov2(const double (&c)[2][2], const MessageLimits& l, const char* field);
std::string check_cov2(const Eigen::Matrix2d& c, const MessageLimits& l, const char* field);
/// A robot pose's covariance (x [m], y [m], theta [rad]): finite, symmetric, positive
/// semi-definite, variances at most cov_ceiling.
std::string check_pose_cov(const double (&c)[3][3], const MessageLimits& l, const char* field);

/// A POSE's content as every receiver checks it (main_robot, evaluate): frame not
/// negative, position within `l`, heading finite, covariance a covariance within `l`.
/// The robot id is the caller's (main: in its team; evaluate: in the contract).
std::string check_pose(const pose_estimate_t& p, const MessageLimits& l, Refusal* reason);

/// One GLOBAL_MAP chunk as every receiver checks it (robot_node before it takes the
/// moving set, evaluate before it scores a recording): the arrays match their counts;
/// frame at least -1 (-1: main_robot's map before any robot has finished a frame);
/// landmark ids not negative, ascending, each once, with positions and covariances
/// within `l`; moving ids in [0, max_moving_id), ascending, each once, moving_by 0 or
/// a member of l's team, moving frames not negative. "" when it holds, else the
/// problem (`reason` its kind).
std::string check_global_map(const global_map_t& m, const MessageLimits& l, int max_moving_id, Refusal* reason);

/// Sequence numbers are believed up to this value (2^62): far beyond any real
/// stream, and differences of two never overflow an int64.
constexpr std::int64_t kMaxSeq = std::int64_t{1} << 62;

/// A forward jump in a sequence (seq numbers, frames) that is not believed at once:
/// `next` is more than `window` ahead of `last`. The first such value is held as
/// a candidate and refused; the next value that continues it (within `window`
/// after the candidate, and not before it) confirms the jump. A single forged
/// far-future value therefore never blocks the real stream, which keeps arriving
/// within the window of `last`. int64 throughout: no overflow for any input.
class JumpGuard {
 public:
  enum class Verdict { kInWindow, kConfirmed, kHeld };
  /// `strictly_after`: the confirming value must be larger than the candidate
  /// (events); else equal is enough (the chunks of one snapshot share a seq).
  Verdict check(std::int64_t last, std::int64_t next, std::int64_t window, bool strictly_after = true);
  void clear() { pending_ = -1; }
  std::int64_t pending() const { return pending_; }

 private:
  std::int64_t pending_ = -1;
};

}  // namespace elaslam

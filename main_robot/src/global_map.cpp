// SPDX-License-Identifier: Apache-2.0
#include "elaslam/common/contract.hpp"
#include "elaslam/common/stats.hpp"
#include "elaslam/main_robot/global_map.hpp"

#include <algorithm>
#include <cstdlib>

#include <Eigen/Cholesky>

#include "elaslam/landmark_event_t.hpp"

namespace elaslam {

const char* to_string(EventResult r) {
  switch (r) {
    case EventResult::kApplied: return "applied";
    case EventResult::kAppliedAfterGap: return "applied_after_gap";
    case EventResult::kDuplicate: return "duplicate";
    case EventResult::kStale: return "stale";
  }
  return "?";
}

int GlobalEntry::contributors() const {
  int bits = 0;
  for (int r = 0; r < kMaxTeamRobots; ++r)
    if (by_robot[static_cast<std::size_t>(r)].valid) bits |= 1 << r;
  return bits;
}

GlobalMap::GlobalMap(const GlobalMapOptions& options)
    : options_(options),
      entries_(static_cast<std::size_t>(options.max_landmark_id)),
      team_check_d2_(options.team_map_check_probability > 0.0 ? chi2_quantile(options.team_map_check_probability, 2)
                                                              : 0.0) {
  for (auto& s : streams_) s.covered.assign(entries_.size(), 0);
}

void RobotStream::restart_repair(std::int64_t seq) {
  std::fill(covered.begin(), covered.end(), 0);
  covered_ids = 0;
  repair_seq = seq;
  gap_pending = true;
}

void RobotStream::cover(std::int64_t seq, int id_begin, int id_end) {
  if (!gap_pending || seq < repair_seq) return;
  for (int id = id_begin; id < id_end; ++id) {
    auto& bit = covered[static_cast<std::size_t>(id)];
    covered_ids += bit == 0;
    bit = 1;
  }
  if (covered_ids >= static_cast<int>(covered.size())) gap_pending = false;
}

IncarnationVerdict GlobalMap::observe_incarnation(int robot_id, std::int64_t incarnation, int frame) {
  RobotStream& s = streams_[static_cast<std::size_t>(robot_id - 1)];
  if (incarnation == s.incarnation || s.incarnation == 0) {
    s.incarnation = incarnation;
    s.incarnation_frame = std::max(s.incarnation_frame, frame);
    return IncarnationVerdict::kCurrent;
  }
  bool back = false;
  // (The replaced incarnation is no challenger: it came before the one followed; its
  // datagrams are late ones or a second sender's, below.)
  if (incarnation < s.incarnation && incarnation != s.previous_incarnation) {
    if (incarnation != s.challenger) s.challenger = incarnation, s.challenger_frame = -1, s.challenger_heard = 0;
    if (frame > s.challenger_frame) s.challenger_frame = frame, ++s.challenger_heard;
    back = s.challenger_heard >= 3 && frame > s.incarnation_frame + kQuietFrames;
  }
  if (incarnation > s.incarnation || back) {  // restarted without its state: a new stream
    s.previous_incarnation = s.incarnation;
    s.previous_frame = s.incarnation_frame;
    s.incarnation_frame = frame;
    s.incarnation = incarnation;
    s.last_seq = 0;
    s.snapshot_seq = 0;
    s.snapshot_frame = -1;
    s.previous_heard = 0;
    s.challenger = 0;
    s.challenger_frame = -1;
    s.challenger_heard = 0;
    s.restarted_back = back;
    ++s.restarts;
    s.restart_repair(0);
    return IncarnationVerdict::kRestarted;
  }
  ++s.stale_incarnation;
  // The replaced incarnation heard again. Its datagrams still on their way when it
  // was replaced (a dead process's last frames, late) carry frames it had reached;
  // a second live sender goes on to new ones: three new frames are two senders.
  if (incarnation == s.previous_incarnation && frame > s.previous_frame) {
    s.previous_frame = frame;
    if (++s.previous_heard >= 3) s.duplicate_until_frame = std::max(newest_frame_, frame) + 50;
  }
  // An older one that keeps pace with the followed one (frames within kQuietFrames of
  // its: not a replay of old frames): a second live sender too.
  if (incarnation == s.challenger && s.challenger_heard >= 3 &&
      std::abs(s.incarnation_frame - s.challenger_frame) <= kQuietFrames)
    s.duplicate_until_frame = std::max(newest_frame_, frame) + 50;
  return IncarnationVerdict::kStale;
}

bool GlobalMap::duplicate_sender(int robot_id) const {
  const RobotStream& s = streams_[static_cast<std::size_t>(robot_id - 1)];
  return s.duplicate_until_frame >= 0 && newest_frame_ <= s.duplicate_until_frame;
}

int GlobalMap::count(GlobalStatus s) const {
  int n = 0;
  for (const auto& g : entries_) n += g.status == s;
  return n;
}

// Information-weighted fusion treats the robots' estimates as independent; they
// are not quite (robots that share a map share its errors), so covariance
// intersection is the conservative option. Its weights follow the fast
// trace-based rule w_r ~ 1/tr(C_r) (Niehsen 2002) rather than an optimisation.
namespace {

// Information fusion of the valid estimates but those of the robots in `skip` (bit
// r-1; 0: none), or their covariance intersection with weights by trace. False when
// none is usable.
bool fuse_estimates(const std::array<RobotEstimate, kMaxTeamRobots>& by_robot, Fusion fusion, unsigned skip,
                    Eigen::Vector2d* position, Eigen::Matrix2d* cov) {
  const auto skipped = [skip](std::size_t r) { return ((skip >> r) & 1u) != 0; };
  Eigen::Matrix2d info = Eigen::Matrix2d::Zero();
  Eigen::Vector2d eta = Eigen::Vector2d::Zero();
  double wsum = 0.0;
  for (std::size_t r = 0; r < by_robot.size(); ++r)
    if (by_robot[r].valid && !skipped(r)) wsum += 1.0 / std::max(by_robot[r].cov.trace(), 1e-12);
  for (std::size_t r = 0; r < by_robot.size(); ++r) {
    const RobotEstimate& e = by_robot[r];
    if (!e.valid || skipped(r)) continue;
    const Eigen::LLT<Eigen::Matrix2d> llt(e.cov);
    if (llt.info() != Eigen::Success) continue;
    double w = 1.0;
    if (fusion == Fusion::kCovarianceIntersection) w = (1.0 / std::max(e.cov.trace(), 1e-12)) / wsum;
    const Eigen::Matrix2d Ci = w * llt.solve(Eigen::Matrix2d::Identity());
    info += Ci;
    eta += Ci * e.position;
  }
  const Eigen::LLT<Eigen::Matrix2d> llt(info);
  if (llt.info() != Eigen::Success) return false;
  *cov = llt.solve(Eigen::Matrix2d::Identity());
  *position = *cov * eta;
  return true;
}

}  // namespace

bool GlobalMap::fuse(GlobalEntry& g) const {
  // No usable estimate: keep the last fused one.
  return fuse_estimates(g.by_robot, options_.fusion, 0u, &g.fused, &g.fused_cov);
}

unsigned GlobalMap::check_team() {
  left_out_ = 0;
  for (auto& t : team_check_) {
    t.shared = 0;
    t.disagree = 0;
  }
  if (!(team_check_d2_ > 0.0)) return 0;
  for (const GlobalEntry& g : entries_) {
    if (g.status != GlobalStatus::kStatic) continue;
    // Each robot's estimate against the fusion of the others' (independent: each
    // robot's own filter), chi-square with 2 dof.
    for (std::size_t q = 0; q < g.by_robot.size(); ++q) {
      const RobotEstimate& e = g.by_robot[q];
      Eigen::Vector2d p;
      Eigen::Matrix2d C;
      if (!e.valid || !fuse_estimates(g.by_robot, options_.fusion, 1u << q, &p, &C)) continue;
      const Eigen::LLT<Eigen::Matrix2d> llt(C + e.cov);
      if (llt.info() != Eigen::Success) continue;
      const Eigen::Vector2d d = e.position - p;
      ++team_check_[q].shared;
      if (d.dot(llt.solve(d)) > team_check_d2_) ++team_check_[q].disagree;
    }
  }
  for (std::size_t q = 0; q < team_check_.size(); ++q) {
    TeamCheck& t = team_check_[q];
    if (!(t.shared >= kTeamCheckMinShared && 2 * t.disagree > t.shared)) continue;
    left_out_ |= 1u << q;
    ++t.rounds_left_out;
  }
  return left_out_;
}

std::int64_t GlobalMap::rounds_left_out() const {
  std::int64_t n = 0;
  for (const TeamCheck& t : team_check_) n += t.rounds_left_out;
  return n;
}

bool GlobalMap::fused_without(int id, int robot_id, Eigen::Vector2d* position, Eigen::Matrix2d* cov) const {
  if (id < 0 || id >= max_landmark_id()) return false;
  Eigen::Vector2d p;
  Eigen::Matrix2d C;
  const unsigned own = robot_id >= 1 && robot_id <= kMaxTeamRobots ? 1u << (robot_id - 1) : 0u;
  const unsigned skip = left_out_ | own;
  if (!fuse_estimates(entries_[static_cast<std::size_t>(id)].by_robot, options_.fusion, skip, &p, &C)) return false;
  *position = p;
  *cov = C;
  return true;
}

void GlobalMap::remove_as_moving(int id, int robot_id, int frame, std::vector<Notice>* notices, bool unconfirmed) {
  GlobalEntry& g = entries_[static_cast<std::size_t>(id)];
  if (g.status == GlobalStatus::kMoving) {  // already known: idempotent, no second notice...
    if (unconfirmed || !g.moving_unconfirmed) return;
    // ...unless only an opinion of unknown age had it moving: this finding confirms
    // it, and the robots hear of it now (no notice went out for the opinion).
    g.moving_unconfirmed = false;
    g.status_frame = frame;
    g.moving_by = robot_id;
    if (notices) notices->push_back({id, robot_id, frame});
    ++version_;
    return;
  }
  g.status = GlobalStatus::kMoving;
  g.status_frame = frame;
  g.moving_by = robot_id;
  g.moving_unconfirmed = unconfirmed;
  for (auto& e : g.by_robot) e.valid = false;  // deleted from the map
  if (notices && !unconfirmed) notices->push_back({id, robot_id, frame});
  ++version_;
}

int GlobalMap::occupy(int robot_id, int frame, const Eigen::Vector2d& position, const Eigen::Matrix2d& cov,
                      std::vector<Notice>* notices) {
  const double radius = options_.body_radius_m;
  if (!(radius > 0.0)) return 0;
  int found = 0;
  for (int id = 0; id < max_landmark_id(); ++id) {
    const GlobalEntry& g = entries_[static_cast<std::size_t>(id)];
    if (g.status != GlobalStatus::kStatic) continue;
    // Closer than the body, and the estimates sharp enough to tell: a robot whose
    // pose is uncertain (or a landmark seen once from afar) proves nothing.
    if ((g.fused - position).squaredNorm() >= radius * radius) continue;
    if ((cov + g.fused_cov).trace() / 2.0 >= radius * radius) continue;
    remove_as_moving(id, robot_id, frame, notices);
    ++found;
  }
  return found;
}

bool GlobalMap::missed_events(int robot_id, std::int64_t seq) {
  RobotStream& s = streams_[static_cast<std::size_t>(robot_id - 1)];
  if (seq <= s.last_seq) return false;  // all in
  ++s.gaps;
  s.start_repair(seq);  // a snapshot taken after them
  return true;
}

EventResult GlobalMap::apply(const GlobalEvent& e, std::vector<Notice>* notices) {
  RobotStream& s = streams_[static_cast<std::size_t>(e.robot_id - 1)];
  if (e.seq <= s.last_seq) {
    ++s.duplicates;
    return e.seq == s.last_seq ? EventResult::kDuplicate : EventResult::kStale;
  }
  const bool gap = e.seq > s.last_seq + 1;
  if (gap) {
    ++s.gaps;
    s.start_repair(e.seq - 1);  // a snapshot taken after the lost events
  }
  s.last_seq = e.seq;
  s.last_frame = std::max(s.last_frame, e.frame);
  newest_frame_ = std::max(newest_frame_, e.frame);

  GlobalEntry& g = entries_[static_cast<std::size_t>(e.landmark_id)];
  if (e.kind == landmark_event_t::MOVING) {
    remove_as_moving(e.landmark_id, e.robot_id, e.frame, notices);
  } else {
    RobotEstimate& est = g.by_robot[static_cast<std::size_t>(e.robot_id - 1)];
    // While it is MOVING (confirmed), an ADD or UPDATE may be of where it was before
    // it moved (sent before the robot had the notice): kept, but out of the fusion,
    // also after a RETURN. The robot's next estimate counts again.
    const bool held_out =
        g.status == GlobalStatus::kMoving && !g.moving_unconfirmed && e.kind != landmark_event_t::RETURN;
    est = {!held_out, e.position, e.cov, e.frame};
    if (g.status == GlobalStatus::kAbsent) g.history_unknown = s.gap_pending;
    // While MOVING, estimates are kept but the landmark stays out until a RETURN
    // (or, for an unconfirmed moving status, any robot's estimate: see GlobalEntry).
    if (g.status == GlobalStatus::kAbsent || e.kind == landmark_event_t::RETURN || g.moving_unconfirmed) {
      if (g.status != GlobalStatus::kStatic) g.status_frame = e.frame;
      g.status = GlobalStatus::kStatic;
      g.moving_unconfirmed = false;
    }
    if (g.status == GlobalStatus::kStatic) fuse(g);
    ++version_;
  }
  return gap ? EventResult::kAppliedAfterGap : EventResult::kApplied;
}

bool GlobalMap::apply_snapshot(int robot_id, std::int64_t seq, int frame, int id_begin, int id_end,
                               const std::vector<std::pair<int, RobotEstimate>>& lms, const std::vector<int>& moving_ids,
                               const std::vector<int>& moving_frames, std::vector<Notice>* notices) {
  RobotStream& s = streams_[static_cast<std::size_t>(robot_id - 1)];
  const std::size_t r = static_cast<std::size_t>(robot_id - 1);
  // An older snapshot than one applied (lower seq, or the same seq and an older
  // frame: no events between them) would roll the map back.
  // So would one older than r's events applied here (a chunk delayed past the next
  // frame's events): a snapshot holds r's map as of its seq.
  if (seq < s.snapshot_seq || (seq == s.snapshot_seq && frame < s.snapshot_frame) || seq < s.last_seq) return false;
  s.snapshot_seq = seq;
  s.snapshot_frame = frame;
  // Events of r this map has not seen: a gap on r's event stream, or a snapshot
  // ahead of r's last applied event (a restarted main_robot: empty, or resumed from
  // a state file up to state_save_interval_s old). Those events may have been
  // MOVING or RETURN: the snapshot's lists stand in for them, chunk by chunk.
  if (seq > s.last_seq) s.start_repair(seq);
  const bool missed = s.gap_pending;
  // Moving ids first: a MOVING event lost in a gap is recovered here.
  if (missed) {
    for (std::size_t k = 0; k < moving_ids.size(); ++k) {
      const int id = moving_ids[k];
      const int found = k < moving_frames.size() ? moving_frames[k] : -1;  // -1: unknown
      const GlobalEntry& g = entries_[static_cast<std::size_t>(id)];
      if (g.status == GlobalStatus::kMoving || g.status_frame > frame) continue;
      const bool newer = g.status == GlobalStatus::kStatic && found > g.status_frame;
      if (g.by_robot[r].valid || newer ||
          (g.status == GlobalStatus::kStatic && !g.history_unknown && g.moving_by == 0)) {
        // r held it here and now lists it as moving, r found it moving after this map
        // last changed its status, or it has never moved as far as this map knows
        // (events or the state file): r's MOVING event was lost. Stamped with the
        // frame r found it moving, when listed: robots compare it with their own view.
        remove_as_moving(id, robot_id, found >= 0 ? std::min(found, frame) : frame, notices);
      } else if (g.contributors() == 0) {
        // r's opinion of unknown age, about a landmark no robot holds here (also one
        // this map has not seen: its ADD was lost too, as after a restart).
        remove_as_moving(id, robot_id, frame, notices, /*unconfirmed=*/true);
      }
      // Else another robot holds it static since before r's finding, or r's finding
      // is of unknown age: r's listing may be stale (a robot lists a landmark as moving
      // until it sees it again, after others took it back).
    }
  }
  for (int id = id_begin; id < id_end; ++id) entries_[static_cast<std::size_t>(id)].by_robot[r].valid = false;
  for (const auto& [id, est] : lms) {
    GlobalEntry& g = entries_[static_cast<std::size_t>(id)];
    g.by_robot[r] = est;
    g.by_robot[r].valid = true;
    // r holds as static a landmark this map has as moving: r took it back after it
    // moved (a robot drops a landmark it learns is moving, by its own test or a
    // notice, before its next frame) and its RETURN was lost; or the moving status
    // is an unconfirmed one (above), which any robot's static holding overrides.
    const bool returned = missed && g.status == GlobalStatus::kMoving && g.status_frame < frame;
    const bool overridden = g.status == GlobalStatus::kMoving && g.moving_unconfirmed && g.status_frame <= frame;
    if (g.status == GlobalStatus::kAbsent) g.history_unknown = missed;
    if (g.status == GlobalStatus::kAbsent || returned || overridden) {
      g.status = GlobalStatus::kStatic;
      g.status_frame = frame;
      g.moving_unconfirmed = false;
    }
    // Still MOVING: r's estimate may predate the move; out of the fusion (as events).
    if (g.status == GlobalStatus::kMoving && !g.moving_unconfirmed) g.by_robot[r].valid = false;
  }
  for (int id = id_begin; id < id_end; ++id) {
    GlobalEntry& g = entries_[static_cast<std::size_t>(id)];
    if (g.status == GlobalStatus::kStatic) fuse(g);
  }
  s.last_seq = std::max(s.last_seq, seq);
  s.cover(seq, id_begin, id_end);
  s.last_frame = std::max(s.last_frame, frame);
  newest_frame_ = std::max(newest_frame_, frame);
  ++version_;
  return true;
}

}  // namespace elaslam

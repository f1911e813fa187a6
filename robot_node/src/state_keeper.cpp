// SPDX-License-Identifier: Apache-2.0
#include "elaslam/robot_node/state_keeper.hpp"

#include <algorithm>
#include <cstdio>
#include <utility>

#include "elaslam/common/atomic_file.hpp"
#include "elaslam/common/log.hpp"
#include "elaslam/robot_node/robot_state.hpp"

namespace elaslam {
namespace {

// More event seq numbers than a robot can send in any save interval (at most
// Robot::event_capacity, 3 x 64 + capacity + 8, events a frame).
constexpr std::int64_t kResumeSeqSkip = std::int64_t{1} << 24;

}  // namespace

bool resume_state(const std::string& path, std::int64_t incarnation, std::uint64_t mission, RobotNode* node) {
  node->set_incarnation(incarnation);
  if (path.empty()) return false;
  std::string text, why;
  bool missing = false;
  if (!files::read_all(path, &text, &why, &missing)) {
    if (!missing)
      log::print(stderr, log::Priority::kWarning, "robot_node %d: cannot read state %s: %s; starting fresh\n",
                 node->robot_id(), path.c_str(), why.c_str());
    return false;
  }
  if (load_robot_state(text, node, &why, mission)) {
    // The events sent after the last save carried the next seq numbers, and
    // main_robot has them: numbering on from the file would have them refused as
    // stale. Jump ahead instead: main_robot sees one gap, asks for a snapshot
    // (LMAP_RESYNC) and refuses none of this run's events.
    node->skip_seq(kResumeSeqSkip);
    // Saved at once, before anything is sent: killed again before its first save, the
    // next resume would reuse this run's seq numbers, and main_robot would take its
    // events for duplicates of this run's and see no gap to repair.
    save_state(path, *node, mission);
    std::fprintf(stderr, "robot_node %d: resumed from %s at frame %d, %d landmarks, seq %lld (incarnation %lld)\n",
                 node->robot_id(), path.c_str(), node->robot().last_frame(), node->robot().filter().num_landmarks(),
                 (long long)node->event_seq(), (long long)node->incarnation());
    return true;
  }
  const std::string aside = path + ".corrupt";
  const bool moved = std::rename(path.c_str(), aside.c_str()) == 0;
  log::print(stderr, log::Priority::kWarning,
             "robot_node %d: state file %s is corrupt: %s; %s, starting fresh\n", node->robot_id(), path.c_str(),
             why.c_str(), moved ? ("moved aside to " + aside).c_str() : "could not move it aside");
  return false;
}

void save_state(const std::string& path, RobotNode& node, std::uint64_t mission) {
  std::string why;
  const bool ok = files::write_atomic(path, save_robot_state(node, mission), &why);
  node.note_save(ok, path + ": " + why);
  if (const std::string alert = node.take_alert(); !alert.empty())
    log::print(stderr, log::Priority::kWarning, "robot_node %d: %s\n", node.robot_id(), alert.c_str());
}


StateKeeper::StateKeeper(std::string path, const RobotOptions& o, RobotNode* node, bool resumed,
                         std::int64_t incarnation, std::uint64_t mission)
    : path_(std::move(path)), options_(o), node_(node), watching_(resumed), next_incarnation_(incarnation + 1),
      mission_(mission),
      period_(std::chrono::microseconds(static_cast<std::int64_t>(o.state_save_interval_s * 1e6))),
      next_save_(Clock::now()), saved_frames_(node->counters().frames), frames_at_start_(saved_frames_),
      refused_at_start_(refused()) {}

void StateKeeper::turn() {
  if (watching_ && !path_.empty()) check_fit();
  check_source();
  if (path_.empty()) return;
  const auto now = Clock::now();
  if (now < next_save_ || node_->counters().frames == saved_frames_) return;
  save_state(path_, *node_, mission_);
  saved_frames_ = node_->counters().frames;
  next_save_ = now + period_;
}

std::int64_t StateKeeper::refused() const {
  const RobotNodeCounters& c = node_->counters();
  return c.frames_out_of_order + c.frames_duplicate + c.rejected_inputs;
}

void StateKeeper::check_fit() {
  if (node_->counters().frames != frames_at_start_) {  // a frame continued the state: it fits
    watching_ = false;
    return;
  }
  if (refused() - refused_at_start_ < kMisfitFrames) return;
  log::print(stderr, log::Priority::kWarning,
             "robot_node %d: the state of %s (frame %d) does not fit the frames arriving (%lld refused, "
             "none processed): starting fresh\n", node_->robot_id(), path_.c_str(), node_->robot().last_frame(),
             (long long)kMisfitFrames);
  start_fresh();
}

// A fresh node with a new incarnation, larger than this start's and any resumed one
// (main_robot takes its stream for a restart).
void StateKeeper::start_fresh() {
  const std::int64_t next = std::max(next_incarnation_, node_->incarnation() + 1);
  *node_ = RobotNode(options_, node_->robot_id());
  node_->set_incarnation(next);
  next_incarnation_ = next + 1;
  watching_ = false;
}

// A sensor source that started over while the node ran (kMisfitFrames frames older
// than the last processed and none processed since, RobotNode::frames_behind): a
// new run. The old map and frames are of the old one: start fresh, with a new
// incarnation (so main_robot takes the new stream for a restart). A replayed old
// recording does the same (the team key refuses one, docs/security.md).
void StateKeeper::check_source() {
  if (node_->frames_behind() < kMisfitFrames) return;
  log::print(stderr, log::Priority::kWarning,
             "robot_node %d: the sensor frames started over (%d in a row older than frame %d, none "
             "processed): a new run, starting fresh\n", node_->robot_id(), node_->frames_behind(),
             node_->robot().last_frame());
  start_fresh();
}

}  // namespace elaslam

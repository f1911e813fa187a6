// SPDX-License-Identifier: Apache-2.0
#include "elaslam/simulator/lockstep.hpp"

#include <algorithm>
#include <set>
#include <string>

#include "elaslam/common/channels.hpp"
#include "elaslam/node_status_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/simulator/scheduler.hpp"

namespace elaslam::sim {

LockstepWaiter::LockstepWaiter(transport::NodeShell& shell, const std::vector<int>& robot_ids)
    : shell_(shell), newest_(robot_ids.size(), -1) {
  for (std::size_t i = 0; i < robot_ids.size(); ++i) {
    const int id = robot_ids[i];
    inputs_.push_back(shell_.subscribe<pose_estimate_t>(
        channels::pose(id, shell_.suffix()),
        [this, i](const pose_estimate_t& m, const std::string&) { newest_[i] = std::max(newest_[i], int(m.frame)); },
        kPoseQueue,
        [id](const pose_estimate_t& m, const std::string& channel) {
          if (m.robot_id != id) return channel + " carries robot " + std::to_string(m.robot_id) + "'s pose";
          return m.frame < 0 ? channel + " with a negative frame" : std::string();
        }));
  }
}

bool LockstepWaiter::wait(int k, int timeout_ms) {
  const std::int64_t end = mono_ns() + timeout_ms * kNsPerMs;
  while (!std::all_of(newest_.begin(), newest_.end(), [k](int f) { return f >= k; })) {
    const std::int64_t left_ns = end - mono_ns();
    if (left_ns <= 0 || shell_.stop_requested()) return false;
    shell_.alive();  // waiting is the loop too: a watchdog ping when due
    const int ms = static_cast<int>(std::min<std::int64_t>((left_ns + kNsPerMs - 1) / kNsPerMs, 50));
    if (shell_.transport().handle_timeout(ms) < 0) {
      if (!shell_.stop_requested()) ++transport_errors_;
      return false;
    }
  }
  return true;
}

std::int64_t LockstepWaiter::rejected() const {
  std::int64_t n = 0;
  for (int in : inputs_) n += shell_.input_counters(in).refused;
  return n;
}

std::int64_t LockstepWaiter::decode_errors() const {
  std::int64_t n = 0;
  for (int in : inputs_) n += shell_.input_counters(in).decode_errors;
  return n;
}

bool wait_for_nodes(transport::NodeShell& shell, int n, int timeout_ms) {
  std::set<std::string> seen;
  const int input = shell.subscribe<node_status_t>(
      "STATUS_(ROBOT_[0-9]+|MAIN)" + shell.suffix(), [&seen](const node_status_t&, const std::string& ch) { seen.insert(ch); },
      transport::kTransportDefaultQueue);
  const std::int64_t end = mono_ns() + static_cast<std::int64_t>(timeout_ms) * kNsPerMs;
  while (static_cast<int>(seen.size()) < n && mono_ns() < end && !shell.stop_requested()) {
    shell.alive();
    shell.transport().handle_timeout(20);
  }
  shell.unsubscribe(input);
  if (static_cast<int>(seen.size()) >= n) {
    shell.say(std::to_string(n) + " nodes ready");
    return true;
  }
  shell.say("only " + std::to_string(seen.size()) + " of " + std::to_string(n) + " nodes announced themselves within " +
            std::to_string(timeout_ms) + " ms", log::Priority::kErr);
  return false;
}

}  // namespace elaslam::sim

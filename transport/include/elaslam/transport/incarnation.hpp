// SPDX-License-Identifier: Apache-2.0
// A process's incarnation: a number larger at each start of the same node, that does
// not come from the wall clock (docs/security.md "Incarnations"). Receivers tell a
// restarted sender from a replay of its old messages by it (auth_transport.hpp) and
// main_robot a restarted robot's new event stream (landmark_event_t.incarnation).
//
//   incarnation = start count << 20 | 20 random bits
//
// The start count is kept beside the node's state file (PATH.starts: the number of
// starts so far, written before the node sends anything), so it grows across
// restarts and reboots, whatever the clock says. A node without a state file counts
// in milliseconds since the machine booted instead (CLOCK_BOOTTIME: not moved by
// date, NTP or a clock set back; it starts over only at a reboot). The random bits
// tell apart two processes started with one count (a duplicated node).
// A sender whose incarnation went back anyway (a state directory lost, a reboot
// without a state file) is taken once its older incarnations have gone quiet
// (auth::kQuietUs; main_robot's rule: GlobalMap::observe_incarnation).
#pragma once

#include <cstdint>
#include <string>

namespace elaslam::transport {

constexpr int kIncarnationRandomBits = 20;

/// A new incarnation for this start. With `state_path` (not ""), PATH.starts is read,
/// incremented and written atomically; when that fails (a read-only or full disk, a
/// damaged file), the boot clock's count is used and *note (optional) says why, as it
/// says which count was used. The result is positive and below 2^62.
std::int64_t start_incarnation(const std::string& state_path, std::string* note = nullptr);

/// The start count an incarnation was made from (its bits above the random ones).
inline std::int64_t incarnation_count(std::int64_t incarnation) { return incarnation >> kIncarnationRandomBits; }

}  // namespace elaslam::transport

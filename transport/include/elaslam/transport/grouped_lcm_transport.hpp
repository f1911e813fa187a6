// SPDX-License-Identifier: Apache-2.0
// LCM with channel groups (team.channel_groups; docs/adr/0037-channel-groups.md).
// One udpm:// LCM instance per group of channels (channels.hpp, channel_group), each on
// its own port: the base URL's port + the group's number. LCM 1.3.1 binds its receive
// socket to INADDR_ANY:port, so groups must differ in port, not in multicast address,
// to be isolated (LCM.md). A process then joins only the ports of the channels it
// subscribes to, and the kernel wakes it only for those: a robot no longer wakes for
// the other robots' SENSOR and POSE, the events or the ground truth.
//
// Instances are opened when first needed (a publish or a subscribe on their group);
// LCM opens an instance's receive socket and thread only at its first subscription,
// so a group a process only publishes on costs it nothing on receipt.
// handle_timeout() polls the receiving instances' descriptors and handles one message
// from each that is ready. Order is kept within a group (one socket), not across
// groups, as between any two senders.
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>

#include "elaslam/transport/transport.hpp"

namespace elaslam::transport {

/// "udpm://GROUP:PORT?OPTIONS" with the port moved by `offset`; "" (with *why set) when
/// `url` is not udpm:// with an explicit or default port, or the port would pass 65535.
/// An empty `url` is LCM's default, udpm://239.255.76.67:7667?ttl=0.
std::string group_url(const std::string& url, int offset, std::string* why);

/// The groups (channel_group numbers) whose channels, with `suffix`, the regular
/// expression `pattern` matches as a whole, as bits of the result; a pattern that
/// matches no known channel gets kGroupTeam, where unknown channels go.
std::uint32_t groups_of_pattern(const std::string& pattern, const std::string& suffix);

class GroupedLcmTransport final : public Transport {
 public:
  /// `url`: the base URL (udpm:// only; "" is LCM's default); `suffix`: the team's
  /// channel suffix, which channel names carry. Not good() when the URL is not udpm://,
  /// leaves no room for every group's port, or the base group cannot be opened.
  /// `who`, `log`: as LcmTransport's, for every group.
  GroupedLcmTransport(const std::string& url, std::string suffix, std::string who = "LCM", std::FILE* log = nullptr);
  ~GroupedLcmTransport() override;

  bool good() const override;
  const char* kind() const override { return "LCM (channel groups)"; }
  bool publish(const std::string& channel, const void* data, std::size_t size) override;
  int subscribe(const std::string& pattern, RawHandler handler, void* context, int queue_capacity) override;
  void unsubscribe(int id) override;
  int handle_timeout(int timeout_ms) override;
  TransportRefusals refusals() const override;  // summed over the groups
  bool channel_groups() const override { return true; }

  /// Why the transport is not good(); "" when it is.
  const std::string& error() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace elaslam::transport

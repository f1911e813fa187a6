// SPDX-License-Identifier: Apache-2.0
#include "elaslam/transport/grouped_lcm_transport.hpp"

#include <poll.h>
#include <regex.h>

#include <array>
#include <vector>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/contract.hpp"
#include "elaslam/transport/lcm_transport.hpp"

namespace elaslam::transport {

static_assert(channels::kMaxGroupRobotId == contract::kMaxRobots, "one port group per possible robot id");
static_assert(channels::kChannelGroups <= 32, "groups_of_pattern returns a 32-bit set");

namespace {

constexpr const char* kDefaultUrl = "udpm://239.255.76.67:7667?ttl=0";  // LCM 1.3.1's default (LCM.md)

/// Every channel name of the system with `suffix` (robot ids 1..kMaxGroupRobotId): what
/// a subscription pattern is matched against to find its groups.
std::vector<std::string> known_channels(const std::string& suffix) {
  std::vector<std::string> names;
  for (std::string_view n : channels::kTeamNames) names.push_back(std::string(n) + suffix);
  for (int r = 1; r <= channels::kMaxGroupRobotId; ++r)
    for (std::string_view p : channels::kRobotPrefixes)
      names.push_back(std::string(p) + std::to_string(r) + suffix);
  return names;
}

}  // namespace

std::string group_url(const std::string& url, int offset, std::string* why) {
  const std::string u = url.empty() ? kDefaultUrl : url;
  const std::string scheme = "udpm://";
  if (u.compare(0, scheme.size(), scheme) != 0) {
    *why = "channel groups need a udpm:// URL, got '" + u + "'";
    return "";
  }
  const std::size_t q = u.find('?');
  const std::string address = u.substr(scheme.size(), q == std::string::npos ? std::string::npos : q - scheme.size());
  const std::string options = q == std::string::npos ? "" : u.substr(q);
  const std::size_t colon = address.rfind(':');
  const std::string group = colon == std::string::npos ? address : address.substr(0, colon);
  long port = 7667;  // LCM's default port when the URL names none
  if (colon != std::string::npos) {
    const std::string digits = address.substr(colon + 1);
    if (digits.empty() || digits.size() > 5 || digits.find_first_not_of("0123456789") != std::string::npos) {
      *why = "not a port in the LCM URL '" + u + "': '" + digits + "'";
      return "";
    }
    port = std::stol(digits);
  }
  if (group.empty()) {
    *why = "no multicast address in the LCM URL '" + u + "'";
    return "";
  }
  if (port < 1 || port + channels::kChannelGroups - 1 > 65535) {
    *why = "channel groups use ports " + std::to_string(port) + ".." +
           std::to_string(port + channels::kChannelGroups - 1) + " of the LCM URL '" + u + "': past 65535";
    return "";
  }
  why->clear();
  return scheme + group + ":" + std::to_string(port + offset) + options;
}

std::uint32_t groups_of_pattern(const std::string& pattern, const std::string& suffix) {
  // POSIX extended expressions, anchored as LCM anchors a subscription (std::regex's
  // GCC 12 headers trip -Wmaybe-uninitialized under the sanitizer build's -O2).
  std::uint32_t groups = 0;
  regex_t re;
  if (regcomp(&re, ("^(" + pattern + ")$").c_str(), REG_EXTENDED | REG_NOSUB) == 0) {
    for (const std::string& name : known_channels(suffix))
      if (regexec(&re, name.c_str(), 0, nullptr, 0) == 0) groups |= 1u << channels::channel_group(name, suffix);
    regfree(&re);
  }
  // A pattern that matches no known name, or that POSIX does not read (LCM decides
  // whether it is one): its channels would be unknown ones, in the team group.
  return groups != 0 ? groups : 1u << channels::kGroupTeam;
}

struct GroupedLcmTransport::Impl {
  struct Sub {
    int id;
    std::vector<std::pair<int, int>> parts;  // (group, the group instance's subscription id)
  };

  std::string suffix, who;
  std::FILE* log = nullptr;
  std::array<std::string, channels::kChannelGroups> urls;
  std::array<std::unique_ptr<LcmTransport>, channels::kChannelGroups> groups;
  std::array<int, channels::kChannelGroups> subscriptions{};  // per group: live subscriptions
  std::vector<pollfd> fds;                                    // the groups with a subscription
  std::vector<int> fd_group;                                  // fds[i] is group fd_group[i]
  std::vector<Sub> subs;
  std::string error;
  int next_id = 1;

  LcmTransport* instance(int g) {
    if (!groups[g]) {
      groups[g] = std::make_unique<LcmTransport>(urls[g], who, log);
      if (!groups[g]->good()) error = "cannot open LCM at " + urls[g];
    }
    return groups[g]->good() ? groups[g].get() : nullptr;
  }

  void rebuild_fds() {
    fds.clear();
    fd_group.clear();
    for (int g = 0; g < channels::kChannelGroups; ++g) {
      if (subscriptions[g] == 0 || !groups[g]) continue;
      fds.push_back(pollfd{groups[g]->fileno(), POLLIN, 0});
      fd_group.push_back(g);
    }
  }
};

GroupedLcmTransport::GroupedLcmTransport(const std::string& url, std::string suffix, std::string who, std::FILE* log)
    : impl_(std::make_unique<Impl>()) {
  impl_->suffix = std::move(suffix);
  impl_->who = std::move(who);
  impl_->log = log;
  for (int g = 0; g < channels::kChannelGroups; ++g) {
    impl_->urls[g] = group_url(url, g, &impl_->error);
    if (impl_->urls[g].empty()) return;
  }
  impl_->instance(channels::kGroupTeam);  // a bad address or no multicast route shows here
}

GroupedLcmTransport::~GroupedLcmTransport() = default;

bool GroupedLcmTransport::good() const { return impl_->error.empty(); }

const std::string& GroupedLcmTransport::error() const { return impl_->error; }

bool GroupedLcmTransport::publish(const std::string& channel, const void* data, std::size_t size) {
  if (!good()) return false;
  LcmTransport* t = impl_->instance(channels::channel_group(channel, impl_->suffix));
  return t != nullptr && t->publish(channel, data, size);
}

int GroupedLcmTransport::subscribe(const std::string& pattern, RawHandler handler, void* context, int queue_capacity) {
  if (!good()) return 0;
  Impl::Sub sub{impl_->next_id, {}};
  const std::uint32_t groups = groups_of_pattern(pattern, impl_->suffix);
  for (int g = 0; g < channels::kChannelGroups; ++g) {
    if ((groups & (1u << g)) == 0) continue;
    LcmTransport* t = impl_->instance(g);
    const int id = t != nullptr ? t->subscribe(pattern, handler, context, queue_capacity) : 0;
    if (id <= 0) {
      for (const auto& [pg, pid] : sub.parts) {
        impl_->groups[pg]->unsubscribe(pid);
        --impl_->subscriptions[pg];
      }
      impl_->rebuild_fds();
      return 0;
    }
    sub.parts.emplace_back(g, id);
    ++impl_->subscriptions[g];
  }
  impl_->subs.push_back(std::move(sub));
  impl_->rebuild_fds();
  return impl_->next_id++;
}

void GroupedLcmTransport::unsubscribe(int id) {
  for (auto it = impl_->subs.begin(); it != impl_->subs.end(); ++it) {
    if (it->id != id) continue;
    for (const auto& [g, gid] : it->parts) {
      impl_->groups[g]->unsubscribe(gid);
      --impl_->subscriptions[g];
    }
    impl_->subs.erase(it);
    impl_->rebuild_fds();
    return;
  }
}

TransportRefusals GroupedLcmTransport::refusals() const {
  TransportRefusals sum;
  for (const auto& g : impl_->groups) {
    if (!g) continue;
    const TransportRefusals r = g->refusals();
    sum.total += r.total, sum.unauthenticated += r.unauthenticated, sum.malformed += r.malformed;
  }
  return sum;
}

int GroupedLcmTransport::handle_timeout(int timeout_ms) {
  if (!good()) return -1;
  if (impl_->fds.empty()) {  // nothing to receive: wait as asked, as LCM does
    if (timeout_ms > 0) ::poll(nullptr, 0, timeout_ms);
    return 0;
  }
  const int ready = ::poll(impl_->fds.data(), impl_->fds.size(), timeout_ms);
  if (ready <= 0) return ready < 0 ? -1 : 0;  // < 0 also on EINTR, as LCM's handleTimeout
  // The ready groups first: a handler may subscribe or unsubscribe, which rebuilds fds.
  std::array<int, channels::kChannelGroups> ready_groups{};
  int n = 0;
  for (std::size_t i = 0; i < impl_->fds.size(); ++i)
    if ((impl_->fds[i].revents & (POLLIN | POLLERR | POLLHUP)) != 0) ready_groups[n++] = impl_->fd_group[i];
  int handled = 0;
  for (int i = 0; i < n; ++i) {
    const int rc = impl_->subscriptions[ready_groups[i]] > 0 ? impl_->groups[ready_groups[i]]->handle_timeout(0) : 0;
    if (rc < 0) return -1;
    handled += rc;
  }
  return handled;
}

}  // namespace elaslam::transport

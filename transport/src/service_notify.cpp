// SPDX-License-Identifier: Apache-2.0
#include "elaslam/transport/service_notify.hpp"

#include <systemd/sd-daemon.h>

#include <cstdlib>

namespace elaslam::transport {

ServiceNotifier::ServiceNotifier() {
  const char* socket = std::getenv("NOTIFY_SOCKET");
  enabled_ = socket != nullptr && socket[0] != '\0';
  std::uint64_t usec = 0;
  // > 0: WATCHDOG_USEC is set and WATCHDOG_PID is unset or this process (0: keep the
  // variables, a child process started later is not the service's main process anyway).
  if (enabled_ && sd_watchdog_enabled(0, &usec) > 0 && usec > 0)
    watchdog_ = std::chrono::microseconds(static_cast<std::int64_t>(usec));
}

void ServiceNotifier::send(const char* state) {
  if (sd_notify(0, state) < 0) ++send_errors_;
}

void ServiceNotifier::ready(const std::string& status) {
  if (!enabled_ || ready_sent_) return;
  ready_sent_ = true;
  send(status.empty() ? "READY=1" : ("READY=1\nSTATUS=" + status).c_str());
  next_ping_ = Clock::now();  // the first ping right away: systemd's timer runs from start-up
}

void ServiceNotifier::alive(Clock::time_point now) {
  if (watchdog_.count() == 0 || now < next_ping_) return;
  send("WATCHDOG=1");
  ++pings_;
  next_ping_ = now + ping_interval();
}

void ServiceNotifier::stopping() {
  if (enabled_) send("STOPPING=1");
}

}  // namespace elaslam::transport

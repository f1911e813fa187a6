// SPDX-License-Identifier: Apache-2.0
// The service manager's notification protocol (sd_notify(3), libsystemd's sd-daemon):
// a node started by systemd as a Type=notify unit says READY=1 once it is ready (LCM
// open, inputs subscribed, state resumed) and, when the unit has WatchdogSec=, says
// WATCHDOG=1 from its main loop. The pings come from the loop and nowhere else (no
// thread of their own): a handler that hangs stops the loop, the pings stop, and
// systemd kills and restarts the service after WatchdogSec (docs/deployment.md,
// "Watchdog").
//
// Without $NOTIFY_SOCKET (a node started by hand, a test, run_team.sh) it does nothing.
// The environment is read once, at construction.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace elaslam::transport {

class ServiceNotifier {
 public:
  using Clock = std::chrono::steady_clock;

  /// Reads $NOTIFY_SOCKET and, through sd_watchdog_enabled(), $WATCHDOG_USEC and
  /// $WATCHDOG_PID (a watchdog meant for another process is not ours).
  ServiceNotifier();

  /// A service manager listens ($NOTIFY_SOCKET set).
  bool enabled() const { return enabled_; }
  /// The watchdog's period (WatchdogSec=), zero when there is none.
  std::chrono::microseconds watchdog() const { return watchdog_; }
  /// Pings are sent at half the period (sd_watchdog_enabled(3)'s advice).
  std::chrono::microseconds ping_interval() const { return watchdog_ / 2; }

  /// READY=1 (with STATUS=`status` when not empty), the first call only.
  void ready(const std::string& status = {});
  /// From the main loop, every turn: WATCHDOG=1 when a ping is due. Cheap otherwise
  /// (one clock comparison); allocates nothing.
  void alive(Clock::time_point now = Clock::now());
  /// STOPPING=1: the orderly exit has begun (systemd shows "deactivating").
  void stopping();

  bool ready_sent() const { return ready_sent_; }
  std::int64_t pings() const { return pings_; }  // WATCHDOG=1 sent
  std::int64_t send_errors() const { return send_errors_; }

 private:
  void send(const char* state);

  bool enabled_ = false;
  std::chrono::microseconds watchdog_{0};
  bool ready_sent_ = false;
  Clock::time_point next_ping_{};
  std::int64_t pings_ = 0;
  std::int64_t send_errors_ = 0;
};

}  // namespace elaslam::transport

// SPDX-License-Identifier: Apache-2.0
// The service manager's notifications (service_notify.hpp) as systemd sees them: a
// datagram socket of the test's own stands in for $NOTIFY_SOCKET. READY=1 once, then
// WATCHDOG=1 at half of $WATCHDOG_USEC from the shell's loop; a handler that hangs
// stops the pings (so systemd's watchdog restarts the node), and they resume after.
// Bounded waits (poll with deadlines), no sleeps.
#include <gtest/gtest.h>

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <string>
#include <thread>

#include "elaslam/dynamic_notice_t.hpp"
#include "elaslam/transport/lcm_transport.hpp"
#include "elaslam/transport/node_shell.hpp"
#include "elaslam/transport/service_notify.hpp"

namespace elaslam::transport {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

/// A fake service manager: a datagram socket bound at a fresh path, published as
/// $NOTIFY_SOCKET (and $WATCHDOG_USEC when given) for the notifiers made after it.
class FakeManager {
 public:
  explicit FakeManager(long watchdog_usec) {
    char dir[] = "/tmp/elaslam-notify-XXXXXX";
    dir_ = mkdtemp(dir);
    path_ = dir_ + "/notify";
    fd_ = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::strncpy(a.sun_path, path_.c_str(), sizeof a.sun_path - 1);
    ok_ = fd_ >= 0 && bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
    setenv("NOTIFY_SOCKET", path_.c_str(), 1);
    unsetenv("WATCHDOG_PID");
    if (watchdog_usec > 0)
      setenv("WATCHDOG_USEC", std::to_string(watchdog_usec).c_str(), 1);
    else
      unsetenv("WATCHDOG_USEC");
  }
  ~FakeManager() {
    unsetenv("NOTIFY_SOCKET");
    unsetenv("WATCHDOG_USEC");
    if (fd_ >= 0) close(fd_);
    unlink(path_.c_str());
    rmdir(dir_.c_str());
  }
  bool ok() const { return ok_; }

  /// The next datagram within `timeout`, "" when none came.
  std::string next(milliseconds timeout) {
    pollfd p{fd_, POLLIN, 0};
    if (poll(&p, 1, static_cast<int>(timeout.count())) != 1) return "";
    char buf[512];
    const ssize_t n = recv(fd_, buf, sizeof buf, 0);
    return n > 0 ? std::string(buf, static_cast<std::size_t>(n)) : "";
  }
  /// Datagrams equal to `what` received within `window` (others are skipped).
  int count(const std::string& what, milliseconds window) {
    int n = 0;
    const auto end = Clock::now() + window;
    for (auto now = Clock::now(); now < end; now = Clock::now())
      if (next(std::chrono::duration_cast<milliseconds>(end - now)) == what) ++n;
    return n;
  }
  /// Throw away what is queued.
  void drain() {
    while (!next(milliseconds(0)).empty()) {
    }
  }

 private:
  std::string dir_, path_;
  int fd_ = -1;
  bool ok_ = false;
};

TEST(ServiceNotifier, DoesNothingWithoutNotifySocket) {
  unsetenv("NOTIFY_SOCKET");
  setenv("WATCHDOG_USEC", "100000", 1);
  ServiceNotifier n;
  EXPECT_FALSE(n.enabled());
  EXPECT_EQ(n.watchdog().count(), 0);
  n.ready();
  n.alive();
  EXPECT_FALSE(n.ready_sent());
  EXPECT_EQ(n.pings(), 0);
  unsetenv("WATCHDOG_USEC");
}

TEST(ServiceNotifier, WatchdogOfAnotherProcessIsNotOurs) {
  FakeManager m(100000);
  ASSERT_TRUE(m.ok());
  setenv("WATCHDOG_PID", std::to_string(getpid() + 1).c_str(), 1);
  ServiceNotifier n;
  EXPECT_TRUE(n.enabled());
  EXPECT_EQ(n.watchdog().count(), 0);
  unsetenv("WATCHDOG_PID");
}

TEST(ServiceNotifier, ReadyOnceThenPingsAtHalfThePeriod) {
  FakeManager m(400000);  // WatchdogSec=400ms
  ASSERT_TRUE(m.ok());
  ServiceNotifier n;
  ASSERT_EQ(n.watchdog(), std::chrono::microseconds(400000));
  EXPECT_EQ(n.ping_interval(), std::chrono::microseconds(200000));
  n.ready("up");
  n.ready();  // a second call says nothing
  EXPECT_EQ(m.next(milliseconds(2000)), "READY=1\nSTATUS=up");
  const auto t0 = Clock::now();
  n.alive(t0);                          // due at once after READY
  n.alive(t0 + milliseconds(100));      // not yet
  n.alive(t0 + milliseconds(199));      // not yet
  n.alive(t0 + milliseconds(200));      // due
  EXPECT_EQ(n.pings(), 2);
  EXPECT_EQ(m.count("WATCHDOG=1", milliseconds(300)), 2);
  EXPECT_EQ(n.send_errors(), 0);
}

// GIVEN a shell spinning with a service and WatchdogSec=300ms, WHEN a handler hangs,
// THEN the pings stop for as long as it hangs, and resume once it returns.
TEST(ServiceNotifier, HungHandlerStopsThePings) {
  FakeManager m(300000);  // pings every 150 ms
  ASSERT_TRUE(m.ok());
  ServiceNotifier service;
  LcmTransport t("memq://");  // its handle_timeout waits (the in-process one would spin hot)
  ASSERT_TRUE(t.good());
  std::atomic<bool> stop{false};
  ShellOptions o("hang_test", "", nullptr);
  o.stop = &stop;
  o.service = &service;
  NodeShell shell(t, o);

  std::mutex mu;
  std::condition_variable cv;
  bool hanging = false, release = false;
  std::atomic<bool> hang_now{false};
  ASSERT_GT(shell.subscribe<dynamic_notice_t>(
                "HANG", [&](const dynamic_notice_t&, const std::string&) {
                  std::unique_lock<std::mutex> lock(mu);
                  hanging = true;
                  cv.notify_all();
                  cv.wait_for(lock, std::chrono::seconds(10), [&] { return release; });  // bounded
                  hanging = false;
                },
                8),
            0);
  // The loop's own thread publishes the message that hangs it.
  shell.every(milliseconds(10), [&] {
    if (hang_now.exchange(false)) shell.publish("HANG", dynamic_notice_t{});
  });
  std::thread loop([&] { shell.spin(10); });

  EXPECT_EQ(m.next(milliseconds(3000)), "READY=1");
  EXPECT_GE(m.count("WATCHDOG=1", milliseconds(700)), 3);  // ~4 in 700 ms

  hang_now = true;
  {
    std::unique_lock<std::mutex> lock(mu);
    ASSERT_TRUE(cv.wait_for(lock, std::chrono::seconds(5), [&] { return hanging; }));
  }
  m.drain();  // pings sent before the handler started
  const std::int64_t pings_at_hang = service.pings();
  EXPECT_EQ(m.count("WATCHDOG=1", milliseconds(900)), 0) << "a hung handler must stop the pings (3 watchdog periods)";
  EXPECT_EQ(service.pings(), pings_at_hang);

  {
    std::lock_guard<std::mutex> lock(mu);
    release = true;
  }
  cv.notify_all();
  EXPECT_EQ(m.next(milliseconds(2000)), "WATCHDOG=1") << "pings resume once the loop turns again";
  stop = true;
  loop.join();
  EXPECT_EQ(m.next(milliseconds(2000)), "STOPPING=1");
}

}  // namespace
}  // namespace elaslam::transport

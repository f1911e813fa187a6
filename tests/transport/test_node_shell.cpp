// SPDX-License-Identifier: Apache-2.0
// The node shell over both transports (the in-process one and LCM's memq://): decode
// into one message, refusals counted and rate-limited, handlers that never throw,
// periodic callbacks, stop on a signal.
#include <gtest/gtest.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "elaslam/dynamic_notice_t.hpp"
#include "elaslam/transport/inprocess_transport.hpp"
#include "elaslam/transport/lcm_transport.hpp"
#include "elaslam/transport/node_shell.hpp"
#include "elaslam/transport/process.hpp"

namespace elaslam::transport {
namespace {

/// The shell's log, read back.
class LogFile {
 public:
  LogFile() : f_(std::tmpfile()) {}
  ~LogFile() { std::fclose(f_); }
  std::FILE* get() { return f_; }
  std::vector<std::string> lines() {
    std::fflush(f_);
    std::rewind(f_);
    std::vector<std::string> out;
    char buf[1024];
    while (std::fgets(buf, sizeof buf, f_)) out.emplace_back(buf);
    return out;
  }

 private:
  std::FILE* f_;
};

dynamic_notice_t notice(std::int64_t seq, int landmark = 7) {
  dynamic_notice_t n{};
  n.seq = seq;
  n.frame = 3;
  n.landmark_id = landmark;
  n.detected_by = 1;
  return n;
}

void drain(Transport& t) {
  while (t.handle_timeout(0) > 0) {
  }
}

template <class T>
std::unique_ptr<Transport> make();
template <>
std::unique_ptr<Transport> make<InProcessTransport>() {
  return std::make_unique<InProcessTransport>();
}
template <>
std::unique_ptr<Transport> make<LcmTransport>() {
  return std::make_unique<LcmTransport>("memq://");
}

template <class T>
class NodeShellTest : public ::testing::Test {
 protected:
  std::unique_ptr<Transport> transport = make<T>();
  LogFile log;
  std::atomic<bool> stop{false};
  ShellOptions options(const std::string& suffix = "") {
    ShellOptions o("test node", suffix, log.get());
    o.stop = &stop;
    return o;
  }
};
using Transports = ::testing::Types<InProcessTransport, LcmTransport>;
TYPED_TEST_SUITE(NodeShellTest, Transports);

TYPED_TEST(NodeShellTest, DecodesEachMessageAndHandsItOver) {
  NodeShell shell(*this->transport, this->options());
  std::vector<std::int64_t> seqs;
  const int in = shell.subscribe<dynamic_notice_t>(
      "DYNAMIC_NOTICE", [&](const dynamic_notice_t& m, const std::string& ch) {
        EXPECT_EQ(ch, "DYNAMIC_NOTICE");
        seqs.push_back(m.seq);
      }, 100);
  ASSERT_GT(in, 0);
  for (int s = 1; s <= 3; ++s) EXPECT_TRUE(shell.publish("DYNAMIC_NOTICE", notice(s)));
  drain(*this->transport);
  EXPECT_EQ(seqs, (std::vector<std::int64_t>{1, 2, 3}));
  EXPECT_EQ(shell.input_counters(in).received, 3);
  EXPECT_EQ(shell.counters().published, 3);
  EXPECT_EQ(shell.counters().inputs.decode_errors, 0);
}

TYPED_TEST(NodeShellTest, DecodeErrorsAreCountedAndTheirWarningsRateLimited) {
  NodeShell shell(*this->transport, this->options());
  int hook = 0, handled = 0;
  shell.on_decode_error([&] { ++hook; });
  const int in = shell.subscribe<dynamic_notice_t>(
      "DYNAMIC_NOTICE", [&](const dynamic_notice_t&, const std::string&) { ++handled; }, kUnboundedQueue);
  const std::uint8_t garbage[5] = {1, 2, 3, 4, 5};
  for (int i = 0; i < 2500; ++i) {
    this->transport->publish("DYNAMIC_NOTICE", garbage, sizeof garbage);
    drain(*this->transport);  // memq: one at a time keeps LCM's own queue small
  }
  shell.publish("DYNAMIC_NOTICE", notice(1));
  drain(*this->transport);
  EXPECT_EQ(shell.input_counters(in).decode_errors, 2500);
  EXPECT_EQ(hook, 2500);
  EXPECT_EQ(handled, 1) << "the node carries on";
  const auto lines = this->log.lines();
  ASSERT_EQ(lines.size(), 22u) << "the first 20, then every 1000th";
  EXPECT_EQ(lines.front(), "test node: cannot decode a dynamic_notice_t (warning 1)\n");
  EXPECT_EQ(lines.back(), "test node: cannot decode a dynamic_notice_t (warning 2000)\n");
}

TYPED_TEST(NodeShellTest, RefusalsByTheValidatorOrTheHandlerAreCounted) {
  NodeShell shell(*this->transport, this->options());
  std::vector<std::int64_t> handled;
  const int in = shell.subscribe<dynamic_notice_t>(
      "DYNAMIC_NOTICE",
      [&](const dynamic_notice_t& m, const std::string&) {
        if (m.landmark_id < 0) return shell.refuse("landmark_id is negative");
        handled.push_back(m.seq);
      },
      100,
      [](const dynamic_notice_t& m, const std::string&) { return m.seq % 2 == 0 ? "even seq" : std::string(); });
  shell.publish("DYNAMIC_NOTICE", notice(1));
  shell.publish("DYNAMIC_NOTICE", notice(2));      // refused by the validator: the handler never sees it
  shell.publish("DYNAMIC_NOTICE", notice(3, -1));  // refused by the handler
  shell.publish("DYNAMIC_NOTICE", notice(5));
  drain(*this->transport);
  EXPECT_EQ(handled, (std::vector<std::int64_t>{1, 5}));
  EXPECT_EQ(shell.input_counters(in).refused, 2);
  const auto lines = this->log.lines();
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0], "test node: even seq (warning 1)\n");
  EXPECT_EQ(lines[1], "test node: landmark_id is negative (warning 2)\n");
}

TYPED_TEST(NodeShellTest, AHandlerNeverLetsAnExceptionOut) {
  NodeShell shell(*this->transport, this->options());
  int handled = 0;
  const int in = shell.subscribe<dynamic_notice_t>(
      "DYNAMIC_NOTICE", [&](const dynamic_notice_t& m, const std::string&) {
        if (m.seq == 1) throw std::runtime_error("boom");
        ++handled;
      }, 100);
  shell.publish("DYNAMIC_NOTICE", notice(1));
  shell.publish("DYNAMIC_NOTICE", notice(2));
  EXPECT_NO_THROW(drain(*this->transport));
  EXPECT_EQ(handled, 1);
  EXPECT_EQ(shell.input_counters(in).handler_errors, 1);
  const auto lines = this->log.lines();
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_NE(lines[0].find("handling a message on DYNAMIC_NOTICE failed: boom"), std::string::npos) << lines[0];
}

TYPED_TEST(NodeShellTest, PeriodicCallbacksFireUntilTheStop) {
  NodeShell shell(*this->transport, this->options());
  int fast = 0, turns = 0, late = 0;
  const auto t0 = NodeShell::Clock::now();
  shell.every(std::chrono::milliseconds(1), [&] {
    if (++fast == 5) this->stop = true;
  });
  shell.every(NodeShell::Clock::duration::zero(), [&] { ++turns; });
  shell.every(std::chrono::hours(1), [&] { ++late; }, std::chrono::hours(1));
  EXPECT_EQ(shell.spin(1), NodeShell::Exit::kStopped);
  EXPECT_EQ(fast, 5);
  EXPECT_GE(turns, 5) << "a zero period: every turn";
  EXPECT_EQ(late, 0) << "first_after delays the first call";
  EXPECT_GE(NodeShell::Clock::now() - t0, std::chrono::milliseconds(4)) << "calls at 0, 1, 2, 3 and 4 ms";
}

TYPED_TEST(NodeShellTest, SpinEndsOnSigterm) {
  install_stop_handlers();
  stop_flag() = false;
  ShellOptions o("test node", "", this->log.get());  // the process's flag (o.stop == nullptr)
  NodeShell shell(*this->transport, o);
  int calls = 0;
  shell.every(std::chrono::milliseconds(1), [&] {
    if (++calls == 3) std::raise(SIGTERM);
  });
  EXPECT_EQ(shell.spin(20), NodeShell::Exit::kStopped);
  EXPECT_EQ(calls, 3);
  EXPECT_TRUE(stop_flag().load());
  stop_flag() = false;
}

TYPED_TEST(NodeShellTest, UnsubscribedInputsKeepTheirCounters) {
  NodeShell shell(*this->transport, this->options());
  int handled = 0;
  const int in = shell.subscribe<dynamic_notice_t>(
      "DYNAMIC_NOTICE", [&](const dynamic_notice_t&, const std::string&) { ++handled; }, 100);
  NodeShell other(*this->transport, this->options());  // keeps the channel subscribed
  other.subscribe<dynamic_notice_t>("DYNAMIC_NOTICE", {}, 100);
  shell.publish("DYNAMIC_NOTICE", notice(1));
  drain(*this->transport);
  shell.unsubscribe(in);
  shell.publish("DYNAMIC_NOTICE", notice(2));
  drain(*this->transport);
  EXPECT_EQ(handled, 1);
  EXPECT_EQ(shell.input_counters(in).received, 1);
}

TEST(SequenceGaps, CountsWhatWasLostBetweenTwoSeqs) {
  SequenceGaps g;
  EXPECT_EQ(g.observe(1), 0);
  EXPECT_EQ(g.observe(2), 0);
  EXPECT_EQ(g.observe(5), 2);
  EXPECT_EQ(g.observe(5), 0) << "a repeat";
  EXPECT_EQ(g.observe(3), 0) << "an older one";
  EXPECT_EQ(g.observe(6), 0);
  EXPECT_EQ(g.newest(), 6);
}

}  // namespace
}  // namespace elaslam::transport

// SPDX-License-Identifier: Apache-2.0
// The simulator process's library (run_simulator) on the in-process transport:
// more landmarks in view than a sensor frame carries is said at once (a FAULT line,
// rate-limited) and flagged in STATUS_SIM, not only in the summary line.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdio>
#include <string>

#include "elaslam/common/channels.hpp"
#include "elaslam/node_status_t.hpp"
#include "elaslam/simulator/sim_node.hpp"
#include "elaslam/transport/inprocess_transport.hpp"
#include "elaslam/transport/node_shell.hpp"
#include "sim_test_util.hpp"

namespace elaslam::sim {
namespace {

std::string run_and_read_log(const ScenarioOptions& o, node_status_t* last_status) {
  transport::InProcessTransport bus;
  std::FILE* log = std::tmpfile();
  std::atomic<bool> stop{false};
  transport::ShellOptions so("simulator", "", log);
  so.stop = &stop;
  transport::NodeShell shell(bus, so);
  transport::ShellOptions oo("observer", "", nullptr);
  oo.stop = &stop;
  transport::NodeShell observer(bus, oo);
  observer.subscribe<node_status_t>(channels::status_sim(), [&](const node_status_t& m, const std::string&) { *last_status = m; },
                                    transport::kUnboundedQueue);
  EXPECT_EQ(run_simulator(shell, o, SimRunOptions{}), 0);
  stop = true;
  bus.dispatch_all();  // deliver what was published
  std::rewind(log);
  std::string text;
  char buf[4096];
  for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, log)) > 0;) text.append(buf, n);
  std::fclose(log);
  return text;
}

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(SimNode, ObservationsBeyondTheFrameCapacityAreSaidAtOnceAndFlagged) {
  ScenarioOptions o = test::paper();
  o.sensor.fov_diameter_m = 60.0;  // all 72 landmarks in view: 8 per robot left out
  o.frames = 5;
  o.rate_hz = 1000.0;
  node_status_t status{};
  const std::string log = run_and_read_log(o, &status);
  EXPECT_EQ(count(log, "FAULT: frame 0: 24 observation(s) beyond the 64"), 1) << log;
  EXPECT_EQ(count(log, "FAULT: frame"), 1) << log;  // rate-limited: once per 100 frames
  EXPECT_NE(status.fault_flags & node_status_t::FAULT_CAPACITY, 0);
}

TEST(SimNode, NoCapacityFaultWhenEverythingFits) {
  ScenarioOptions o = test::paper();
  o.frames = 5;
  o.rate_hz = 1000.0;
  node_status_t status{};
  const std::string log = run_and_read_log(o, &status);
  EXPECT_EQ(count(log, "FAULT"), 0) << log;
  EXPECT_EQ(status.fault_flags & node_status_t::FAULT_CAPACITY, 0);
  EXPECT_EQ(status.node_kind, node_status_t::SIMULATOR);
}

}  // namespace
}  // namespace elaslam::sim

// The LCM transport over memq:// (one process, no network).
#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <vector>

#include "elaslam/transport/lcm_transport.hpp"

namespace elaslam::transport {
namespace {

void record(const RawMessage& m, void* context) {
  static_cast<std::vector<std::string>*>(context)->push_back(
      m.channel + ":" + std::string(reinterpret_cast<const char*>(m.data), m.size));
}

bool pub(Transport& t, const std::string& channel, const std::string& payload) {
  return t.publish(channel, payload.data(), payload.size());
}

TEST(LcmTransport, MemqDeliversInOrderWithPatterns) {
  LcmTransport t("memq://");
  ASSERT_TRUE(t.good());
  std::vector<std::string> log;
  ASSERT_GT(t.subscribe("STATUS_(ROBOT_[0-9]+|MAIN)", &record, &log, kUnboundedQueue), 0);
  EXPECT_TRUE(pub(t, "STATUS_ROBOT_2", "a"));
  EXPECT_TRUE(pub(t, "STATUS_SIM", "b"));
  EXPECT_TRUE(pub(t, "STATUS_MAIN", "c"));
  while (t.handle_timeout(0) > 0) {
  }
  EXPECT_EQ(log, (std::vector<std::string>{"STATUS_ROBOT_2:a", "STATUS_MAIN:c"}));
}

TEST(LcmTransport, HandleTimeoutWaitsAtMostItsTimeout) {
  LcmTransport t("memq://");
  std::vector<std::string> log;
  t.subscribe("A", &record, &log, 5);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(t.handle_timeout(30), 0);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(5));
}

TEST(LcmTransport, UnsubscribeStopsDelivery) {
  LcmTransport t("memq://");
  std::vector<std::string> a, b;
  const int ida = t.subscribe("A", &record, &a, kTransportDefaultQueue);
  t.subscribe("A", &record, &b, kTransportDefaultQueue);
  pub(t, "A", "1");
  while (t.handle_timeout(0) > 0) {
  }
  t.unsubscribe(ida);
  pub(t, "A", "2");
  while (t.handle_timeout(0) > 0) {
  }
  EXPECT_EQ(a, (std::vector<std::string>{"A:1"}));
  EXPECT_EQ(b, (std::vector<std::string>{"A:1", "A:2"}));
}

TEST(LcmTransport, ABadUrlGivesATransportThatSaysSo) {
  LcmTransport t("nosuchprovider://");
  EXPECT_FALSE(t.good());
  std::vector<std::string> log;
  EXPECT_EQ(t.subscribe("A", &record, &log, 5), 0);
  EXPECT_FALSE(pub(t, "A", "1"));
  EXPECT_LT(t.handle_timeout(0), 0);
}

}  // namespace
}  // namespace elaslam::transport

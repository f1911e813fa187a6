// SPDX-License-Identifier: Apache-2.0
// The in-process transport: memq://'s order (LCM.md), deterministic, reusable.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "elaslam/transport/inprocess_transport.hpp"

namespace elaslam::transport {
namespace {

/// A subscriber that writes "<tag>:<channel>:<payload>" for each message and can
/// publish a reply from inside its handler.
struct Sink {
  Sink(std::string t, std::vector<std::string>* l, Transport* reply = nullptr, std::string reply_ch = "", int after = -1)
      : tag(std::move(t)), log(l), reply_on(reply), reply_channel(std::move(reply_ch)), unsubscribe_after(after) {}
  std::string tag;
  std::vector<std::string>* log;
  Transport* reply_on;
  std::string reply_channel;
  int unsubscribe_after;  // unsubscribe `self_id` after this many messages
  int self_id = 0;
  int seen = 0;
};

void record(const RawMessage& m, void* context) {
  auto* s = static_cast<Sink*>(context);
  s->log->push_back(s->tag + ":" + m.channel + ":" + std::string(reinterpret_cast<const char*>(m.data), m.size));
  if (s->reply_on) s->reply_on->publish(s->reply_channel, m.data, m.size);
  if (++s->seen == s->unsubscribe_after) s->reply_on->unsubscribe(s->self_id);
}

bool pub(Transport& t, const std::string& channel, const std::string& payload) {
  return t.publish(channel, payload.data(), payload.size());
}

TEST(InProcessTransport, DispatchesInPublicationOrderToSubscribersInSubscriptionOrder) {
  InProcessTransport t;
  std::vector<std::string> log;
  Sink a{"a", &log}, b{"b", &log};
  ASSERT_GT(t.subscribe("X", &record, &a, kUnboundedQueue), 0);
  ASSERT_GT(t.subscribe("X|Y", &record, &b, kUnboundedQueue), 0);
  pub(t, "X", "1");
  pub(t, "Y", "2");
  pub(t, "X", "3");
  EXPECT_EQ(t.queued(), 3u);
  EXPECT_EQ(t.dispatch_all(), 3);
  EXPECT_EQ(log, (std::vector<std::string>{"a:X:1", "b:X:1", "b:Y:2", "a:X:3", "b:X:3"}));
  EXPECT_EQ(t.handle_timeout(100), 0) << "an empty queue: nothing to wait for in one thread";
}

TEST(InProcessTransport, APublishFromAHandlerIsQueuedBehindWhatIsQueued) {
  // GIVEN a handler on A that answers on B
  InProcessTransport t;
  std::vector<std::string> log;
  Sink answer{"ans", &log, &t, "B"}, b{"b", &log};
  t.subscribe("A", &record, &answer, kUnboundedQueue);
  t.subscribe("B", &record, &b, kUnboundedQueue);
  // WHEN two messages on A are queued and dispatched
  pub(t, "A", "1");
  pub(t, "A", "2");
  EXPECT_EQ(t.handle_timeout(0), 1);
  // THEN the answer waits behind the second A: no recursion
  EXPECT_EQ(log, (std::vector<std::string>{"ans:A:1"}));
  t.dispatch_all();
  EXPECT_EQ(log, (std::vector<std::string>{"ans:A:1", "ans:A:2", "b:B:1", "b:B:2"}));
}

TEST(InProcessTransport, PatternsMatchWholeChannelNames) {
  InProcessTransport t;
  std::vector<std::string> log;
  Sink s{"s", &log};
  t.subscribe("POSE_[0-9]+", &record, &s, kUnboundedQueue);
  for (const char* ch : {"POSE_1", "POSE_12", "POSE_1_SIM", "XPOSE_1", "POSE_"}) pub(t, ch, "p");
  t.dispatch_all();
  EXPECT_EQ(log, (std::vector<std::string>{"s:POSE_1:p", "s:POSE_12:p"}));
  EXPECT_EQ(t.dropped(), 3) << "published with no subscriber: not kept (as memq://)";
  EXPECT_EQ(t.published(), 2);
  EXPECT_EQ(t.subscribe("POSE_(", &record, &s, kUnboundedQueue), 0) << "an invalid pattern is refused";
}

TEST(InProcessTransport, UnsubscribedHandlersGetNothingMore) {
  InProcessTransport t;
  std::vector<std::string> log;
  Sink once{"once", &log, &t, "ignored", 1}, all{"all", &log};
  once.self_id = t.subscribe("A", &record, &once, kUnboundedQueue);
  t.subscribe("A", &record, &all, kUnboundedQueue);
  pub(t, "A", "1");
  pub(t, "A", "2");
  t.dispatch_all();  // `once` unsubscribes itself inside its first call
  EXPECT_EQ(log, (std::vector<std::string>{"once:A:1", "all:A:1", "all:A:2"}));
}

void reenter(const RawMessage&, void* context) {
  auto* t = static_cast<InProcessTransport*>(context);
  EXPECT_EQ(t->handle_timeout(0), -1) << "handle() from inside a handler is refused (LCM aborts)";
}

TEST(InProcessTransport, HandleFromInsideAHandlerIsRefused) {
  InProcessTransport t;
  t.subscribe("A", &reenter, &t, kUnboundedQueue);
  pub(t, "A", "1");
  pub(t, "A", "2");
  EXPECT_EQ(t.dispatch_all(), 2);
}

TEST(InProcessTransport, TheQueueGrowsAndKeepsItsOrder) {
  InProcessTransport t;
  std::vector<std::string> log;
  Sink s{"s", &log};
  t.subscribe("A", &record, &s, kUnboundedQueue);
  for (int i = 0; i < 1000; ++i) {
    pub(t, "A", std::to_string(i));
    if (i % 3 == 0) t.handle_timeout(0);  // the ring wraps while it grows
  }
  t.dispatch_all();
  ASSERT_EQ(log.size(), 1000u);
  for (int i = 0; i < 1000; ++i) EXPECT_EQ(log[static_cast<std::size_t>(i)], "s:A:" + std::to_string(i));
}

}  // namespace
}  // namespace elaslam::transport

// SPDX-License-Identifier: Apache-2.0
// The bytes from the network (docs/security.md "Bytes from the network"): LCM's
// datagrams parsed by DatagramAssembler with every size checked (udpm_receiver.hpp),
// the checks every transport applies to a message it hands over (malformed_message),
// and the two datagrams that crashed every keyed process, at each layer.
#include <arpa/inet.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "elaslam/common/contract.hpp"
#include "elaslam/transport/transport.hpp"
#include "elaslam/transport/udpm_receiver.hpp"

namespace elaslam::transport {
namespace {

using Result = DatagramAssembler::Result;
using Bytes = std::vector<std::uint8_t>;

void put32(Bytes* b, std::uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) b->push_back(static_cast<std::uint8_t>(v >> s));
}
void put16(Bytes* b, std::uint16_t v) {
  b->push_back(static_cast<std::uint8_t>(v >> 8));
  b->push_back(static_cast<std::uint8_t>(v));
}
void put(Bytes* b, const std::string& s, bool nul = true) {
  b->insert(b->end(), s.begin(), s.end());
  if (nul) b->push_back(0);
}

Bytes short_message(std::uint32_t seq, const std::string& channel, const Bytes& payload, bool nul = true) {
  Bytes b;
  put(&b, "LC02", false);
  put32(&b, seq);
  put(&b, channel, nul);
  b.insert(b.end(), payload.begin(), payload.end());
  return b;
}

Bytes fragment(std::uint32_t seq, std::uint32_t size, std::uint32_t offset, std::uint16_t number, std::uint16_t count,
               const std::string* channel, const Bytes& data) {
  Bytes b;
  put(&b, "LC03", false);
  put32(&b, seq);
  put32(&b, size);
  put32(&b, offset);
  put16(&b, number);
  put16(&b, count);
  if (channel != nullptr) put(&b, *channel);
  b.insert(b.end(), data.begin(), data.end());
  return b;
}

Bytes payload_of(std::size_t n) {
  Bytes p(n);
  for (std::size_t i = 0; i < n; ++i) p[i] = static_cast<std::uint8_t>(i * 31 + 7);
  return p;
}

struct Fed {
  Result result;
  std::string channel;
  Bytes data;
  std::string why;
};

Fed feed(DatagramAssembler& a, const Bytes& d, std::uint64_t source = 1) {
  const std::string* channel = nullptr;
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
  const char* why = nullptr;
  Fed f;
  f.result = a.feed(d.data(), d.size(), source, &channel, &data, &size, &why);
  if (f.result == Result::kMessage) {
    f.channel = *channel;
    f.data.assign(data, data + size);
  }
  if (why != nullptr) f.why = why;
  return f;
}

TEST(Datagrams, AShortMessageGivesItsChannelAndPayload) {
  DatagramAssembler a;
  const Fed f = feed(a, short_message(1, "SENSOR_1", payload_of(40)));
  ASSERT_EQ(f.result, Result::kMessage) << f.why;
  EXPECT_EQ(f.channel, "SENSOR_1");
  EXPECT_EQ(f.data, payload_of(40));
}

// The pair that crashed every keyed process: LCM 1.3.1 read the unterminated name
// into the previous datagram's zeros and reported a payload size of -1.
TEST(Datagrams, TheTwoDatagramsThatCrashedEveryKeyedNodeAreRefused) {
  DatagramAssembler a;
  EXPECT_EQ(feed(a, Bytes(200, 0)).result, Result::kRefused);
  const Fed f = feed(a, short_message(7, "SENSOR_1", {}, false));
  ASSERT_EQ(f.result, Result::kRefused);
  EXPECT_NE(f.why.find("runs past the datagram's end"), std::string::npos) << f.why;
}

TEST(Datagrams, EveryPrefixOfAValidDatagramIsRefusedOrWhole) {
  DatagramAssembler a;
  const Bytes whole = short_message(3, "LMAP_EVENTS", payload_of(25));
  for (std::size_t k = 0; k <= whole.size(); ++k) {
    const Bytes prefix(whole.begin(), whole.begin() + static_cast<std::ptrdiff_t>(k));
    const Fed f = feed(a, prefix);
    const std::size_t header_and_name = 8 + std::string("LMAP_EVENTS").size() + 1;
    if (k < header_and_name) {
      EXPECT_EQ(f.result, Result::kRefused) << "prefix of " << k << " bytes";
    } else {
      ASSERT_EQ(f.result, Result::kMessage) << "prefix of " << k << " bytes: " << f.why;
      EXPECT_EQ(f.channel, "LMAP_EVENTS");
      EXPECT_EQ(f.data.size(), k - header_and_name);
    }
  }
}

TEST(Datagrams, ChannelNamesLcmCannotHaveAreRefused) {
  DatagramAssembler a;
  EXPECT_EQ(feed(a, short_message(1, std::string(63, 'A'), payload_of(9))).result, Result::kMessage);
  for (const std::string& bad : {std::string(), std::string(64, 'A'), std::string(255, 'A'), std::string("SENSOR_1\x01"),
                                 std::string("POSE_1\xff"), std::string("A B"), std::string("\n")}) {
    const Fed f = feed(a, short_message(1, bad, payload_of(9)));
    EXPECT_EQ(f.result, Result::kRefused) << "channel of " << bad.size() << " bytes";
    EXPECT_FALSE(f.why.empty());
  }
  EXPECT_EQ(feed(a, Bytes{'L', 'C', '0', '4', 0, 0, 0, 1, 'A', 0}).result, Result::kRefused);  // another magic
}

TEST(Datagrams, AFragmentedMessageIsAssembledInOrder) {
  DatagramAssembler a;
  const std::string ch = "GROUND_TRUTH";
  const Bytes whole = payload_of(3000);
  const Bytes p0(whole.begin(), whole.begin() + 1000), p1(whole.begin() + 1000, whole.begin() + 2000),
      p2(whole.begin() + 2000, whole.end());
  EXPECT_EQ(feed(a, fragment(9, 3000, 0, 0, 3, &ch, p0)).result, Result::kPending);
  EXPECT_EQ(feed(a, fragment(9, 3000, 1000, 1, 3, nullptr, p1)).result, Result::kPending);
  const Fed f = feed(a, fragment(9, 3000, 2000, 2, 3, nullptr, p2));
  ASSERT_EQ(f.result, Result::kMessage) << f.why;
  EXPECT_EQ(f.channel, ch);
  EXPECT_EQ(f.data, whole);
}

TEST(Datagrams, FragmentsWithImpossibleSizesAreRefused) {
  DatagramAssembler a;
  const std::string ch = "SENSOR_1";
  const Bytes d = payload_of(16);
  // Shorter than the fragment header: LCM 1.3.1 underflowed the data size and copied ~4 GB.
  for (std::size_t n = 8; n < 20; ++n) {
    Bytes f = fragment(1, 100, 0, 0, 1, nullptr, {});
    f.resize(n);
    EXPECT_EQ(feed(a, f).result, Result::kRefused) << n << " bytes";
  }
  // An offset near 2^32: LCM 1.3.1's `offset + size > total` wrapped and it wrote 4 GB away.
  EXPECT_EQ(feed(a, fragment(2, 1400, 0xFFFFFFF8u, 1, 2, nullptr, d)).result, Result::kRefused);
  EXPECT_EQ(feed(a, fragment(2, 1400, 0xFFFFFFFFu, 0, 2, &ch, d)).result, Result::kRefused);
  EXPECT_EQ(feed(a, fragment(3, 0, 0, 0, 1, &ch, d)).result, Result::kRefused);  // an empty message
  EXPECT_EQ(feed(a, fragment(3, 0xFFFFFFFFu, 0, 0, 2, &ch, d)).result, Result::kRefused);
  EXPECT_EQ(feed(a, fragment(3, static_cast<std::uint32_t>(contract::kMaxMessageBytes) + 1, 0, 0, 2, &ch, d)).result,
            Result::kRefused);
  EXPECT_EQ(feed(a, fragment(4, 100, 0, 0, 0, &ch, d)).result, Result::kRefused);  // no fragments
  EXPECT_EQ(feed(a, fragment(4, 100, 0, 2, 2, &ch, d)).result, Result::kRefused);  // number past the count
  EXPECT_EQ(feed(a, fragment(5, 10, 0, 0, 2, &ch, d)).result, Result::kRefused);   // more data than the message
  // Fragment 0 whose channel runs off the end of the datagram (strlen in LCM 1.3.1).
  Bytes cut = fragment(6, 100, 0, 0, 2, nullptr, {});
  put(&cut, "SENSOR_1", false);
  const Fed f = feed(a, cut);
  EXPECT_EQ(f.result, Result::kRefused);
  EXPECT_NE(f.why.find("runs past"), std::string::npos) << f.why;
}

TEST(Datagrams, FragmentsOfNoMessageInProgressAreDroppedAndMessagesWithHolesNeverComplete) {
  DatagramAssembler a;
  const std::string ch = "GLOBAL_MAP";
  const Bytes d = payload_of(10);
  EXPECT_EQ(feed(a, fragment(1, 30, 10, 1, 3, nullptr, d)).result, Result::kDropped);  // its fragment 0 lost
  // Out of order: fragment 2 before 1 loses the message, fragment 1 then belongs to none.
  EXPECT_EQ(feed(a, fragment(2, 30, 0, 0, 3, &ch, d)).result, Result::kPending);
  EXPECT_EQ(feed(a, fragment(2, 30, 20, 2, 3, nullptr, d)).result, Result::kDropped);
  EXPECT_EQ(feed(a, fragment(2, 30, 10, 1, 3, nullptr, d)).result, Result::kDropped);
  // A fragment repeated, or one at the wrong offset: never a message with a hole.
  EXPECT_EQ(feed(a, fragment(3, 30, 0, 0, 3, &ch, d)).result, Result::kPending);
  EXPECT_EQ(feed(a, fragment(3, 30, 0, 0, 3, &ch, d)).result, Result::kPending);  // starts the message over
  EXPECT_EQ(feed(a, fragment(3, 30, 15, 1, 3, nullptr, Bytes(5))).result, Result::kDropped);
  // The fragments do not add up to the message's size.
  EXPECT_EQ(feed(a, fragment(4, 30, 0, 0, 2, &ch, d)).result, Result::kPending);
  EXPECT_EQ(feed(a, fragment(4, 30, 10, 1, 2, nullptr, d)).result, Result::kRefused);
}

TEST(Datagrams, SendersAreAssembledApartAndTheIdlestGivesWay) {
  DatagramAssembler a;
  const std::string ch = "GROUND_TRUTH";
  const Bytes d = payload_of(10);
  for (std::uint64_t s = 1; s <= DatagramAssembler::kAssemblies + 1; ++s)
    EXPECT_EQ(feed(a, fragment(1, 20, 0, 0, 2, &ch, d), s).result, Result::kPending);
  // Sender 1 waited longest: its slot went to the last sender.
  EXPECT_EQ(feed(a, fragment(1, 20, 10, 1, 2, nullptr, d), 1).result, Result::kDropped);
  for (std::uint64_t s = 2; s <= DatagramAssembler::kAssemblies + 1; ++s) {
    const Fed f = feed(a, fragment(1, 20, 10, 1, 2, nullptr, d), s);
    ASSERT_EQ(f.result, Result::kMessage) << "sender " << s;
    EXPECT_EQ(f.data.size(), 20u);
  }
}

// Every header field at its extremes, in every combination the datagrams' family
// (tests/system/raw_datagrams.py) sends: nothing but a refusal or a whole message of
// the size it says, within the bounds.
TEST(Datagrams, EverySizeFieldAtItsExtremesIsHandled) {
  DatagramAssembler a;
  const std::string ch = "SENSOR_1";
  const std::uint32_t big = static_cast<std::uint32_t>(contract::kMaxMessageBytes);
  int messages = 0;
  for (std::uint32_t size : {0u, 1u, 2u, 16u, 1400u, 65535u, big, big + 1, 0x7FFFFFFFu, 0xFFFFFFFFu})
    for (std::uint32_t offset : {0u, 1u, size - 1, size, size + 1, 0xFFFFFFF0u, 0xFFFFFFFFu})
      for (const auto& [number, count] : std::vector<std::pair<int, int>>{{0, 1}, {0, 2}, {1, 2}, {0, 0}, {5, 2}, {0, 65535}, {65535, 65535}})
        for (std::size_t data : {0u, 1u, 16u}) {
          const Fed f = feed(a, fragment(size, size, offset, static_cast<std::uint16_t>(number),
                                         static_cast<std::uint16_t>(count), number == 0 ? &ch : nullptr, payload_of(data)));
          if (f.result != Result::kMessage) continue;
          ++messages;
          EXPECT_EQ(f.data.size(), size);
          EXPECT_LE(f.data.size(), contract::kMaxMessageBytes);
        }
  EXPECT_GT(messages, 0);  // the valid single-fragment cases came through
}

TEST(DatagramDispatcher, MessagesGoToTheSubscriptionsThatMatchAsLcmMatchesAndRefusalsAreCounted) {
  DatagramDispatcher d("test", nullptr);
  struct Got {
    std::vector<std::string> channels;
    std::vector<std::int64_t> times;
  } pose, any;
  const auto record = [](const RawMessage& m, void* g) {
    static_cast<Got*>(g)->channels.push_back(m.channel);
    static_cast<Got*>(g)->times.push_back(m.recv_utime);
  };
  ASSERT_GT(d.subscribe("POSE_[0-9]+", record, &pose), 0);
  const int all = d.subscribe(".*", record, &any);
  ASSERT_GT(all, 0);
  EXPECT_EQ(d.subscribe("POSE_[", record, &pose), 0);  // not a regular expression
  EXPECT_TRUE(d.feed(short_message(1, "POSE_12", payload_of(9)).data(), short_message(1, "POSE_12", payload_of(9)).size(), 1, 77));
  const Bytes other = short_message(2, "XPOSE_1", payload_of(9));  // anchored: not POSE_[0-9]+
  EXPECT_TRUE(d.feed(other.data(), other.size(), 1, 78));
  EXPECT_EQ(pose.channels, std::vector<std::string>{"POSE_12"});
  EXPECT_EQ(any.channels, (std::vector<std::string>{"POSE_12", "XPOSE_1"}));
  EXPECT_EQ(any.times, (std::vector<std::int64_t>{77, 78}));
  d.unsubscribe(all);
  const Bytes cut = short_message(3, "POSE_1", {}, false);
  EXPECT_FALSE(d.feed(cut.data(), cut.size(), 1, 79));
  const Bytes orphan = fragment(4, 30, 10, 1, 3, nullptr, payload_of(10));
  EXPECT_FALSE(d.feed(orphan.data(), orphan.size(), 1, 80));
  EXPECT_EQ(d.malformed(), 1);
  EXPECT_EQ(d.dropped_fragments(), 1);
  EXPECT_EQ(any.channels.size(), 2u);
}

TEST(MalformedMessage, SizesAndNamesNoMessageCanHaveAreRefused) {
  const std::uint8_t b[4] = {};
  EXPECT_EQ(malformed_message("SENSOR_1", b, 4), nullptr);
  EXPECT_NE(malformed_message("SENSOR_1", b, 0xFFFFFFFFu), nullptr);  // LCM 1.3.1's -1
  EXPECT_NE(malformed_message("SENSOR_1", b, contract::kMaxMessageBytes + 1), nullptr);
  EXPECT_NE(malformed_message("SENSOR_1", nullptr, 4), nullptr);
  EXPECT_NE(malformed_message("", b, 4), nullptr);
  EXPECT_NE(malformed_message(std::string(64, 'A'), b, 4), nullptr);
  EXPECT_NE(malformed_message(std::string("SENSOR_1\0\0", 10), b, 4), nullptr);
  char out[4 * contract::kMaxChannelBytes + 8];
  EXPECT_STREQ(printable_channel(std::string("A\x01\xff"), out), "A\\x01\\xff");
}

TEST(UdpmUrl, LcmsSyntaxIsRead) {
  UdpmAddress a;
  std::string why;
  ASSERT_TRUE(parse_udpm_url("", &a, &why)) << why;
  EXPECT_EQ(a.port, 7667);
  char text[INET_ADDRSTRLEN];
  EXPECT_STREQ(inet_ntop(AF_INET, &a.group, text, sizeof text), "239.255.76.67");
  ASSERT_TRUE(parse_udpm_url("udpm://239.255.76.67:7701?ttl=0&recv_buf_size=8388608", &a, &why)) << why;
  EXPECT_EQ(a.port, 7701);
  EXPECT_EQ(a.recv_buf_size, 8388608);
  for (const char* bad : {"memq://", "udpm://10.0.0.1:7667", "udpm://239.255.76.67:0", "udpm://239.255.76.67:70000",
                          "udpm://239.255.76.67:x", "udpm://239.255.76.67:7667?recv_buf_size=-1"})
    EXPECT_FALSE(parse_udpm_url(bad, &a, &why)) << bad;
}

}  // namespace
}  // namespace elaslam::transport

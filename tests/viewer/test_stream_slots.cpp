// SPDX-License-Identifier: Apache-2.0
// ReadProgress and StreamSlots: which event stream's reader has stopped taking what is
// sent, and whose slot a new stream takes when all are held.
#include <chrono>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "elaslam/viewer/stream_slots.hpp"

namespace elaslam::viewer {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;

const StreamClock::time_point t0{};

TEST(ReadProgress, AReaderThatTakesEverythingNeverStalls) {
  ReadProgress p(t0);
  for (int i = 1; i <= 100; ++i) p.observe(0, 0, t0 + seconds(i));  // nothing ever waits
  EXPECT_FALSE(p.stalled());
  EXPECT_EQ(p.stalled_for(t0 + seconds(200)), StreamClock::duration::zero());
}

TEST(ReadProgress, ASlowReaderThatAcknowledgesIsNotStalled) {
  // GIVEN data always waiting (a slow link), but the peer acknowledging more each time
  ReadProgress p(t0);
  for (int i = 1; i <= 100; ++i) p.observe(50000, 1000ull * static_cast<unsigned>(i), t0 + seconds(i));
  EXPECT_FALSE(p.stalled());
}

TEST(ReadProgress, APeerThatAcknowledgesNothingWithDataWaitingStallsFromTheFirstSuchLook) {
  ReadProgress p(t0);
  p.observe(0, 1000, t0 + seconds(1));
  p.observe(300, 1200, t0 + seconds(2));  // more acknowledged: taking
  EXPECT_FALSE(p.stalled());
  p.observe(600, 1200, t0 + seconds(3));  // nothing more acknowledged, data waiting
  ASSERT_TRUE(p.stalled());
  EXPECT_EQ(p.stalled_since(), t0 + seconds(3));
  p.observe(900, 1200, t0 + seconds(4));
  p.observe(1200, 1200, t0 + seconds(5));
  EXPECT_EQ(p.stalled_for(t0 + seconds(8)), seconds(5));
  // WHEN it reads again THEN the stall ends
  p.observe(100, 2500, t0 + seconds(9));
  EXPECT_FALSE(p.stalled());
  p.observe(100, 2500, t0 + seconds(10));
  EXPECT_EQ(p.stalled_since(), t0 + seconds(10));
}

TEST(ReadProgress, WithoutAnAcknowledgedCountOnlyAnEmptyQueueIsProgress) {
  // A kernel without tcpi_bytes_acked: acked stays 0.
  ReadProgress p(t0);
  p.observe(0, 0, t0 + seconds(1));
  p.observe(500, 0, t0 + seconds(2));
  EXPECT_TRUE(p.stalled());
  p.observe(0, 0, t0 + seconds(3));
  EXPECT_FALSE(p.stalled());
}

/// A stream that records its eviction.
struct FakeStream : Evictable {
  void evict() override { ++evicted; }
  int evicted = 0;
};

class Slots : public ::testing::Test {
 protected:
  static constexpr int kMax = 8;
  Slots() : slots_(kMax, seconds(2)), streams_(40) {}
  /// Opens stream i from `peer` at second `at`.
  StreamSlots::Admit open(std::size_t i, const std::string& peer, int at) {
    return slots_.open(&streams_[i], peer, t0 + seconds(at));
  }
  int evicted() const {
    int n = 0;
    for (const auto& s : streams_) n += s.evicted;
    return n;
  }
  StreamSlots slots_;
  std::vector<FakeStream> streams_;
};

TEST_F(Slots, UpToTheMaximumThenANewOneFromTheSameAddressIsRefused) {
  for (std::size_t i = 0; i < kMax; ++i) EXPECT_EQ(open(i, "127.0.0.1", 0), StreamSlots::Admit::kOpened);
  EXPECT_EQ(slots_.size(), kMax);
  EXPECT_EQ(open(8, "127.0.0.1", 1), StreamSlots::Admit::kRefused);
  EXPECT_EQ(evicted(), 0);
  slots_.close(&streams_[3]);
  EXPECT_EQ(open(8, "127.0.0.1", 1), StreamSlots::Admit::kOpened);
}

TEST_F(Slots, TheStreamStalledLongestIsEvictedOnceStalledForEvictAfter) {
  for (std::size_t i = 0; i < kMax; ++i) open(i, "127.0.0.1", 0);
  slots_.set_stalled(&streams_[2], t0 + seconds(5));
  slots_.set_stalled(&streams_[6], t0 + seconds(4));  // the longest
  // Stalled 1.5 s: not yet.
  EXPECT_EQ(slots_.open(&streams_[8], "127.0.0.1", t0 + milliseconds(5500)), StreamSlots::Admit::kRefused);
  // Stalled 2 s and more: the longest goes.
  EXPECT_EQ(open(8, "127.0.0.1", 6), StreamSlots::Admit::kEvictedStalled);
  EXPECT_EQ(streams_[6].evicted, 1);
  EXPECT_EQ(evicted(), 1);
  EXPECT_EQ(slots_.size(), kMax);
  EXPECT_EQ(open(9, "127.0.0.1", 7), StreamSlots::Admit::kEvictedStalled);
  EXPECT_EQ(streams_[2].evicted, 1);
  EXPECT_EQ(slots_.evictions(), 2);
  // The evicted streams end later: closing them changes nothing.
  slots_.close(&streams_[6]);
  slots_.close(&streams_[2]);
  EXPECT_EQ(slots_.size(), kMax);
}

TEST_F(Slots, AStreamThatReadsAgainIsNoLongerEvictable) {
  for (std::size_t i = 0; i < kMax; ++i) open(i, "127.0.0.1", 0);
  slots_.set_stalled(&streams_[1], t0 + seconds(1));
  slots_.set_stalled(&streams_[1], std::nullopt);
  EXPECT_EQ(open(8, "127.0.0.1", 10), StreamSlots::Admit::kRefused);
}

TEST_F(Slots, OneAddressCannotKeepAnotherOut) {
  // GIVEN every slot held by one address (none stalled)
  for (std::size_t i = 0; i < kMax; ++i) open(i, "127.0.0.1", static_cast<int>(i));
  // WHEN another address comes THEN the first's oldest stream makes room
  EXPECT_EQ(open(8, "127.0.0.2", 20), StreamSlots::Admit::kEvictedFair);
  EXPECT_EQ(streams_[0].evicted, 1);
  // and the first address coming again is refused: it holds more already
  EXPECT_EQ(open(9, "127.0.0.1", 21), StreamSlots::Admit::kRefused);
  // The second address takes slots until the shares are even (4 and 4), then is
  // refused too: nobody takes turns.
  EXPECT_EQ(open(10, "127.0.0.2", 22), StreamSlots::Admit::kEvictedFair);
  EXPECT_EQ(open(11, "127.0.0.2", 23), StreamSlots::Admit::kEvictedFair);
  EXPECT_EQ(open(12, "127.0.0.2", 24), StreamSlots::Admit::kEvictedFair);
  EXPECT_EQ(open(13, "127.0.0.2", 25), StreamSlots::Admit::kRefused);
  EXPECT_EQ(open(14, "127.0.0.1", 26), StreamSlots::Admit::kRefused);
  EXPECT_EQ(evicted(), 4);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_EQ(streams_[i].evicted, 1) << "the oldest go first: " << i;
}

TEST_F(Slots, SharesSettleAmongThreeAddresses) {
  for (std::size_t i = 0; i < kMax; ++i) open(i, "10.0.0.1", static_cast<int>(i));
  int t = 10;
  std::size_t next = kMax;
  // Two more addresses keep asking, in turn, until both are refused.
  int refused_in_a_row = 0;
  while (refused_in_a_row < 2 && next < streams_.size()) {
    const std::string peer = next % 2 == 0 ? "10.0.0.2" : "10.0.0.3";
    refused_in_a_row = open(next++, peer, t++) == StreamSlots::Admit::kRefused ? refused_in_a_row + 1 : 0;
  }
  EXPECT_EQ(slots_.size(), kMax);
  EXPECT_LE(evicted(), 6);
  // No address holds two more than another that asked: 10.0.0.1 keeps at most 4.
  int first = 0;
  for (std::size_t i = 0; i < kMax; ++i) first += streams_[i].evicted == 0;
  EXPECT_LE(first, 4);
  EXPECT_GE(first, 2);
}

}  // namespace
}  // namespace elaslam::viewer

// SPDX-License-Identifier: Apache-2.0
// Message authentication (auth_transport.hpp): sign and verify, every reason a message
// is refused (no trailer, a key not the sender's, a signature that does not verify,
// the sender-channel binding, another mission, replays, counter jumps, stale
// incarnations), the decorator under the node shell, the keys and their files
// (keys.hpp), and the team: section (process.hpp: roster, mission, the node's key).
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <sodium.h>

#include "../support/test_keys.hpp"
#include "elaslam/common/config.hpp"
#include "elaslam/landmark_event_t.hpp"
#include "elaslam/node_status_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/transport/auth_transport.hpp"
#include "elaslam/transport/inprocess_transport.hpp"
#include "elaslam/transport/keys.hpp"
#include "elaslam/transport/lcm_transport.hpp"
#include "elaslam/transport/node_shell.hpp"
#include "elaslam/transport/process.hpp"

namespace elaslam::transport::auth {
namespace {

using test::kTestMission;
using test::team_key;
using test::team_setup;

/// An encoded message with room for the trailer.
template <class Msg>
std::vector<std::uint8_t> encoded(const Msg& m) {
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()) + kTrailerBytes);
  EXPECT_EQ(m.encode(buf.data(), 0, m.getEncodedSize()), m.getEncodedSize());
  buf.resize(static_cast<std::size_t>(m.getEncodedSize()));
  return buf;
}

landmark_event_t event(int robot) {
  landmark_event_t e{};
  e.robot_id = static_cast<std::int16_t>(robot);
  e.frame = 12;
  e.seq = 3;
  e.kind = landmark_event_t::ADD;
  e.landmark_id = 17;
  e.x = 1.5;
  e.y = -2.25;
  e.cov[0][0] = e.cov[1][1] = 0.01;
  return e;
}

/// One message with its trailer, on a channel, for receivers to open.
struct Sealed {
  std::string channel;
  std::vector<std::uint8_t> bytes;
};

Sealed seal(Authenticator& from, const std::string& channel, std::vector<std::uint8_t> payload) {
  const std::size_t n = payload.size();
  payload.resize(n + kTrailerBytes);
  payload.resize(from.seal(channel, payload.data(), n));
  return {channel, payload};
}

/// The trailer made here from its fields, independently of Authenticator::seal (the
/// wire format as docs/security.md states it), signed with `key`.
Sealed forge(const SigningKey& key, std::int16_t sender, std::uint32_t kid, std::uint64_t mission,
             std::int64_t incarnation, std::uint64_t counter, const std::string& channel,
             std::vector<std::uint8_t> payload) {
  const std::size_t n = payload.size();
  std::uint8_t h[kHeaderBytes];
  std::memcpy(h, "ELA2", 4);
  const auto put = [](std::uint8_t* p, std::uint64_t v, int bytes) {
    for (int i = bytes - 1; i >= 0; --i, v >>= 8) p[i] = static_cast<std::uint8_t>(v & 0xff);
  };
  put(h + 4, static_cast<std::uint16_t>(sender), 2);
  put(h + 6, kid, 4);
  put(h + 10, mission, 8);
  put(h + 18, static_cast<std::uint64_t>(incarnation), 8);
  put(h + 26, counter, 8);
  std::vector<std::uint8_t> signed_bytes;
  std::uint8_t len[4];
  put(len, channel.size(), 4);
  signed_bytes.insert(signed_bytes.end(), len, len + 4);
  signed_bytes.insert(signed_bytes.end(), channel.begin(), channel.end());
  signed_bytes.insert(signed_bytes.end(), payload.begin(), payload.end());
  signed_bytes.insert(signed_bytes.end(), h, h + kHeaderBytes);
  std::uint8_t digest[64], sig[64];
  crypto_hash_sha512(digest, signed_bytes.data(), signed_bytes.size());
  key.sign(digest, sig);
  payload.insert(payload.end(), h, h + kHeaderBytes);
  payload.insert(payload.end(), sig, sig + kSignatureBytes);
  EXPECT_EQ(payload.size(), n + kTrailerBytes);
  return {channel, payload};
}

Verdict open(Authenticator& to, const Sealed& s, std::size_t* payload = nullptr, std::int64_t now_us = 1000) {
  std::size_t n = 0;
  Sender who;
  const Verdict v = to.open(s.channel, s.bytes.data(), s.bytes.size(), &n, &who, 0, now_us);
  if (payload) *payload = n;
  return v;
}

std::int64_t refused(const Authenticator& a, Verdict v) { return a.counters().refused_by[static_cast<int>(v)]; }

class Auth : public ::testing::Test {
 protected:
  Authenticator robot1{team_setup(1, 1000)};
  Authenticator main{team_setup(kSenderMain, 2000)};
  Sealed ev() { return seal(robot1, "LMAP_EVENT", encoded(event(1))); }
};

TEST_F(Auth, SealThenOpenGivesThePayloadAndLcmDecodesTheSealedBytesAsTheyAre) {
  const auto payload = encoded(event(1));
  const Sealed s = ev();
  ASSERT_EQ(s.bytes.size(), payload.size() + kTrailerBytes);
  EXPECT_EQ(kTrailerBytes, 98u);
  std::size_t n = 0;
  EXPECT_EQ(open(main, s, &n), Verdict::kAccepted);
  EXPECT_EQ(n, payload.size());
  EXPECT_EQ(std::memcmp(s.bytes.data(), payload.data(), n), 0);
  EXPECT_EQ(std::memcmp(s.bytes.data() + n, "ELA2", 4), 0);
  // LCM's generated decoder reads what the type needs and ignores the trailer
  // (what recordings, lcm-spy and the Python tools rely on).
  landmark_event_t d{};
  ASSERT_EQ(d.decode(s.bytes.data(), 0, static_cast<int>(s.bytes.size())), static_cast<int>(payload.size()));
  EXPECT_EQ(d.landmark_id, 17);
  EXPECT_EQ(d.x, 1.5);
  EXPECT_EQ(main.counters().accepted, 1);
  EXPECT_EQ(robot1.counters().sealed, 1);
}

TEST_F(Auth, TheWireFormatIsTheDocumentedOne) {
  // A trailer made from the documented fields and digest verifies; Authenticator's own
  // trailer is byte for byte the one made here from the same fields.
  const auto payload = encoded(event(1));
  const Sealed mine = forge(team_key(1), 1, key_id(team_key(1).public_key()), kTestMission, 1000, 1, "LMAP_EVENT", payload);
  EXPECT_EQ(ev().bytes, mine.bytes);
  Authenticator fresh(team_setup(kSenderMain, 1));
  EXPECT_EQ(open(fresh, mine), Verdict::kAccepted);
}

TEST_F(Auth, AMessageWithoutATrailerIsUnauthenticated) {
  const Sealed plain{"LMAP_EVENT", encoded(event(1))};
  EXPECT_EQ(open(main, plain), Verdict::kUnauthenticated);
  const Sealed tiny{"LMAP_EVENT", {1, 2, 3}};
  EXPECT_EQ(open(main, tiny), Verdict::kUnauthenticated);
  Sealed old = ev();
  old.bytes[old.bytes.size() - kTrailerBytes + 3] = '1';  // "ELA1": the shared-key format
  EXPECT_EQ(open(main, old), Verdict::kUnauthenticated);
  EXPECT_EQ(refused(main, Verdict::kUnauthenticated), 3);
}

TEST_F(Auth, AFlippedByteAnywhereIsRefused) {
  const Sealed good = ev();
  const std::size_t t = good.bytes.size() - kTrailerBytes;
  for (std::size_t i = 0; i < good.bytes.size(); ++i) {
    if (i >= t && i < t + kMagicBytes) continue;
    Sealed s = good;
    s.bytes[i] ^= 0x01;
    Authenticator fresh(team_setup(kSenderMain, 1));
    // The sender id or the key id changed: no such key of that sender; anything else:
    // the signature does not verify.
    const bool names_key = i >= t + 4 && i < t + 10;
    EXPECT_EQ(open(fresh, s), names_key ? Verdict::kUnknownKey : Verdict::kForged) << "byte " << i;
  }
}

TEST_F(Auth, TheChannelNameIsCovered) {
  Sealed s = ev();
  s.channel = "LMAP_EVENU";
  EXPECT_EQ(open(main, s), Verdict::kForged);
  s.channel = "LMAP_EVENT_";  // the length prefix: a name is not its prefix
  EXPECT_EQ(open(main, s), Verdict::kForged);
}

// The attack of a shared key: one team member speaking as another. With keys of their
// own, robot 2 can sign only as robot 2.
TEST_F(Auth, AMemberCannotSpeakAsAnother) {
  const auto payload = encoded(event(1));
  const SigningKey robot2 = team_key(2);
  // Robot 2 signs robot 1's event, naming robot 1 and its own key: not robot 1's key.
  EXPECT_EQ(open(main, forge(robot2, 1, key_id(robot2.public_key()), kTestMission, 5, 1, "LMAP_EVENT", payload)),
            Verdict::kUnknownKey);
  // ... naming robot 1's key id: the signature is not robot 1's.
  EXPECT_EQ(open(main, forge(robot2, 1, key_id(team_key(1).public_key()), kTestMission, 5, 2, "LMAP_EVENT", payload)),
            Verdict::kForged);
  // ... as itself: its own key, but robot 1's channel or robot 1's event.
  pose_estimate_t p{};
  p.robot_id = 1;
  EXPECT_EQ(open(main, forge(robot2, 2, key_id(robot2.public_key()), kTestMission, 5, 3, "POSE_1", encoded(p))),
            Verdict::kWrongSender);
  EXPECT_EQ(open(main, forge(robot2, 2, key_id(robot2.public_key()), kTestMission, 5, 4, "LMAP_EVENT", payload)),
            Verdict::kWrongSender);
  // Main's notices and the simulator's frames: only with their keys.
  EXPECT_EQ(open(robot1, forge(robot2, kSenderMain, key_id(robot2.public_key()), kTestMission, 5, 5, "DYNAMIC_NOTICE",
                               encoded(p))),
            Verdict::kUnknownKey);
  EXPECT_EQ(open(robot1, forge(robot2, kSenderSimulator, key_id(team_key(kSenderSimulator).public_key()), kTestMission,
                               5, 6, "SENSOR_1", encoded(p))),
            Verdict::kForged);
  EXPECT_EQ(main.counters().accepted + robot1.counters().accepted, 0);
  // A node cannot even start as another: its key is not that sender's in the roster.
  AuthSetup s = team_setup(2, 1);
  s.sender_id = 1;
  EXPECT_THROW(Authenticator{std::move(s)}, std::invalid_argument);
}

TEST_F(Auth, AKeyOutsideTheRosterOrRevokedIsRefusedAndARotationAcceptsBothKeys) {
  const auto payload = encoded(event(1));
  const SigningKey outsider = test::test_key(999);
  EXPECT_EQ(open(main, forge(outsider, 1, key_id(outsider.public_key()), kTestMission, 5, 1, "LMAP_EVENT", payload)),
            Verdict::kUnknownKey);
  // Robot 1's key rotated: old and new both listed, both verify.
  AuthSetup r = team_setup(kSenderMain, 1);
  const SigningKey next = test::test_key(501);
  std::string why;
  ASSERT_TRUE(r.roster.add(1, next.public_key(), &why)) << why;
  Authenticator rotating(std::move(r));
  EXPECT_EQ(open(rotating, forge(next, 1, key_id(next.public_key()), kTestMission, 7, 1, "LMAP_EVENT", payload)),
            Verdict::kAccepted);
  EXPECT_EQ(open(rotating, forge(team_key(1), 1, key_id(team_key(1).public_key()), kTestMission, 7, 2, "LMAP_EVENT",
                                 payload)),
            Verdict::kAccepted);
  // The old key revoked: refused, the new one still taken.
  AuthSetup v = team_setup(kSenderMain, 1);
  ASSERT_TRUE(v.roster.add(1, next.public_key(), &why)) << why;
  ASSERT_TRUE(v.roster.revoke(team_key(1).public_key()));
  EXPECT_FALSE(v.roster.add(1, team_key(1).public_key(), &why));  // never again
  Authenticator revoking(std::move(v));
  EXPECT_EQ(open(revoking, forge(team_key(1), 1, key_id(team_key(1).public_key()), kTestMission, 8, 1, "LMAP_EVENT",
                                 payload)),
            Verdict::kUnknownKey);
  EXPECT_EQ(open(revoking, forge(next, 1, key_id(next.public_key()), kTestMission, 8, 2, "LMAP_EVENT", payload)),
            Verdict::kAccepted);
  // A third key for one sender, a key given to two senders, a point off the curve: refused.
  Roster roster = test::team_roster();
  EXPECT_FALSE(roster.add(2, team_key(3).public_key(), &why));
  ASSERT_TRUE(roster.add(2, next.public_key(), &why));
  EXPECT_FALSE(roster.add(2, test::test_key(502).public_key(), &why));
  PublicKey junk{};
  junk.fill(0xff);
  EXPECT_FALSE(roster.add(3, junk, &why));
}

TEST_F(Auth, AMessageOfAnotherMissionIsRefused) {
  const auto payload = encoded(event(1));
  const Sealed old = forge(team_key(1), 1, key_id(team_key(1).public_key()), kTestMission + 1, 1000, 1, "LMAP_EVENT", payload);
  EXPECT_EQ(open(main, old), Verdict::kOtherMission);
  EXPECT_EQ(refused(main, Verdict::kOtherMission), 1);
  EXPECT_EQ(open(main, ev()), Verdict::kAccepted);  // and it moved nothing
}

TEST_F(Auth, AReplayedMessageIsRefused) {
  const Sealed s = ev();
  EXPECT_EQ(open(main, s), Verdict::kAccepted);
  EXPECT_EQ(open(main, s), Verdict::kReplayed);
  EXPECT_EQ(refused(main, Verdict::kReplayed), 1);
}

TEST_F(Auth, ReorderedWithinTheWindowIsAcceptedOnce) {
  std::vector<Sealed> m;
  for (int i = 0; i < 10; ++i) m.push_back(ev());
  for (int i : {0, 5, 2, 9, 1, 3, 4, 8, 7, 6}) EXPECT_EQ(open(main, m[i]), Verdict::kAccepted) << i;
  for (int i = 0; i < 10; ++i) EXPECT_EQ(open(main, m[i]), Verdict::kReplayed) << i;
}

TEST_F(Auth, ACounterBelowTheWindowIsRefused) {
  const Sealed old = ev();
  for (int i = 0; i < kWindow; ++i) ASSERT_EQ(open(main, ev()), Verdict::kAccepted);
  // The newest is counter kWindow + 1: counter 1 is kWindow behind, just out.
  EXPECT_EQ(open(main, old), Verdict::kReplayed);
  // One inside the window that was never seen is still accepted.
  Authenticator main2(team_setup(kSenderMain, 1));
  std::vector<Sealed> m;
  for (int i = 0; i < kWindow + 10; ++i) m.push_back(ev());
  EXPECT_EQ(open(main2, m.back()), Verdict::kAccepted);
  EXPECT_EQ(open(main2, m[m.size() - kWindow]), Verdict::kAccepted);  // kWindow - 1 behind
  EXPECT_EQ(open(main2, m[m.size() - kWindow - 1]), Verdict::kReplayed);
}

TEST_F(Auth, AJumpWithinTheBoundSlidesTheWindow) {
  std::vector<Sealed> m;
  for (int i = 0; i < 3 * kWindow; ++i) m.push_back(ev());
  EXPECT_EQ(open(main, m[0]), Verdict::kAccepted);
  EXPECT_EQ(open(main, m[100]), Verdict::kAccepted);
  EXPECT_EQ(open(main, m[100 + 70]), Verdict::kAccepted);  // a shift of 70: across a word
  EXPECT_EQ(open(main, m[100]), Verdict::kReplayed);
  EXPECT_EQ(open(main, m[120]), Verdict::kAccepted);
  EXPECT_EQ(open(main, m[3 * kWindow - 1]), Verdict::kAccepted);
  EXPECT_EQ(open(main, m[170]), Verdict::kReplayed);  // now below the window
}

// One signed datagram with a far counter (2^64 - 9) must not make every later message
// of its sender a replay: it is held, the real stream goes on, and a real jump (a long
// partition) is taken at the sender's next message.
TEST_F(Auth, AFarCounterIsHeldAndNeverSilencesItsSender) {
  const auto payload = encoded(event(1));
  const SigningKey k = team_key(1);
  const std::uint32_t id = key_id(k.public_key());
  const auto msg = [&](std::uint64_t counter) {
    return forge(k, 1, id, kTestMission, 1000, counter, "LMAP_EVENT", payload);
  };
  for (std::uint64_t c = 1; c <= 40; ++c) ASSERT_EQ(open(main, msg(c)), Verdict::kAccepted);
  EXPECT_EQ(open(main, msg(~std::uint64_t{0} - 8)), Verdict::kJump);
  for (std::uint64_t c = 41; c <= 150; ++c) EXPECT_EQ(open(main, msg(c)), Verdict::kAccepted) << c;
  EXPECT_EQ(refused(main, Verdict::kJump), 1);
  // A partition longer than the bound: the first message after it is held, the next confirms.
  const std::uint64_t far = 150 + kMaxCounterJump + 1000;
  EXPECT_EQ(open(main, msg(far)), Verdict::kJump);
  EXPECT_EQ(open(main, msg(far + 3)), Verdict::kAccepted);
  EXPECT_EQ(main.counters().healed, 1);
  EXPECT_EQ(open(main, msg(far + 1)), Verdict::kAccepted);  // inside the window now
  EXPECT_EQ(open(main, msg(151)), Verdict::kReplayed);      // the old stream is far below
}

TEST_F(Auth, TwoLiveIncarnationsOfOneSenderAreBothAccepted) {
  // main_robot's duplicate-sender detection needs both processes' messages.
  Authenticator twin(team_setup(1, 1500));
  for (int i = 0; i < 20; ++i) {
    EXPECT_EQ(open(main, ev()), Verdict::kAccepted);
    EXPECT_EQ(open(main, seal(twin, "LMAP_EVENT", encoded(event(1)))), Verdict::kAccepted);
  }
}

TEST_F(Auth, AnOlderIncarnationIsStaleWhileItsSenderIsHeardAndTakenOnceItIsQuiet) {
  std::vector<std::unique_ptr<Authenticator>> inc;
  for (int i = 0; i < kIncarnations + 3; ++i) inc.push_back(std::make_unique<Authenticator>(team_setup(1, 100 + i)));
  const auto send = [&](int i, std::int64_t now) { return open(main, seal(*inc[i], "LMAP_EVENT", encoded(event(1))), nullptr, now); };
  std::int64_t now = 1000;
  for (int i = 2; i < 2 + kIncarnations; ++i) EXPECT_EQ(send(i, now), Verdict::kAccepted);  // 102..105 tracked
  EXPECT_EQ(send(1, now), Verdict::kStale);                              // 101: older than all, 105 just heard
  EXPECT_EQ(send(2 + kIncarnations, now), Verdict::kAccepted);           // 106: a restart; 102 is evicted
  EXPECT_EQ(send(2, now), Verdict::kStale);
  EXPECT_EQ(send(3, now), Verdict::kAccepted);  // still tracked
  EXPECT_EQ(refused(main, Verdict::kStale), 2);
  // The sender quiet for longer than kQuietUs, then back with an incarnation that went
  // back (its start count or clock reset): taken.
  now += kQuietUs + 1;
  EXPECT_EQ(send(0, now), Verdict::kAccepted);
  EXPECT_EQ(send(0, now + 1), Verdict::kAccepted);
}

TEST_F(Auth, ARobotMayPublishOnlyItsOwnChannelsAndItsOwnEvents) {
  Authenticator robot2(team_setup(2, 1));
  Authenticator sim(team_setup(kSenderSimulator, 1));
  pose_estimate_t p{};
  p.robot_id = 1;
  const auto pose = encoded(p);
  EXPECT_EQ(open(main, seal(robot1, "POSE_1", pose)), Verdict::kAccepted);
  EXPECT_EQ(open(main, seal(robot2, "POSE_1", pose)), Verdict::kWrongSender);
  EXPECT_EQ(open(main, seal(robot2, "STATUS_ROBOT_1", pose)), Verdict::kWrongSender);
  EXPECT_EQ(open(main, seal(robot2, "LMAP_EVENT", encoded(event(1)))), Verdict::kWrongSender);  // robot_id 1
  EXPECT_EQ(open(main, seal(robot2, "LMAP_EVENT", encoded(event(2)))), Verdict::kAccepted);
  EXPECT_EQ(open(main, seal(robot2, "DYNAMIC_NOTICE", pose)), Verdict::kWrongSender);
  EXPECT_EQ(open(main, seal(robot2, "GLOBAL_MAP", pose)), Verdict::kWrongSender);
  EXPECT_EQ(open(robot1, seal(robot2, "TEAM_MAP_1", pose)), Verdict::kWrongSender);  // main's alone
  EXPECT_EQ(open(robot1, seal(main, "TEAM_MAP_1", pose)), Verdict::kAccepted);
  EXPECT_EQ(open(main, seal(robot2, "CANDIDATES_1", pose)), Verdict::kWrongSender);  // robot 1's alone
  EXPECT_EQ(open(main, seal(robot1, "CANDIDATES_1", pose)), Verdict::kAccepted);
  EXPECT_EQ(open(main, seal(robot2, "TRACKS_1", pose)), Verdict::kWrongSender);  // robot 1's alone
  EXPECT_EQ(open(main, seal(sim, "TRACKS_1", pose)), Verdict::kWrongSender);
  EXPECT_EQ(open(main, seal(robot1, "TRACKS_1", pose)), Verdict::kAccepted);
  EXPECT_EQ(open(robot1, seal(robot2, "GLOBAL_TRACKS", pose)), Verdict::kWrongSender);  // main's alone
  EXPECT_EQ(open(robot1, seal(main, "GLOBAL_TRACKS", pose)), Verdict::kAccepted);
  EXPECT_EQ(open(main, seal(robot2, "SENSOR_2", pose)), Verdict::kWrongSender);
  EXPECT_EQ(open(main, seal(sim, "SENSOR_2", pose)), Verdict::kAccepted);
  EXPECT_EQ(open(main, seal(sim, "LMAP_EVENT", encoded(event(1)))), Verdict::kWrongSender);
  EXPECT_EQ(open(robot1, seal(main, "DYNAMIC_NOTICE", pose)), Verdict::kAccepted);
  EXPECT_EQ(open(main, seal(robot2, "SOME_TOOL_CHANNEL", pose)), Verdict::kAccepted);  // not a team channel
}

TEST_F(Auth, TheChannelSuffixIsPartOfTheBinding) {
  Authenticator main_s(team_setup(kSenderMain, 1, "_SIM2"));
  Authenticator robot2(team_setup(2, 1));
  pose_estimate_t p{};
  EXPECT_EQ(open(main_s, seal(robot1, "POSE_1_SIM2", encoded(p))), Verdict::kAccepted);
  EXPECT_EQ(open(main_s, seal(robot2, "POSE_1_SIM2", encoded(p))), Verdict::kWrongSender);
}

TEST_F(Auth, AReceiverWithoutAKeyVerifiesAndCannotSign) {
  Authenticator viewer(team_setup(kSenderTool, 0, "", false));
  EXPECT_FALSE(viewer.can_sign());
  EXPECT_EQ(open(viewer, ev()), Verdict::kAccepted);
  std::vector<std::uint8_t> buf(10 + kTrailerBytes);
  EXPECT_THROW(viewer.seal("X", buf.data(), 10), std::logic_error);
}

// ---- the transport decorator under the node shell -------------------------------------

TEST(AuthenticatedTransport, NodesTalkAndAnUnsignedForgedOrReplayedMessageNeverReachesAHandler) {
  InProcessTransport bus;
  AuthenticatedTransport robot_t(bus, team_setup(1, 10), "robot", nullptr);
  AuthenticatedTransport main_t(bus, team_setup(kSenderMain, 20), "main", nullptr);
  NodeShell robot(robot_t, ShellOptions("robot", "", nullptr));
  NodeShell main(main_t, ShellOptions("main", "", nullptr));
  std::vector<landmark_event_t> got;
  int also = 0;
  main.subscribe<landmark_event_t>("LMAP_EVENT", [&](const landmark_event_t& e, const std::string&) { got.push_back(e); },
                                   kUnboundedQueue);
  // A second subscription matching the same channel gets the same datagram: not a replay.
  main.subscribe<landmark_event_t>("LMAP_.*", [&](const landmark_event_t&, const std::string&) { ++also; },
                                   kUnboundedQueue);
  // A recorder on the bus sees the signed bytes: capture them to replay.
  std::vector<std::vector<std::uint8_t>> wire;
  bus.subscribe("LMAP_EVENT", [](const RawMessage& m, void* w) {
    static_cast<std::vector<std::vector<std::uint8_t>>*>(w)->emplace_back(m.data, m.data + m.size);
  }, &wire, kUnboundedQueue);

  ASSERT_TRUE(robot.publish("LMAP_EVENT", event(1)));
  bus.dispatch_all();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].landmark_id, 17);
  EXPECT_EQ(also, 1);
  ASSERT_EQ(wire.size(), 1u);
  EXPECT_EQ(main_t.counters().accepted, 2);  // once per subscription, one signature check

  // An outsider: plain LCM bytes, then a trailer signed with a key not in the roster.
  landmark_event_t forged = event(9);
  forged.x = forged.y = 100.0;
  auto plain = encoded(forged);
  bus.publish("LMAP_EVENT", plain.data(), plain.size());
  const SigningKey outsider = test::test_key(77);
  const Sealed s = forge(outsider, 9, key_id(outsider.public_key()), kTestMission, 1, 1, "LMAP_EVENT", plain);
  bus.publish("LMAP_EVENT", s.bytes.data(), s.bytes.size());
  // A genuine datagram replayed, and one altered in flight.
  bus.publish("LMAP_EVENT", wire[0].data(), wire[0].size());
  auto altered = wire[0];
  altered[30] ^= 0x40;
  bus.publish("LMAP_EVENT", altered.data(), altered.size());
  bus.dispatch_all();

  EXPECT_EQ(got.size(), 1u);
  EXPECT_EQ(also, 1);
  const AuthCounters& c = main_t.counters();
  // Two subscriptions: each refused datagram is counted once per subscription it reached.
  EXPECT_EQ(c.refused_by[static_cast<int>(Verdict::kUnauthenticated)], 2);
  EXPECT_EQ(c.refused_by[static_cast<int>(Verdict::kUnknownKey)], 2);
  EXPECT_EQ(c.refused_by[static_cast<int>(Verdict::kForged)], 2);
  EXPECT_EQ(c.refused_by[static_cast<int>(Verdict::kReplayed)], 2);
  EXPECT_EQ(main.counters().auth_refused, 8);
  EXPECT_EQ(main.counters().auth_unauthenticated, 2);
  EXPECT_EQ(main.counters().inputs.decode_errors, 0);  // nothing refused was decoded
}

// STATUS says when the transport refused anything since the last one
// (FAULT_INPUT_REFUSED), with one line at the start of a series.
TEST(AuthenticatedTransport, RefusalsSinceTheLastStatusAreFlagged) {
  InProcessTransport bus;
  AuthenticatedTransport main_t(bus, team_setup(kSenderMain, 20), "main", nullptr);
  NodeShell main(main_t, ShellOptions("main", "", nullptr));
  main.subscribe<landmark_event_t>("LMAP_EVENT", [](const landmark_event_t&, const std::string&) {}, kUnboundedQueue);
  node_status_t st{};
  main.stamp_auth(&st);
  EXPECT_FALSE(st.fault_flags & node_status_t::FAULT_INPUT_REFUSED);
  const auto plain = encoded(event(1));
  bus.publish("LMAP_EVENT", plain.data(), plain.size());
  bus.dispatch_all();
  st = node_status_t{};
  main.stamp_auth(&st);
  EXPECT_TRUE(st.fault_flags & node_status_t::FAULT_INPUT_REFUSED);
  EXPECT_EQ(st.auth_refused, 1);
  st = node_status_t{};
  main.stamp_auth(&st);  // none since: cleared
  EXPECT_FALSE(st.fault_flags & node_status_t::FAULT_INPUT_REFUSED);
  EXPECT_EQ(st.auth_refused, 1);
}

// The size LCM 1.3.1 reported for a cut datagram (-1): refused before a byte is read.
TEST(AuthenticatedTransport, AMessageOfAnImpossibleSizeIsRefusedUnread) {
  struct Stub final : Transport {
    RawHandler handler = nullptr;
    void* context = nullptr;
    bool good() const override { return true; }
    const char* kind() const override { return "stub"; }
    bool publish(const std::string&, const void*, std::size_t) override { return true; }
    int subscribe(const std::string&, RawHandler h, void* c, int) override { return handler = h, context = c, 1; }
    void unsubscribe(int) override {}
    int handle_timeout(int) override { return 0; }
  } stub;
  AuthenticatedTransport t(stub, team_setup(1, 1), "robot", nullptr);
  int handled = 0;
  t.subscribe("SENSOR_1", [](const RawMessage&, void* n) { ++*static_cast<int*>(n); }, &handled, 0);
  const std::string channel = "SENSOR_1";
  std::uint8_t few[9] = {};
  stub.handler(RawMessage{channel, few, 0xFFFFFFFFu}, stub.context);  // ASan: any read past `few` fails
  EXPECT_EQ(handled, 0);
  EXPECT_EQ(t.counters().refused_by[static_cast<int>(Verdict::kMalformed)], 1);
  EXPECT_EQ(t.refusals().malformed, 1);
}

TEST(AuthenticatedTransport, OverLcmMemqToo) {
  AuthenticatedTransport t(std::make_unique<LcmTransport>("memq://"), team_setup(kSenderSimulator, 1), "sim", nullptr);
  ASSERT_TRUE(t.good());
  NodeShell shell(t, ShellOptions("sim", "", nullptr));
  int poses = 0;
  shell.subscribe<pose_estimate_t>("POSE_[0-9]+", [&](const pose_estimate_t&, const std::string&) { ++poses; }, 0);
  pose_estimate_t p{};
  ASSERT_TRUE(shell.publish("POSE_1", p));  // the simulator may not publish a robot's pose
  while (t.handle_timeout(0) > 0) {
  }
  EXPECT_EQ(poses, 0);
  EXPECT_EQ(t.counters().refused_by[static_cast<int>(Verdict::kWrongSender)], 1);
}

// ---- the key files ---------------------------------------------------------------------

class KeyFile : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/elaslam_keyXXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    dir = tmpl;
  }
  void TearDown() override { std::filesystem::remove_all(dir); }
  void write(const std::string& path, const std::string& text, mode_t mode) {
    std::ofstream(path, std::ios::binary) << text;
    chmod(path.c_str(), mode);
  }
  std::string load(const std::string& path) {
    std::array<std::uint8_t, kKeyBytes> seed{};
    std::string why;
    return load_secret_key_file(path, &seed, &why) ? "" : why;
  }
  std::string dir;
};

/// build/bin/keys ARGS: its exit status, its standard output in *out.
int keys(const std::string& args, std::string* out = nullptr) {
  const std::string cmd = std::string(ELASLAM_BINARY_DIR) + "/bin/keys " + args + " 2>/dev/null";
  FILE* p = popen(cmd.c_str(), "r");
  std::string text;
  char buf[256];
  while (p != nullptr && std::fgets(buf, sizeof buf, p) != nullptr) text += buf;
  const int rc = p != nullptr ? pclose(p) : -1;
  if (out != nullptr) *out = text;
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

TEST_F(KeyFile, AKeyMadeByTheToolLoadsPrintsItsPublicKeyAndIsNeverOverwritten) {
  const std::string p = dir + "/node.key";
  std::string pub, again;
  ASSERT_EQ(keys("new '" + p + "'", &pub), 0);
  struct stat st {};
  ASSERT_EQ(stat(p.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  EXPECT_EQ(st.st_size, 65);
  EXPECT_EQ(load(p), "");
  SigningKey k;
  std::string why;
  ASSERT_TRUE(SigningKey::load(p, &k, &why)) << why;
  EXPECT_EQ(pub, to_hex(k.public_key().data(), kKeyBytes) + "\n");
  ASSERT_EQ(keys("public '" + p + "'", &again), 0);
  EXPECT_EQ(again, pub);
  std::string before;
  std::ifstream(p) >> before;
  EXPECT_EQ(keys("new '" + p + "'"), 1);
  std::string after;
  std::ifstream(p) >> after;
  EXPECT_EQ(before, after);
  // Two keys made are different; no temporary file is left behind.
  ASSERT_EQ(keys("new '" + dir + "/b.key'"), 0);
  std::string other;
  std::ifstream(dir + "/b.key") >> other;
  EXPECT_NE(before, other);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), std::filesystem::directory_iterator()), 2);
}

TEST_F(KeyFile, TheToolDoesNotWriteThroughASymlink) {
  const std::string target = dir + "/elsewhere", link = dir + "/node.key";
  ASSERT_EQ(symlink(target.c_str(), link.c_str()), 0);  // dangling
  EXPECT_EQ(keys("new '" + link + "'"), 1);
  EXPECT_FALSE(std::filesystem::exists(target));
  EXPECT_EQ(keys("new '" + dir + "/no/such/dir/k'"), 1);
  EXPECT_EQ(keys("new"), 2);
}

TEST_F(KeyFile, TheToolMakesATeamWhoseRosterVerifiesEveryMember) {
  std::string yaml;
  ASSERT_EQ(keys("team '" + dir + "/keys' --robots 1,2", &yaml), 0);
  for (const char* f : {"main.key", "simulator.key", "robot_1.key", "robot_2.key"}) EXPECT_EQ(load(dir + "/keys/" + f), "") << f;
  EXPECT_FALSE(std::filesystem::exists(dir + "/keys/robot_3.key"));
  // Its team.yaml as the config's roster file; each node signs with its own key.
  write(dir + "/c.yaml", "team:\n  key_file: " + dir + "/keys/{sender}.key\n  roster_file: keys/team.yaml\n", 0600);
  TransportArgs args;
  AuthSetup setup;
  bool on = false;
  ASSERT_TRUE(configured_auth(args, dir + "/c.yaml", "test", 2, true, &setup, &on));
  EXPECT_TRUE(on);
  EXPECT_EQ(setup.roster.size(), 4);
  EXPECT_NE(setup.mission, 0u);
  EXPECT_NE(yaml.find("mission:"), std::string::npos);
  EXPECT_EQ(keys("team '" + dir + "/keys' --robots 1"), 1);  // never over an existing team
  EXPECT_EQ(keys("team '" + dir + "/k2' --robots 17"), 2);
  std::string m1, m2;
  ASSERT_EQ(keys("mission", &m1), 0);
  ASSERT_EQ(keys("mission", &m2), 0);
  std::uint64_t v = 0;
  std::string why;
  EXPECT_TRUE(parse_mission(m1.substr(0, 16), &v, &why)) << m1;
  EXPECT_NE(m1, m2);
}

// The key of a node's own files (main's state) is its key's and its mission's: the same
// pair gives the same key at every start, another mission or another node another one, and
// it is neither zero nor the public key (a key derived with BLAKE2b keyed by the seed).
TEST(FileKey, DependsOnTheKeyAndTheMissionAndOnNothingElse) {
  const SigningKey a = test::test_key(1), b = test::test_key(2);
  const auto a1 = a.file_key(0x1122334455667788ULL);
  EXPECT_EQ(a1, test::test_key(1).file_key(0x1122334455667788ULL));
  EXPECT_NE(a1, a.file_key(0x1122334455667789ULL));  // one bit of the mission
  EXPECT_NE(a1, a.file_key(0x8877665544332211ULL));  // its bytes in another order
  EXPECT_NE(a1, b.file_key(0x1122334455667788ULL));
  const std::array<std::uint8_t, kKeyBytes> zero{};
  EXPECT_NE(a1, zero);
  const PublicKey pub = a.public_key();
  EXPECT_FALSE(std::equal(pub.begin(), pub.end(), a1.begin()));
}

TEST_F(KeyFile, RawAndHexKeysLoad) {
  write(dir + "/raw", std::string(32, '\x5a'), 0600);
  EXPECT_EQ(load(dir + "/raw"), "");
  write(dir + "/hex", std::string(64, 'a'), 0400);
  EXPECT_EQ(load(dir + "/hex"), "");
  write(dir + "/hexnl", std::string(64, 'B') + "\n", 0600);
  EXPECT_EQ(load(dir + "/hexnl"), "");
}

TEST_F(KeyFile, GroupOrOtherPermissionsAreRefused) {
  write(dir + "/k", std::string(64, 'a'), 0644);
  EXPECT_NE(load(dir + "/k").find("mode 0644"), std::string::npos) << load(dir + "/k");
  chmod((dir + "/k").c_str(), 0640);
  EXPECT_NE(load(dir + "/k"), "");
  chmod((dir + "/k").c_str(), 0604);
  EXPECT_NE(load(dir + "/k"), "");
}

TEST_F(KeyFile, ASymlinkADirectoryOrAMissingFileIsRefused) {
  write(dir + "/real", std::string(64, 'a'), 0600);
  ASSERT_EQ(symlink((dir + "/real").c_str(), (dir + "/link").c_str()), 0);
  EXPECT_NE(load(dir + "/link").find("symbolic link"), std::string::npos);
  std::filesystem::create_directory(dir + "/d");
  chmod((dir + "/d").c_str(), 0700);
  EXPECT_NE(load(dir + "/d"), "");
  EXPECT_NE(load(dir + "/none"), "");
}

TEST_F(KeyFile, AWrongLengthNonHexOrAllZeroKeyIsRefused) {
  write(dir + "/short", std::string(31, 'a'), 0600);
  EXPECT_NE(load(dir + "/short").find("has 31 bytes"), std::string::npos) << load(dir + "/short");
  write(dir + "/long", std::string(33, 'a'), 0600);
  EXPECT_NE(load(dir + "/long"), "");
  write(dir + "/hex63", std::string(63, 'a'), 0600);
  EXPECT_NE(load(dir + "/hex63"), "");
  write(dir + "/nothex", std::string(64, 'g'), 0600);
  EXPECT_NE(load(dir + "/nothex").find("not a key"), std::string::npos) << load(dir + "/nothex");
  write(dir + "/zero", std::string(64, '0'), 0600);
  EXPECT_NE(load(dir + "/zero").find("all zeros"), std::string::npos);
  write(dir + "/empty", "", 0600);
  EXPECT_NE(load(dir + "/empty"), "");
}

TEST_F(KeyFile, TheReasonNeverContainsTheKey) {
  const std::string hex = "00112233445566778899aabbccddeeff00112233445566778899aabbccddeeff";
  write(dir + "/k", hex, 0644);
  const std::string why = load(dir + "/k");
  EXPECT_NE(why, "");
  EXPECT_EQ(why.find("0011223344"), std::string::npos) << why;
}

// ---- the team: section ------------------------------------------------------------------

TEST_F(KeyFile, TheConfigNamesTheKeySenderByNameAndKeyFileOverridesIt) {
  write(dir + "/c.yaml", "team:\n  key_file: /etc/elaslam/keys/{sender}.key\n", 0600);
  write(dir + "/none.yaml", "robot: {}\n", 0600);
  write(dir + "/bad.yaml", "team:\n  key: /etc/elaslam/team.key\n", 0600);
  TransportArgs args;
  std::string origin;
  EXPECT_EQ(node_key_file(args, dir + "/c.yaml", "robot_2", &origin), "/etc/elaslam/keys/robot_2.key");
  EXPECT_EQ(node_key_file(args, dir + "/c.yaml", "main"), "/etc/elaslam/keys/main.key");
  EXPECT_NE(origin.find("team.key_file in"), std::string::npos);
  EXPECT_EQ(node_key_file(args, dir + "/none.yaml", "main"), "");
  EXPECT_EQ(node_key_file(args, "", "main"), "");
  EXPECT_THROW(node_key_file(args, dir + "/bad.yaml", "main"), config::ConfigError);  // unknown key team.key
  args.key_file = dir + "/mine.key";
  EXPECT_EQ(node_key_file(args, dir + "/c.yaml", "main", &origin), dir + "/mine.key");
  EXPECT_EQ(origin, "--key-file");
}

TEST_F(KeyFile, TheRosterTheMissionAndTheNodesOwnKeyAreCheckedAtStart) {
  const auto yaml = [&](const std::string& name, const std::string& team) { write(dir + "/" + name, team, 0600); };
  write(dir + "/robot_1.key", test::team_key_text(1), 0600);
  write(dir + "/robot_2.key", test::team_key_text(2), 0600);
  const std::string roster = test::team_yaml({1, kSenderMain});
  yaml("ok.yaml", roster + "  key_file: " + dir + "/{sender}.key\n");
  TransportArgs args;
  AuthSetup setup;
  bool on = false;
  std::string line;
  ASSERT_TRUE(configured_auth(args, dir + "/ok.yaml", "test", 1, true, &setup, &on, &line));
  EXPECT_TRUE(on);
  EXPECT_EQ(setup.mission, kTestMission);
  EXPECT_NE(line.find("signing as robot_1"), std::string::npos) << line;
  // A receiver needs no key; a sender without one, or whose key is another's, does not start.
  ASSERT_TRUE(configured_auth(args, dir + "/ok.yaml", "test", kSenderTool, false, &setup, &on));
  EXPECT_TRUE(on);
  EXPECT_FALSE(configured_auth(args, dir + "/ok.yaml", "test", 2, true, &setup, &on));  // robot_2 not in the roster
  args.key_file = dir + "/robot_2.key";
  EXPECT_FALSE(configured_auth(args, dir + "/ok.yaml", "test", 1, true, &setup, &on));  // not robot_1's key
  args.key_file.clear();
  // Its own key revoked: refused at start.
  yaml("revoked.yaml", roster + "  key_file: " + dir + "/{sender}.key\n  revoked: \"" +
                           to_hex(team_key(1).public_key().data(), kKeyBytes) + "\"\n");
  EXPECT_FALSE(configured_auth(args, dir + "/revoked.yaml", "test", 1, true, &setup, &on));
  // A roster needs a mission; --mission overrides it; bad ones are refused.
  yaml("nomission.yaml", "team:\n  public_keys:\n    main: \"" + to_hex(team_key(kSenderMain).public_key().data(), kKeyBytes) + "\"\n");
  EXPECT_FALSE(configured_auth(args, dir + "/nomission.yaml", "test", kSenderTool, false, &setup, &on));
  args.mission = "00000000000000ff";
  EXPECT_TRUE(configured_auth(args, dir + "/nomission.yaml", "test", kSenderTool, false, &setup, &on));
  EXPECT_EQ(setup.mission, 0xffu);
  args.mission = "0000000000000000";
  EXPECT_FALSE(configured_auth(args, dir + "/nomission.yaml", "test", kSenderTool, false, &setup, &on));
  args.mission = "xyz";
  EXPECT_FALSE(configured_auth(args, dir + "/nomission.yaml", "test", kSenderTool, false, &setup, &on));
  args.mission.clear();
  // Not keys, names that are no sender, the roster in two places: configuration errors.
  yaml("notkey.yaml", "team:\n  mission: \"0123456789abcdef\"\n  public_keys:\n    main: \"abc\"\n");
  EXPECT_FALSE(configured_auth(args, dir + "/notkey.yaml", "test", kSenderTool, false, &setup, &on));
  yaml("noname.yaml", "team:\n  mission: \"0123456789abcdef\"\n  public_keys:\n    robot_17: \"" +
                          to_hex(team_key(1).public_key().data(), kKeyBytes) + "\"\n");
  EXPECT_THROW(read_team_section(dir + "/noname.yaml"), config::ConfigError);
  yaml("roster.yaml", roster);
  yaml("both.yaml", roster + "  roster_file: roster.yaml\n");
  EXPECT_THROW(read_team_section(dir + "/both.yaml"), config::ConfigError);
  yaml("file.yaml", "team:\n  roster_file: roster.yaml\n");
  EXPECT_EQ(read_team_section(dir + "/file.yaml").public_keys.size(), 2u);
  // No roster: authentication off, whatever else is there.
  yaml("off.yaml", "team:\n  channel_groups: false\n");
  EXPECT_TRUE(configured_auth(args, dir + "/off.yaml", "test", 1, true, &setup, &on));
  EXPECT_FALSE(on);
}

// team.channel_groups (grouped_lcm_transport.hpp): off unless the config or
// --channel-groups turns it on; a bad value, or a URL without room for the groups'
// ports, is a configuration error (exit 2 at start), said with its reason.
TEST_F(KeyFile, ChannelGroupsComeFromTheConfigOrTheFlag) {
  write(dir + "/on.yaml", "team:\n  channel_groups: true\n", 0600);
  write(dir + "/both.yaml", "team:\n  key_file: /k\n  channel_groups: false\n", 0600);
  write(dir + "/none.yaml", "robot: {}\n", 0600);
  write(dir + "/bad.yaml", "team:\n  channel_groups: 7\n", 0600);
  EXPECT_TRUE(read_team_section(dir + "/on.yaml").channel_groups);
  EXPECT_FALSE(read_team_section(dir + "/both.yaml").channel_groups);
  EXPECT_EQ(read_team_section(dir + "/both.yaml").key_file, "/k");
  EXPECT_FALSE(read_team_section(dir + "/none.yaml").channel_groups);
  EXPECT_FALSE(read_team_section("").channel_groups);
  EXPECT_THROW(read_team_section(dir + "/bad.yaml"), config::ConfigError);

  TransportArgs args;
  args.lcm_url = "udpm://239.255.76.67:7700?ttl=0";
  bool on = true;
  EXPECT_TRUE(channel_groups_on(args, dir + "/none.yaml", "test", &on));
  EXPECT_FALSE(on);
  EXPECT_TRUE(channel_groups_on(args, dir + "/on.yaml", "test", &on));
  EXPECT_TRUE(on);
  args.channel_groups = true;  // --channel-groups
  EXPECT_TRUE(channel_groups_on(args, dir + "/both.yaml", "test", &on));
  EXPECT_TRUE(on);
  EXPECT_FALSE(channel_groups_on(args, dir + "/bad.yaml", "test", &on));  // the team: section is wrong
  args.lcm_url = "memq://";
  EXPECT_FALSE(channel_groups_on(args, dir + "/none.yaml", "test", &on));  // groups need udpm://
  args.lcm_url = "udpm://239.255.76.67:65530";
  EXPECT_FALSE(channel_groups_on(args, dir + "/none.yaml", "test", &on));  // ports past 65535
  args.channel_groups = false;
  EXPECT_TRUE(channel_groups_on(args, dir + "/none.yaml", "test", &on));  // off: the URL is LCM's business
  EXPECT_FALSE(on);
}

TEST_F(KeyFile, ASystemdCredentialIsTakenWhateverItsModeBits) {
  // systemd's copy (LoadCredential=) is the service's only, by an ACL that shows as
  // group bits, and root's shown as nobody under PrivateUsers=.
  write(dir + "/node.key", std::string(64, 'c'), 0640);
  write(dir + "/c.yaml", "team:\n  key_file: /etc/elaslam/keys/{sender}.key\n", 0600);
  write(dir + "/none.yaml", "robot: {}\n", 0600);
  EXPECT_NE(load(dir + "/node.key"), "");
  ASSERT_EQ(setenv("CREDENTIALS_DIRECTORY", dir.c_str(), 1), 0);
  EXPECT_EQ(load(dir + "/node.key"), "");
  TransportArgs args;
  EXPECT_EQ(node_key_file(args, dir + "/c.yaml", "robot_1"), dir + "/node.key");
  EXPECT_EQ(node_key_file(args, dir + "/none.yaml", "robot_1"), "");  // the config decides: no key named, none used
  std::filesystem::create_directory(dir + "/d");
  write(dir + "/d/node.key", std::string(64, 'c'), 0640);
  EXPECT_NE(load(dir + "/d/node.key"), "");  // only files directly in the directory
  unsetenv("CREDENTIALS_DIRECTORY");
}

}  // namespace
}  // namespace elaslam::transport::auth

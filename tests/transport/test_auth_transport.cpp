// Message authentication (auth_transport.hpp): seal and open, every reason a message
// is refused, the replay windows, the sender-channel binding, the transport decorator
// under the node shell, and the team key file's checks (team_key.hpp).
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "elaslam/landmark_event_t.hpp"
#include "elaslam/pose_estimate_t.hpp"
#include "elaslam/transport/auth_transport.hpp"
#include "elaslam/transport/inprocess_transport.hpp"
#include "elaslam/transport/lcm_transport.hpp"
#include "elaslam/common/config.hpp"
#include "elaslam/transport/node_shell.hpp"
#include "elaslam/transport/process.hpp"
#include "elaslam/transport/team_key.hpp"

namespace elaslam::transport::auth {
namespace {

TeamKey key_of(std::uint8_t seed) {
  std::array<std::uint8_t, TeamKey::kBytes> b{};
  for (std::size_t i = 0; i < b.size(); ++i) b[i] = static_cast<std::uint8_t>(seed + 7 * i + 1);
  return TeamKey(b);
}

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

/// One sender (`from`) sealing messages on a channel, for receivers to open.
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

Verdict open(Authenticator& to, const Sealed& s, std::size_t* payload = nullptr) {
  std::size_t n = 0;
  Sender who;
  const Verdict v = to.open(s.channel, s.bytes.data(), s.bytes.size(), &n, &who);
  if (payload) *payload = n;
  return v;
}

class Auth : public ::testing::Test {
 protected:
  TeamKey key = key_of(1);
  Authenticator robot1{key, 1, 1000};
  Authenticator main{key, kSenderMain, 2000};
  Sealed ev() { return seal(robot1, "LMAP_EVENT", encoded(event(1))); }
};

TEST_F(Auth, SealThenOpenGivesThePayloadAndLcmDecodesTheSealedBytesAsTheyAre) {
  const auto payload = encoded(event(1));
  const Sealed s = ev();
  ASSERT_EQ(s.bytes.size(), payload.size() + kTrailerBytes);
  EXPECT_EQ(kTrailerBytes, 54u);
  std::size_t n = 0;
  EXPECT_EQ(open(main, s, &n), Verdict::kAccepted);
  EXPECT_EQ(n, payload.size());
  EXPECT_EQ(std::memcmp(s.bytes.data(), payload.data(), n), 0);
  EXPECT_EQ(std::memcmp(s.bytes.data() + n, "ELA1", 4), 0);
  // LCM's generated decoder reads what the type needs and ignores the trailer
  // (what lcm-logger recordings, lcm-spy and the Python tools rely on).
  landmark_event_t d{};
  ASSERT_EQ(d.decode(s.bytes.data(), 0, static_cast<int>(s.bytes.size())), static_cast<int>(payload.size()));
  EXPECT_EQ(d.landmark_id, 17);
  EXPECT_EQ(d.x, 1.5);
  EXPECT_EQ(main.counters().accepted, 1);
  EXPECT_EQ(robot1.counters().sealed, 1);
}

TEST_F(Auth, AMessageWithoutATrailerIsUnauthenticated) {
  const Sealed plain{"LMAP_EVENT", encoded(event(1))};
  EXPECT_EQ(open(main, plain), Verdict::kUnauthenticated);
  const Sealed tiny{"LMAP_EVENT", {1, 2, 3}};
  EXPECT_EQ(open(main, tiny), Verdict::kUnauthenticated);
  EXPECT_EQ(main.counters().refused_by[static_cast<int>(Verdict::kUnauthenticated)], 2);
}

TEST_F(Auth, ABadMagicIsUnauthenticated) {
  Sealed s = ev();
  s.bytes[s.bytes.size() - kTrailerBytes] = 'X';
  EXPECT_EQ(open(main, s), Verdict::kUnauthenticated);
}

TEST_F(Auth, AFlippedByteAnywhereIsForged) {
  const Sealed good = ev();
  for (std::size_t i = 0; i < good.bytes.size(); ++i) {
    if (i >= good.bytes.size() - kTrailerBytes && i < good.bytes.size() - kTrailerBytes + kMagicBytes) continue;
    Sealed s = good;
    s.bytes[i] ^= 0x01;
    Authenticator fresh(key, kSenderMain, 1);
    EXPECT_EQ(open(fresh, s), Verdict::kForged) << "byte " << i;
  }
}

TEST_F(Auth, TheChannelNameIsCovered) {
  Sealed s = ev();
  s.channel = "LMAP_EVENU";
  EXPECT_EQ(open(main, s), Verdict::kForged);
  s.channel = "LMAP_EVENT_";  // the length prefix: a name is not its prefix
  EXPECT_EQ(open(main, s), Verdict::kForged);
}

TEST_F(Auth, AnotherKeyIsForged) {
  Authenticator other(key_of(2), kSenderMain, 1);
  EXPECT_EQ(open(other, ev()), Verdict::kForged);
}

TEST_F(Auth, AReplayedMessageIsRefused) {
  const Sealed s = ev();
  EXPECT_EQ(open(main, s), Verdict::kAccepted);
  EXPECT_EQ(open(main, s), Verdict::kReplayed);
  EXPECT_EQ(main.counters().refused_by[static_cast<int>(Verdict::kReplayed)], 1);
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
  Authenticator main2(key, kSenderMain, 1);
  std::vector<Sealed> m;
  for (int i = 0; i < kWindow + 10; ++i) m.push_back(ev());
  EXPECT_EQ(open(main2, m.back()), Verdict::kAccepted);
  EXPECT_EQ(open(main2, m[m.size() - kWindow]), Verdict::kAccepted);  // kWindow - 1 behind
  EXPECT_EQ(open(main2, m[m.size() - kWindow - 1]), Verdict::kReplayed);
}

TEST_F(Auth, AJumpAheadKeepsNothingOfTheOldWindow) {
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

TEST_F(Auth, TwoLiveIncarnationsOfOneSenderAreBothAccepted) {
  // main_robot's duplicate-sender detection needs both processes' messages.
  Authenticator twin(key, 1, 1500);
  for (int i = 0; i < 20; ++i) {
    EXPECT_EQ(open(main, ev()), Verdict::kAccepted);
    EXPECT_EQ(open(main, seal(twin, "LMAP_EVENT", encoded(event(1)))), Verdict::kAccepted);
  }
}

TEST_F(Auth, AnIncarnationOlderThanEveryOneTrackedIsRefusedANewerOneEvictsTheOldest) {
  std::vector<std::unique_ptr<Authenticator>> inc;
  for (int i = 0; i < kIncarnations + 2; ++i) inc.push_back(std::make_unique<Authenticator>(key, 1, 100 + i));
  auto send = [&](int i) { return open(main, seal(*inc[i], "LMAP_EVENT", encoded(event(1)))); };
  for (int i = 1; i <= kIncarnations; ++i) EXPECT_EQ(send(i), Verdict::kAccepted);  // 101..104 tracked
  EXPECT_EQ(send(0), Verdict::kStale);                                              // 100: older than all
  EXPECT_EQ(send(kIncarnations + 1), Verdict::kAccepted);  // 105: a restart; 101 is evicted
  EXPECT_EQ(send(1), Verdict::kStale);
  EXPECT_EQ(send(2), Verdict::kAccepted);  // still tracked
  EXPECT_EQ(main.counters().refused_by[static_cast<int>(Verdict::kStale)], 2);
}

TEST_F(Auth, ARobotMayPublishOnlyItsOwnChannelsAndItsOwnEvents) {
  Authenticator robot2(key, 2, 1);
  Authenticator sim(key, kSenderSimulator, 1);
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
  EXPECT_EQ(open(main, seal(robot2, "SENSOR_2", pose)), Verdict::kWrongSender);
  EXPECT_EQ(open(main, seal(sim, "SENSOR_2", pose)), Verdict::kAccepted);
  EXPECT_EQ(open(main, seal(sim, "LMAP_EVENT", encoded(event(1)))), Verdict::kWrongSender);
  EXPECT_EQ(open(robot1, seal(main, "DYNAMIC_NOTICE", pose)), Verdict::kAccepted);
  EXPECT_EQ(open(main, seal(robot2, "SOME_TOOL_CHANNEL", pose)), Verdict::kAccepted);  // not a team channel
  Authenticator stranger(key, 55, 1);  // not a team sender id
  EXPECT_EQ(open(main, seal(stranger, "SOME_TOOL_CHANNEL", pose)), Verdict::kWrongSender);
}

TEST_F(Auth, TheChannelSuffixIsPartOfTheBinding) {
  Authenticator main_s(key, kSenderMain, 1, "_SIM2");
  Authenticator robot2(key, 2, 1);
  pose_estimate_t p{};
  EXPECT_EQ(open(main_s, seal(robot1, "POSE_1_SIM2", encoded(p))), Verdict::kAccepted);
  EXPECT_EQ(open(main_s, seal(robot2, "POSE_1_SIM2", encoded(p))), Verdict::kWrongSender);
}

// ---- the transport decorator under the node shell -------------------------------------

TEST(AuthenticatedTransport, KeyedNodesTalkAndAnUnkeyedOrForgedOrReplayedMessageNeverReachesAHandler) {
  InProcessTransport bus;
  const TeamKey key = key_of(1);
  AuthenticatedTransport robot_t(bus, key, 1, 10, "", "robot", nullptr);
  AuthenticatedTransport main_t(bus, key, kSenderMain, 20, "", "main", nullptr);
  NodeShell robot(robot_t, ShellOptions("robot", "", nullptr));
  NodeShell main(main_t, ShellOptions("main", "", nullptr));
  std::vector<landmark_event_t> got;
  int also = 0;
  main.subscribe<landmark_event_t>("LMAP_EVENT", [&](const landmark_event_t& e, const std::string&) { got.push_back(e); },
                                   kUnboundedQueue);
  // A second subscription matching the same channel gets the same datagram: not a replay.
  main.subscribe<landmark_event_t>("LMAP_.*", [&](const landmark_event_t&, const std::string&) { ++also; },
                                   kUnboundedQueue);
  // A recorder on the bus (lcm-logger) sees the sealed bytes: capture them to replay.
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

  // An outsider without the key: plain LCM bytes, then a forged trailer.
  landmark_event_t forged = event(9);
  forged.x = forged.y = 100.0;
  auto plain = encoded(forged);
  bus.publish("LMAP_EVENT", plain.data(), plain.size());
  Authenticator outsider(key_of(99), 9, 1);
  const Sealed s = seal(outsider, "LMAP_EVENT", plain);
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
  EXPECT_EQ(c.refused_by[static_cast<int>(Verdict::kForged)], 4);
  EXPECT_EQ(c.refused_by[static_cast<int>(Verdict::kReplayed)], 2);
  EXPECT_EQ(main.counters().auth_refused, 8);
  EXPECT_EQ(main.counters().auth_unauthenticated, 2);
  EXPECT_EQ(main.counters().inputs.decode_errors, 0);  // nothing refused was decoded
}

TEST(AuthenticatedTransport, OverLcmMemqToo) {
  const TeamKey key = key_of(3);
  AuthenticatedTransport t(std::make_unique<LcmTransport>("memq://"), key, kSenderSimulator, 1, "", "sim", nullptr);
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

// ---- the key file ---------------------------------------------------------------------

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
    TeamKey k;
    std::string why;
    return load_team_key(path, &k, &why) ? "" : why;
  }
  std::string dir;
};

/// tools/make_team_key.sh PATH's exit status.
int make_key(const std::string& path) {
  const std::string cmd = std::string(ELASLAM_SOURCE_DIR) + "/tools/make_team_key.sh '" + path + "' 2>/dev/null";
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

TEST_F(KeyFile, AKeyMadeByTheToolLoadsAndIsNeverOverwritten) {
  const std::string p = dir + "/team.key";
  ASSERT_EQ(make_key(p), 0);
  struct stat st {};
  ASSERT_EQ(stat(p.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  EXPECT_EQ(st.st_size, 65);
  EXPECT_EQ(load(p), "");
  std::string before;
  std::ifstream(p) >> before;
  EXPECT_EQ(make_key(p), 1);
  std::string after;
  std::ifstream(p) >> after;
  EXPECT_EQ(before, after);
  // Two keys made are different; no temporary file is left behind.
  ASSERT_EQ(make_key(dir + "/b.key"), 0);
  std::string other;
  std::ifstream(dir + "/b.key") >> other;
  EXPECT_NE(before, other);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), std::filesystem::directory_iterator()), 2);
}

TEST_F(KeyFile, TheToolDoesNotWriteThroughASymlink) {
  const std::string target = dir + "/elsewhere", link = dir + "/team.key";
  ASSERT_EQ(symlink(target.c_str(), link.c_str()), 0);  // dangling
  EXPECT_EQ(make_key(link), 1);
  EXPECT_FALSE(std::filesystem::exists(target));
  EXPECT_EQ(make_key(dir + "/no/such/dir/k"), 1);
  EXPECT_EQ(make_key(""), 2);
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
  EXPECT_NE(load(dir + "/nothex").find("hexadecimal"), std::string::npos);
  write(dir + "/zero", std::string(64, '0'), 0600);
  EXPECT_NE(load(dir + "/zero").find("all zeros"), std::string::npos);
  write(dir + "/empty", "", 0600);
  EXPECT_NE(load(dir + "/empty"), "");
}

TEST_F(KeyFile, TheConfigNamesTheKeyAndKeyFileOverridesIt) {
  write(dir + "/c.yaml", "team:\n  key_file: /etc/elaslam/team.key\n", 0600);
  write(dir + "/none.yaml", "robot: {}\n", 0600);
  write(dir + "/bad.yaml", "team:\n  key: /etc/elaslam/team.key\n", 0600);
  TransportArgs args;
  std::string origin;
  EXPECT_EQ(team_key_file(args, dir + "/c.yaml", &origin), "/etc/elaslam/team.key");
  EXPECT_NE(origin.find("team.key_file in"), std::string::npos);
  EXPECT_EQ(team_key_file(args, dir + "/none.yaml"), "");
  EXPECT_EQ(team_key_file(args, ""), "");
  EXPECT_THROW(team_key_file(args, dir + "/bad.yaml"), config::ConfigError);  // unknown key team.key
  args.key_file = dir + "/mine.key";
  EXPECT_EQ(team_key_file(args, dir + "/c.yaml", &origin), dir + "/mine.key");
  EXPECT_EQ(origin, "--key-file");
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
  write(dir + "/team.key", std::string(64, 'c'), 0640);
  write(dir + "/c.yaml", "team:\n  key_file: /etc/elaslam/team.key\n", 0600);
  write(dir + "/none.yaml", "robot: {}\n", 0600);
  EXPECT_NE(load(dir + "/team.key"), "");
  ASSERT_EQ(setenv("CREDENTIALS_DIRECTORY", dir.c_str(), 1), 0);
  EXPECT_EQ(load(dir + "/team.key"), "");
  TransportArgs args;
  EXPECT_EQ(team_key_file(args, dir + "/c.yaml"), dir + "/team.key");
  EXPECT_EQ(team_key_file(args, dir + "/none.yaml"), "");  // the config decides: no key named, none used
  write(dir + "/sub.key", std::string(64, 'c'), 0640);
  std::filesystem::create_directory(dir + "/d");
  write(dir + "/d/team.key", std::string(64, 'c'), 0640);
  EXPECT_NE(load(dir + "/d/team.key"), "");  // only files directly in the directory
  unsetenv("CREDENTIALS_DIRECTORY");
}

TEST_F(KeyFile, TheReasonNeverContainsTheKey) {
  const std::string hex = "00112233445566778899aabbccddeeff00112233445566778899aabbccddeeff";
  write(dir + "/k", hex, 0644);
  const std::string why = load(dir + "/k");
  EXPECT_NE(why, "");
  EXPECT_EQ(why.find("0011223344"), std::string::npos) << why;
}

}  // namespace
}  // namespace elaslam::transport::auth

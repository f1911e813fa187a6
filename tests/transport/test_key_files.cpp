// SPDX-License-Identifier: Apache-2.0
// Making the team's keys (transport/key_files.hpp): new files never replace or follow
// anything, a key file loads with the public key it was made with, missions, the
// team's senders and its key files with their roster.
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "elaslam/transport/key_files.hpp"

namespace elaslam::transport {
namespace {

namespace fs = std::filesystem;

class KeyFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = (fs::temp_directory_path() / ("key_files_" + std::to_string(::getpid()))).string();
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }
  static unsigned mode_of(const std::string& p) {
    struct stat st {};
    return ::stat(p.c_str(), &st) == 0 ? st.st_mode & 0777 : 0;
  }
  static std::string text_of(const std::string& p) {
    std::ifstream in(p);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  std::string dir;
};

TEST_F(KeyFiles, ANewFileNeverReplacesOrFollowsAnything) {
  std::string why;
  ASSERT_TRUE(write_new_file(dir + "/a", "one\n", &why)) << why;
  EXPECT_EQ(mode_of(dir + "/a"), 0600u);
  EXPECT_FALSE(write_new_file(dir + "/a", "two\n", &why));
  EXPECT_EQ(why, dir + "/a: exists (a key is never overwritten)");
  EXPECT_EQ(text_of(dir + "/a"), "one\n");
  ASSERT_EQ(::symlink((dir + "/elsewhere").c_str(), (dir + "/link").c_str()), 0);
  EXPECT_FALSE(write_new_file(dir + "/link", "x", &why));
  EXPECT_FALSE(fs::exists(dir + "/elsewhere"));
  EXPECT_FALSE(write_new_file(dir + "/no/such/f", "x", &why));
  EXPECT_EQ(why.rfind("cannot create a file in " + dir + "/no/such: ", 0), 0u) << why;
  ASSERT_TRUE(write_new_file(dir + "/public", "p\n", &why, 0644));
  EXPECT_EQ(mode_of(dir + "/public"), 0644u);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 3);  // no temporary left
}

TEST_F(KeyFiles, AKeyFileLoadsWithItsPublicKey) {
  PublicKey pub{}, other{};
  std::string why;
  ASSERT_TRUE(make_key_file(dir + "/k.key", &pub, &why)) << why;
  EXPECT_EQ(text_of(dir + "/k.key").size(), 65u);
  SigningKey k;
  ASSERT_TRUE(SigningKey::load(dir + "/k.key", &k, &why)) << why;
  EXPECT_EQ(k.public_key(), pub);
  ASSERT_TRUE(make_key_file(dir + "/l.key", &other, &why));
  EXPECT_NE(other, pub);
  EXPECT_FALSE(make_key_file(dir + "/k.key", &other, &why));
}

TEST_F(KeyFiles, MissionsParseAndDiffer) {
  const std::string a = new_mission(), b = new_mission();
  std::uint64_t m = 0;
  std::string why;
  EXPECT_TRUE(parse_mission(a, &m, &why)) << why;
  EXPECT_NE(m, 0u);
  EXPECT_EQ(a.size(), 16u);
  EXPECT_NE(a, b);
}

TEST_F(KeyFiles, TeamSenders) {
  std::vector<std::int16_t> s;
  std::string why;
  ASSERT_TRUE(team_senders({1, 3}, true, &s, &why));
  EXPECT_EQ(s, (std::vector<std::int16_t>{kSenderMain, kSenderSimulator, 1, 3, kSenderTool}));
  EXPECT_FALSE(team_senders({1, 0}, false, &s, &why));
  EXPECT_EQ(why, "0 is not a robot id (1.." + std::to_string(kMaxRobotSenders) + ")");
}

TEST_F(KeyFiles, ATeamsKeysAndRoster) {
  std::string yaml, why;
  const std::string keys = dir + "/keys";
  ASSERT_TRUE(make_team_keys(keys, {kSenderMain, 2}, keys + "/team.yaml", &yaml, &why)) << why;
  EXPECT_EQ(mode_of(keys), 0700u);
  EXPECT_EQ(mode_of(keys + "/team.yaml"), 0644u);
  EXPECT_EQ(text_of(keys + "/team.yaml"), yaml);
  SigningKey main_key, robot_key;
  ASSERT_TRUE(SigningKey::load(keys + "/main.key", &main_key, &why)) << why;
  ASSERT_TRUE(SigningKey::load(keys + "/robot_2.key", &robot_key, &why)) << why;
  const std::string main_hex = to_hex(main_key.public_key().data(), kKeyBytes);
  const std::string robot_hex = to_hex(robot_key.public_key().data(), kKeyBytes);
  EXPECT_EQ(yaml.substr(0, 18), "team:\n  mission: \"");
  EXPECT_NE(yaml.find("\"\n  public_keys:\n    main: \"" + main_hex + "\"\n    robot_2: \"" + robot_hex + "\"\n"),
            std::string::npos)
      << yaml;
  // A second team in the same directory: the first key already there stops it.
  EXPECT_FALSE(make_team_keys(keys, {kSenderMain}, keys + "/other.yaml", &yaml, &why));
  EXPECT_EQ(why, keys + "/main.key: exists (a key is never overwritten)");
}

}  // namespace
}  // namespace elaslam::transport

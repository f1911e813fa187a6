// SPDX-License-Identifier: Apache-2.0
// The viewer's access token: the file's checks (as the team key's), making one, the
// comparison and who must show it.
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "elaslam/viewer/access_token.hpp"

namespace elaslam::viewer {
namespace {

namespace fs = std::filesystem;

const std::string kToken = "00112233445566778899aabbccddeeff00112233445566778899aabbccddeeff";

class TokenFile : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string t = (fs::temp_directory_path() / "viewer_token_XXXXXX").string();
    ASSERT_NE(::mkdtemp(t.data()), nullptr);
    dir_ = t;
  }
  void TearDown() override {
    ::unsetenv("CREDENTIALS_DIRECTORY");
    fs::remove_all(dir_);
  }
  std::string write(const std::string& name, const std::string& text, mode_t mode = 0600) {
    const std::string p = dir_ + "/" + name;
    std::ofstream(p) << text;
    ::chmod(p.c_str(), mode);
    return p;
  }
  /// load_access_token's verdict: "" when taken, else why not.
  static std::string why_not(const std::string& path, std::string* token = nullptr) {
    std::string t, why;
    if (load_access_token(path, &t, &why)) {
      if (token != nullptr) *token = t;
      return "";
    }
    EXPECT_NE(why.find(path), std::string::npos) << "the message names the file: " << why;
    return why;
  }
  std::string dir_;
};

TEST_F(TokenFile, AGoodFileIsTakenWithOrWithoutItsNewline) {
  std::string t;
  EXPECT_EQ(why_not(write("a", kToken + "\n"), &t), "");
  EXPECT_EQ(t, kToken);
  EXPECT_EQ(why_not(write("b", kToken, 0400), &t), "");
  EXPECT_EQ(t, kToken);
  const std::string longest(kTokenMaxHex, 'f');
  EXPECT_EQ(why_not(write("c", longest + "\n"), &t), "");
  EXPECT_EQ(t, longest);
}

TEST_F(TokenFile, GroupOrOthersMayNotReadIt) {
  for (const mode_t m : {0640, 0604, 0644, 0660, 0666}) {
    const std::string why = why_not(write("m" + std::to_string(m), kToken, m));
    EXPECT_NE(why.find("chmod 600"), std::string::npos) << why;
  }
}

TEST_F(TokenFile, ASymbolicLinkIsRefusedEvenToAGoodFile) {
  const std::string good = write("good", kToken);
  const std::string link = dir_ + "/link";
  ASSERT_EQ(::symlink(good.c_str(), link.c_str()), 0);
  EXPECT_NE(why_not(link).find("symbolic link"), std::string::npos);
}

TEST_F(TokenFile, NotARegularFileIsRefusedWithoutHanging) {
  EXPECT_NE(why_not(dir_).find("not a regular file"), std::string::npos);
  const std::string fifo = dir_ + "/fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_NE(why_not(fifo).find("not a regular file"), std::string::npos);
  EXPECT_NE(why_not(dir_ + "/missing").find("No such file"), std::string::npos);
}

TEST_F(TokenFile, AnotherUsersFileIsRefused) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to give a file to another user";
  const std::string p = write("theirs", kToken);
  ASSERT_EQ(::chown(p.c_str(), 65534, 65534), 0);
  EXPECT_NE(why_not(p).find("owned by uid 65534"), std::string::npos);
}

TEST_F(TokenFile, TheTextMustBeEnoughHexadecimalDigits) {
  EXPECT_NE(why_not(write("short", kToken.substr(0, kTokenMinHex - 2))).find("64 to 256"), std::string::npos);
  EXPECT_NE(why_not(write("odd", kToken + "a")).find("64 to 256"), std::string::npos);
  EXPECT_NE(why_not(write("long", std::string(kTokenMaxHex + 2, 'a'))).find("64 to 256"), std::string::npos);
  EXPECT_NE(why_not(write("huge", std::string(100000, 'a'))).find("too many"), std::string::npos);
  EXPECT_NE(why_not(write("nothex", "g" + kToken.substr(1))).find("hexadecimal"), std::string::npos);
  EXPECT_NE(why_not(write("space", kToken.substr(0, 32) + " " + kToken.substr(33))).find("hexadecimal"),
            std::string::npos);
  EXPECT_NE(why_not(write("twolines", kToken + "\n\n")).find("64 to 256"), std::string::npos);
  EXPECT_NE(why_not(write("zeros", std::string(64, '0'))).find("all zeros"), std::string::npos);
  EXPECT_NE(why_not(write("empty", "")).find("64 to 256"), std::string::npos);
}

TEST_F(TokenFile, ASystemdCredentialIsTakenWhateverItsMode) {
  const std::string p = write("viewer.token", kToken, 0644);
  EXPECT_NE(why_not(p), "");
  ::setenv("CREDENTIALS_DIRECTORY", dir_.c_str(), 1);
  EXPECT_EQ(why_not(p), "");
}

TEST_F(TokenFile, MakeWritesA0600FileThatLoads) {
  const std::string p = dir_ + "/made";
  std::string why;
  ASSERT_TRUE(make_access_token(p, &why)) << why;
  struct stat st {};
  ASSERT_EQ(::stat(p.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0600u);
  EXPECT_EQ(st.st_size, 65);
  std::string t;
  EXPECT_EQ(why_not(p, &t), "");
  EXPECT_EQ(t.size(), 64u);
  // Two tokens differ (32 random bytes each).
  std::string t2;
  ASSERT_TRUE(make_access_token(dir_ + "/made2", &why)) << why;
  EXPECT_EQ(why_not(dir_ + "/made2", &t2), "");
  EXPECT_NE(t, t2);
}

TEST_F(TokenFile, MakeEvenUnderAWideUmaskGives0600) {
  const mode_t old = ::umask(0);
  std::string why;
  const bool made = make_access_token(dir_ + "/wide", &why);
  ::umask(old);
  ASSERT_TRUE(made) << why;
  struct stat st {};
  ASSERT_EQ(::stat((dir_ + "/wide").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0600u);
}

TEST_F(TokenFile, MakeNeverOverwritesNorFollowsALink) {
  std::string why;
  const std::string existing = write("existing", "keep me");
  EXPECT_FALSE(make_access_token(existing, &why));
  EXPECT_NE(why.find("never overwritten"), std::string::npos) << why;
  std::ifstream in(existing);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, "keep me");
  // A dangling link: its target is not created.
  const std::string target = dir_ + "/target", link = dir_ + "/dangling";
  ASSERT_EQ(::symlink(target.c_str(), link.c_str()), 0);
  EXPECT_FALSE(make_access_token(link, &why));
  EXPECT_FALSE(fs::exists(target));
  EXPECT_FALSE(make_access_token(dir_ + "/no/such/dir/token", &why));
  EXPECT_NE(why.find("No such file"), std::string::npos) << why;
}

TEST(TokensEqual, OnlyTheSameTextIsEqual) {
  EXPECT_TRUE(tokens_equal(kToken, kToken));
  for (std::size_t i = 0; i < kToken.size(); ++i) {  // a difference anywhere
    std::string other = kToken;
    other[i] = other[i] == 'a' ? 'b' : 'a';
    EXPECT_FALSE(tokens_equal(kToken, other)) << i;
  }
  EXPECT_FALSE(tokens_equal(kToken, kToken.substr(0, 63)));
  EXPECT_FALSE(tokens_equal(kToken, kToken + "0"));
  EXPECT_FALSE(tokens_equal(kToken, kToken + kToken));  // wraps around: still longer
  EXPECT_FALSE(tokens_equal(kToken, ""));
  EXPECT_FALSE(tokens_equal("", ""));  // no token: nothing matches
}

TEST(BearerToken, TakesTheCredentialOfTheBearerScheme) {
  EXPECT_EQ(bearer_token("Bearer " + kToken), kToken);
  EXPECT_EQ(bearer_token("bearer   " + kToken + "  "), kToken);
  EXPECT_EQ(bearer_token("BEARER x"), "x");
  EXPECT_EQ(bearer_token("Basic dXNlcjpwYXNz"), "");
  EXPECT_EQ(bearer_token("Bearer"), "");
  EXPECT_EQ(bearer_token("Bearer "), "");
  EXPECT_EQ(bearer_token(""), "");
  EXPECT_EQ(bearer_token(kToken), "");
}

TEST(AccessPolicy, LoopbackNeedsNothingOthersTheToken) {
  const AccessPolicy with(kToken);
  EXPECT_TRUE(with.allows("127.0.0.1", "", ""));
  EXPECT_TRUE(with.allows("::1", "", ""));
  EXPECT_TRUE(with.allows("127.0.0.2", "", ""));
  EXPECT_FALSE(with.allows("10.200.0.2", "", ""));
  EXPECT_TRUE(with.allows("10.200.0.2", "Bearer " + kToken, ""));
  EXPECT_TRUE(with.allows("10.200.0.2", "", kToken));
  EXPECT_TRUE(with.allows("10.200.0.2", "Bearer wrong", kToken));
  EXPECT_FALSE(with.allows("10.200.0.2", "Bearer wrong", "wrong"));
  EXPECT_FALSE(with.allows("10.200.0.2", "Basic " + kToken, ""));
  EXPECT_FALSE(with.allows("10.200.0.2", "", kToken.substr(1)));
  const AccessPolicy without("");
  EXPECT_TRUE(without.allows("127.0.0.1", "", ""));
  EXPECT_FALSE(without.allows("10.200.0.2", "Bearer ", ""));
  EXPECT_FALSE(without.allows("10.200.0.2", "", ""));
}

}  // namespace
}  // namespace elaslam::viewer

// SPDX-License-Identifier: Apache-2.0
// Journal priorities (common/log.hpp): with $JOURNAL_STREAM naming stderr's device
// and inode (as systemd sets it for a service whose stderr is the journal), a refused
// message's line starts with SD_WARNING "<4>", a fatal one with SD_ERR "<3>"; without
// it, or when stderr is something else, the lines are plain text.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "elaslam/common/log.hpp"
#include "elaslam/dynamic_notice_t.hpp"
#include "elaslam/transport/inprocess_transport.hpp"
#include "elaslam/transport/node_shell.hpp"

namespace elaslam {
namespace {

std::string dev_ino(int fd) {
  struct stat st {};
  EXPECT_EQ(fstat(fd, &st), 0);
  return std::to_string(static_cast<unsigned long long>(st.st_dev)) + ":" +
         std::to_string(static_cast<unsigned long long>(st.st_ino));
}

/// stderr redirected into a temporary file for the fixture's life, read back by lines.
class CapturedStderr : public ::testing::Test {
 protected:
  void SetUp() override {
    std::fflush(stderr);
    file_ = std::tmpfile();
    ASSERT_NE(file_, nullptr);
    saved_ = dup(STDERR_FILENO);
    ASSERT_GE(dup2(fileno(file_), STDERR_FILENO), 0);
    unsetenv("JOURNAL_STREAM");
  }
  void TearDown() override {
    std::fflush(stderr);
    dup2(saved_, STDERR_FILENO);
    close(saved_);
    std::fclose(file_);
    unsetenv("JOURNAL_STREAM");
  }
  std::vector<std::string> lines() {
    std::fflush(stderr);
    std::vector<std::string> out;
    std::FILE* f = std::fopen(("/proc/self/fd/" + std::to_string(fileno(file_))).c_str(), "r");
    char buf[1024];
    while (f != nullptr && std::fgets(buf, sizeof buf, f)) out.emplace_back(buf);
    if (f != nullptr) std::fclose(f);
    return out;
  }
  /// A node shell logging to stderr, refusing every DYNAMIC_NOTICE.
  std::string refusal_line() {
    transport::InProcessTransport t;
    transport::NodeShell shell(t, transport::ShellOptions("robot_node 2", "", stderr));
    shell.subscribe<dynamic_notice_t>(
        "NOTICE", [](const dynamic_notice_t&, const std::string&) {}, 8,
        [](const dynamic_notice_t&, const std::string&) { return std::string("a notice from nowhere"); });
    shell.publish("NOTICE", dynamic_notice_t{});
    t.dispatch_all();
    const auto all = lines();
    return all.empty() ? "" : all.back();
  }
  std::FILE* file_ = nullptr;
  int saved_ = -1;
};

TEST_F(CapturedStderr, RefusalIsAWarningInTheJournal) {
  setenv("JOURNAL_STREAM", dev_ino(STDERR_FILENO).c_str(), 1);
  EXPECT_TRUE(log::is_journal(stderr));
  EXPECT_EQ(refusal_line(), "<4>robot_node 2: a notice from nowhere (warning 1)\n");
}

TEST_F(CapturedStderr, PlainTextWithoutJournalStream) {
  EXPECT_FALSE(log::is_journal(stderr));
  EXPECT_EQ(refusal_line(), "robot_node 2: a notice from nowhere (warning 1)\n");
}

TEST_F(CapturedStderr, PlainTextWhenTheJournalIsAnotherStream) {
  // systemd set it for the service, then stderr was redirected (a test, a pipe).
  setenv("JOURNAL_STREAM", dev_ino(STDOUT_FILENO) == dev_ino(STDERR_FILENO) ? "1:1" : dev_ino(STDOUT_FILENO).c_str(),
         1);
  EXPECT_FALSE(log::is_journal(stderr));
  EXPECT_EQ(refusal_line(), "robot_node 2: a notice from nowhere (warning 1)\n");
}

TEST_F(CapturedStderr, EveryLineGetsItsPriority) {
  setenv("JOURNAL_STREAM", dev_ino(STDERR_FILENO).c_str(), 1);
  log::print(stderr, log::Priority::kErr, "main_robot: %s\n", "cannot open LCM");
  log::print(stderr, log::Priority::kInfo, "a\nb\n");
  EXPECT_EQ(lines(), (std::vector<std::string>{"<3>main_robot: cannot open LCM\n", "<6>a\n", "<6>b\n"}));
}

TEST(JournalStream, MalformedValueIsNotTheJournal) {
  for (const char* v : {"", "12", "x:y", "1:2:3", "1:2x"}) {
    setenv("JOURNAL_STREAM", v, 1);
    EXPECT_FALSE(log::is_journal(stderr)) << v;
    EXPECT_STREQ(log::prefix(stderr, log::Priority::kWarning), "") << v;
  }
  unsetenv("JOURNAL_STREAM");
  EXPECT_FALSE(log::is_journal(nullptr));
}

}  // namespace
}  // namespace elaslam

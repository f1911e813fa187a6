// SPDX-License-Identifier: Apache-2.0
// A program under test as a child process (system tests), its stderr captured in
// a temporary file. Killed with SIGKILL on destruction if still running.
#pragma once

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

extern char** environ;

namespace elaslam::test {

class Child {
 public:
  /// `env`: changes to this process's environment for the child: "NAME=value" sets,
  /// "NAME" alone removes.
  Child(const std::string& program, std::vector<std::string> args, const std::vector<std::string>& env = {}) {
    char tmpl[] = "/tmp/elaslam_child_stderr_XXXXXX";
    const int fd = mkstemp(tmpl);
    EXPECT_GE(fd, 0);
    stderr_path_ = tmpl;
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, fd, STDERR_FILENO);
    args.insert(args.begin(), program);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    std::vector<std::string> vars;
    for (char** e = environ; *e; ++e) {
      const std::string v = *e;
      bool changed = false;
      for (const auto& c : env) changed = changed || v.compare(0, c.find('=') == std::string::npos ? c.size() + 1 : c.find('=') + 1,
                                                              c.substr(0, c.find('=')) + "=") == 0;
      if (!changed) vars.push_back(v);
    }
    for (const auto& c : env)
      if (c.find('=') != std::string::npos) vars.push_back(c);
    std::vector<char*> envp;
    for (auto& v : vars) envp.push_back(v.data());
    envp.push_back(nullptr);
    EXPECT_EQ(posix_spawn(&pid_, program.c_str(), &fa, nullptr, argv.data(), envp.data()), 0) << program;
    posix_spawn_file_actions_destroy(&fa);
    close(fd);
  }
  ~Child() {
    if (pid_ > 0 && !exited_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    unlink(stderr_path_.c_str());
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  /// Non-blocking: true once the child has exited (status in exit_code()).
  bool poll() {
    if (exited_ || pid_ <= 0) return true;
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) == pid_) {
      exited_ = true;
      exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    }
    return exited_;
  }
  /// Blocking wait, bounded: SIGKILL after timeout_ms. Returns the exit code.
  int wait(int timeout_ms = 10000) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    while (!poll()) {
      if (std::chrono::steady_clock::now() > end) {
        kill(pid_, SIGKILL);
        waitpid(pid_, nullptr, 0);
        exited_ = true;
        exit_code_ = 128 + SIGKILL;
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));  // polling a child, not synchronising
    }
    return exit_code_;
  }
  /// SIGTERM, then wait (bounded).
  int stop(int timeout_ms = 10000) {
    signal(SIGTERM);
    return wait(timeout_ms);
  }
  void signal(int sig) {
    if (!exited_) kill(pid_, sig);
  }
  int exit_code() const { return exit_code_; }
  std::string stderr_text() const {
    std::ifstream in(stderr_path_);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }

 private:
  pid_t pid_ = -1;
  bool exited_ = false;
  int exit_code_ = -1;
  std::string stderr_path_;
};

}  // namespace elaslam::test

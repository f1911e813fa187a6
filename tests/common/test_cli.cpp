// SPDX-License-Identifier: Apache-2.0
// The command-line rules every program shares (common/cli.hpp): the config lookup
// order and its errors, --version's text, the command line as provenance.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <limits>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <yaml-cpp/yaml.h>

#include "elaslam/common/cli.hpp"
#include "elaslam/common/config.hpp"
#include "elaslam/common/version.hpp"
#include "../support/expect_has.hpp"

namespace elaslam::cli {
namespace {

/// A file that exists (its path).
std::string touch(const std::string& name) {
  const std::string p = testing::TempDir() + "/" + name;
  std::ofstream(p) << "x: 1\n";
  return p;
}

std::string error_of(const ConfigPlaces& p) {
  try {
    find_config(p);
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(ConfigLookup, FirstPlaceThatAppliesWinsInTheDocumentedOrder) {
  const std::string given = touch("given.yaml"), env = touch("env.yaml"), sys = touch("system.yaml"),
                    inst = touch("installed.yaml");
  ConfigPlaces p{given, env, sys, inst};
  EXPECT_EQ(find_config(p).path, given);
  EXPECT_EQ(find_config(p).origin, "--config");
  p.given.clear();
  EXPECT_EQ(find_config(p).path, env);
  EXPECT_EQ(find_config(p).origin, "$ELASLAM_CONFIG");
  p.env.reset();
  EXPECT_EQ(find_config(p).path, sys);
  EXPECT_EQ(find_config(p).origin, sys);
  p.system = testing::TempDir() + "/no-such-system.yaml";
  EXPECT_EQ(find_config(p).path, inst);
  EXPECT_EQ(find_config(p).origin, "installed default");
}

TEST(ConfigLookup, APathThatWasAskedForNeverFallsThrough) {
  const std::string sys = touch("system2.yaml"), inst = touch("installed2.yaml");
  ConfigPlaces p{testing::TempDir() + "/missing.yaml", std::nullopt, sys, inst};
  EXPECT_NE(error_of(p).find("--config " + p.given + ": no such file"), std::string::npos) << error_of(p);
  p.given = testing::TempDir();  // a directory
  EXPECT_NE(error_of(p).find("not a regular file"), std::string::npos) << error_of(p);
  p.given.clear();
  p.env = testing::TempDir() + "/missing-env.yaml";
  EXPECT_NE(error_of(p).find("$ELASLAM_CONFIG=" + *p.env + ": no such file"), std::string::npos) << error_of(p);
}

TEST(ConfigLookup, NothingFoundListsEveryPlaceLookedAt) {
  ConfigPlaces p{"", std::nullopt, "/nonexistent/etc/elaslam.yaml", "/nonexistent/share/elaslam/config/paper.yaml"};
  const std::string e = error_of(p);
  for (const char* want : {"--config: not given", "$ELASLAM_CONFIG: not set", "/nonexistent/etc/elaslam.yaml: no such file",
                           "/nonexistent/share/elaslam/config/paper.yaml (installed default): no such file"})
    EXPECT_NE(e.find(want), std::string::npos) << want << "\n" << e;
}

TEST(ConfigLookup, InstalledDefaultIsBesideTheProgramsDirectory) {
  // This test program runs from <build>/tests: its prefix is <build>.
  EXPECT_EQ(data_dir(), std::string(ELASLAM_BINARY_DIR) + "/share/elaslam");
  EXPECT_EQ(python_tool("plot_sweep.py"), data_dir() + "/tools/plot_sweep.py");
}

TEST(Cli, VersionLineNamesProgramVersionAndCommit) {
  const std::string v = version_line("robot_node");
  EXPECT_EQ(v, std::string("robot_node (elaslam ") + version() + ", git " + git_commit() + ")");
  EXPECT_FALSE(std::string(git_commit()).empty());
}

TEST(Cli, CommandLineIsShellQuoted) {
  const char* argv[] = {"run_scenario", "--out", "my dir", "--config", "it's.yaml", "--seed", "3"};
  EXPECT_EQ(command_line(7, argv), "run_scenario --out 'my dir' --config 'it'\\''s.yaml' --seed 3");
}

// ---- parse: numeric options refuse nan, inf and out-of-range values ---------------

struct Parsed {
  int rc = 0;           // parse's result: -1 to go on, else the exit code
  std::string stderr_;  // what it printed there
};

/// A program's options: --speed with a range, --gain without one, --count (int).
struct Options {
  double speed = 1.0, gain = 1.0;
  int count = 1;
};

Parsed parse_args(std::vector<std::string> args, Options* o) {
  CLI::App app{"test"};
  app.add_option("--speed", o->speed, "[m/s]")->check(range(0.0, 1000.0));
  app.add_option("--gain", o->gain, "no range");
  app.add_option("--count", o->count, "items")->check(range(1, 100));
  args.insert(args.begin(), "prog");
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  testing::internal::CaptureStderr();
  testing::internal::CaptureStdout();
  Parsed p;
  p.rc = parse(app, static_cast<int>(argv.size()), argv.data());
  p.stderr_ = testing::internal::GetCapturedStderr();
  testing::internal::GetCapturedStdout();
  return p;
}

TEST(CliParse, ValidNumbersGoOn) {
  Options o;
  const Parsed p = parse_args({"--speed", "0.5", "--gain", "-3", "--count", "100"}, &o);
  EXPECT_EQ(p.rc, -1) << p.stderr_;
  EXPECT_DOUBLE_EQ(o.speed, 0.5);
  EXPECT_DOUBLE_EQ(o.gain, -3.0);
  EXPECT_EQ(o.count, 100);
  EXPECT_EQ(parse_args({"--speed", "0", "--count", "1"}, &o).rc, -1) << "the bounds are inside";
  EXPECT_EQ(parse_args({"--speed", "1000"}, &o).rc, -1) << "the bounds are inside";
}

TEST(CliParse, NanAndInfAreNotNumbersForAnyOption) {
  // CLI::Range let nan through (every comparison with it is false): the simulator
  // published landmarks at nan, robot_node divided a period of nan.
  for (const char* v : {"nan", "NaN", "-nan", "inf", "-inf", "infinity", "1e999"}) {
    for (const char* opt : {"--speed", "--gain"}) {
      Options o;
      const Parsed p = parse_args({opt, v}, &o);
      EXPECT_EQ(p.rc, kExitBadInput) << opt << " " << v;
      EXPECT_HAS(p.stderr_, std::string(opt) + ": " + v + " is not a finite number");
    }
    Options o;
    const Parsed p = parse_args({"--count", v}, &o);
    EXPECT_EQ(p.rc, kExitBadInput) << v;
    EXPECT_HAS(p.stderr_, "--count: ");
  }
}

TEST(CliParse, OutOfRangeNamesOptionAndRange) {
  Options o;
  Parsed p = parse_args({"--speed", "-5"}, &o);
  EXPECT_EQ(p.rc, kExitBadInput);
  EXPECT_HAS(p.stderr_, "--speed: -5 is out of range: expected a number in [0, 1000]");
  p = parse_args({"--speed", "1000.001"}, &o);
  EXPECT_EQ(p.rc, kExitBadInput);
  p = parse_args({"--count", "0"}, &o);
  EXPECT_EQ(p.rc, kExitBadInput);
  EXPECT_HAS(p.stderr_, "--count: 0 is out of range: expected a number in [1, 100]");
  p = parse_args({"--count", "2147483648"}, &o);  // beyond int, and beyond the range
  EXPECT_EQ(p.rc, kExitBadInput);
  EXPECT_HAS(p.stderr_, "--count: 2147483648 is out of range");
  p = parse_args({"--speed", "fast"}, &o);
  EXPECT_EQ(p.rc, kExitBadInput);
  EXPECT_HAS(p.stderr_, "--speed: fast is not a number");
  EXPECT_DOUBLE_EQ(o.speed, 1.0) << "a refused value is not stored";
}

TEST(CliParse, HelpAndVersionExitZero) {
  Options o;
  EXPECT_EQ(parse_args({"--help"}, &o).rc, kExitOk);
  EXPECT_EQ(parse_args({"--no-such-option"}, &o).rc, kExitBadInput);
}

// ---- guarded_main: no exception escapes main ---------------------------------------

struct Guarded {
  int rc;
  std::string stderr_;
};

Guarded guarded(const std::function<int()>& body) {
  testing::internal::CaptureStderr();
  const int rc = guarded_main("prog", body);
  return {rc, testing::internal::GetCapturedStderr()};
}

TEST(GuardedMain, ReturnsTheBodysExitCode) {
  EXPECT_EQ(guarded([] { return 0; }).rc, 0);
  EXPECT_EQ(guarded([] { return 7; }).rc, 7);
  EXPECT_EQ(guarded([] { return 0; }).stderr_, "");
}

TEST(GuardedMain, BadInputExitsTwoWithTheMessage) {
  Guarded g = guarded([]() -> int { throw config::ConfigError("a.yaml", {"robot.x: missing (required key)"}); });
  EXPECT_EQ(g.rc, kExitBadInput);
  EXPECT_EQ(g.stderr_, "prog: a.yaml: 1 configuration problem:\n  robot.x: missing (required key)\n");
  g = guarded([]() -> int { return YAML::Load("[a, b]").as<std::string>().size(); });  // YAML::TypedBadConversion
  EXPECT_EQ(g.rc, kExitBadInput);
  EXPECT_HAS(g.stderr_, "prog: configuration: yaml-cpp: error at line 1, column 1: bad conversion");
  g = guarded([]() -> int { throw std::invalid_argument("--speed: 'x' is not a number"); });
  EXPECT_EQ(g.rc, kExitBadInput);
  EXPECT_EQ(g.stderr_, "prog: --speed: 'x' is not a number\n");
}

TEST(GuardedMain, AnythingElseExitsOneAndSaysSo) {
  Guarded g = guarded([]() -> int { throw std::runtime_error("disk full"); });
  EXPECT_EQ(g.rc, kExitFailure);
  EXPECT_EQ(g.stderr_, "prog: error: disk full\n");
  g = guarded([]() -> int { throw std::bad_alloc(); });
  EXPECT_EQ(g.rc, kExitFailure);
  EXPECT_EQ(g.stderr_, "prog: out of memory\n");
  g = guarded([]() -> int { throw 42; });
  EXPECT_EQ(g.rc, kExitFailure);
  EXPECT_EQ(g.stderr_, "prog: error: an exception of unknown type\n");
}

}  // namespace
}  // namespace elaslam::cli

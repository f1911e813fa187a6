// The command-line rules every program shares (common/cli.hpp): the config lookup
// order and its errors, --version's text, the command line as provenance.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <string>

#include "elaslam/common/cli.hpp"
#include "elaslam/common/config.hpp"
#include "elaslam/common/version.hpp"

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

}  // namespace
}  // namespace elaslam::cli

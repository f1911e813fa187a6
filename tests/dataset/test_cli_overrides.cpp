// SPDX-License-Identifier: Apache-2.0
// The dataset: overrides on the command line (cli_overrides.hpp): an option given
// replaces the config's value, one not given leaves it; a value outside its limit is
// refused by the parser; a bad --robots list is refused with the reason and changes
// nothing.
#include "elaslam/dataset/cli_overrides.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace elaslam::mrclam {
namespace {

// Parses `args` (after the program name); the parser's exit code, -1 when it goes on.
int parse(std::vector<std::string> args, DatasetOverrides* d) {
  CLI::App app{"test"};
  add_options(app, d);
  args.insert(args.begin(), "test");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  try {
    app.parse(static_cast<int>(argv.size()), argv.data());
  } catch (const CLI::ParseError& e) {
    return e.get_exit_code();
  }
  return -1;
}

Options config() {
  Options o;
  o.rate_hz = 10.0;
  o.start_s = 5.0;
  o.duration_s = 60.0;
  o.robots = {1, 2, 3, 4, 5};
  return o;
}

TEST(DatasetOverrides, GivenOptionsOverrideTheConfigAndOthersLeaveIt) {
  DatasetOverrides d;
  ASSERT_EQ(parse({"--start", "0", "--robots", "2,4"}, &d), -1);
  Options o = config();
  std::string why;
  ASSERT_TRUE(apply(d, &o, &why)) << why;
  EXPECT_EQ(o.start_s, 0.0);  // given, even as the default value 0
  EXPECT_EQ(o.rate_hz, 10.0);
  EXPECT_EQ(o.duration_s, 60.0);
  EXPECT_EQ(o.robots, (std::vector<int>{2, 4}));
  DatasetOverrides none;
  ASSERT_EQ(parse({}, &none), -1);
  Options same = config();
  ASSERT_TRUE(apply(none, &same, &why));
  EXPECT_EQ(same.rate_hz, 10.0);
  EXPECT_EQ(same.start_s, 5.0);
  EXPECT_EQ(same.robots, config().robots);
}

TEST(DatasetOverrides, ValuesOutsideTheirLimitsAndBadRobotListsAreRefused) {
  DatasetOverrides d;
  EXPECT_NE(parse({"--rate", "0"}, &d), -1);
  DatasetOverrides far;
  EXPECT_NE(parse({"--duration", "1e9"}, &far), -1);
  DatasetOverrides bad;
  ASSERT_EQ(parse({"--robots", "1,x", "--rate", "20"}, &bad), -1);
  Options o = config();
  std::string why;
  EXPECT_FALSE(apply(bad, &o, &why));
  EXPECT_FALSE(why.empty());
  EXPECT_EQ(o.rate_hz, 10.0);  // nothing applied
  EXPECT_EQ(o.robots, config().robots);
}

}  // namespace
}  // namespace elaslam::mrclam

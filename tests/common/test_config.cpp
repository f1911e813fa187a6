// Config loading: every bad-config case is reported with its key path, all at once.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <string>

#include "elaslam/common/config.hpp"

namespace elaslam::config {
namespace {

struct Opts {
  double sigma_m = 0.0;
  int capacity = 0;
  bool joseph = false;
  std::string mode;
  double gate_probability = 0.99;  // optional, documented default
  std::vector<double> start;
  std::vector<int> ids;
};

void parse(Reader& r, Opts* o) {
  r.read("sigma_m", &o->sigma_m, 1e-6, 10.0);
  r.read("capacity", &o->capacity, 1, 512);
  r.read("joseph", &o->joseph);
  r.read_enum("mode", &o->mode, {"ekf", "gated"});
  r.read_optional("gate_probability", &o->gate_probability, 0.5, 0.999999);
  r.read_vector("start", &o->start, 3, -100.0, 100.0);
  r.list("robots", [&](Reader& item, std::size_t) {
    int id = 0;
    item.read("id", &id, 1, 8);
    o->ids.push_back(id);
  }, 1, 8);
}

const char* kGood = R"(
robot:
  sigma_m: 0.1
  capacity: 128
  joseph: true
  mode: gated
  start: [1, 2, 0.5]
  robots:
    - {id: 1}
    - {id: 2}
)";

// Parse `text`, return the error message ("" if it parsed).
std::string errors_of(const std::string& text, Opts* o = nullptr) {
  Opts local;
  try {
    Document doc = Document::from_string(text, "test.yaml");
    doc.section("robot", [&](Reader& r) { parse(r, o ? o : &local); });
    doc.finish();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto pos = s.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  return s.replace(pos, from.size(), to);
}

TEST(Config, GoodFileParsesWithDefaultsAndEcho) {
  Opts o;
  ASSERT_EQ(errors_of(kGood, &o), "");
  EXPECT_DOUBLE_EQ(o.sigma_m, 0.1);
  EXPECT_EQ(o.capacity, 128);
  EXPECT_TRUE(o.joseph);
  EXPECT_EQ(o.mode, "gated");
  EXPECT_DOUBLE_EQ(o.gate_probability, 0.99);
  ASSERT_EQ(o.start.size(), 3u);
  EXPECT_DOUBLE_EQ(o.start[2], 0.5);
  EXPECT_EQ(o.ids, (std::vector<int>{1, 2}));
}

TEST(Config, EffectiveConfigEchoesValuesAndDefaults) {
  Opts o;
  Document doc = Document::from_string(kGood, "test.yaml");
  doc.section("robot", [&](Reader& r) { parse(r, &o); });
  doc.finish();
  const YAML::Node eff = YAML::Load(doc.effective_yaml());
  EXPECT_DOUBLE_EQ(eff["robot"]["sigma_m"].as<double>(), 0.1);
  EXPECT_DOUBLE_EQ(eff["robot"]["gate_probability"].as<double>(), 0.99);  // default shown
  EXPECT_EQ(eff["robot"]["robots"][1]["id"].as<int>(), 2);
  EXPECT_EQ(eff["robot"]["start"].size(), 3u);
}

TEST(Config, MissingKeyNamed) {
  const std::string e = errors_of(replace(kGood, "  capacity: 128\n", ""));
  EXPECT_NE(e.find("robot.capacity: missing"), std::string::npos) << e;
}

TEST(Config, WrongTypeNamed) {
  const std::string e = errors_of(replace(kGood, "capacity: 128", "capacity: lots"));
  EXPECT_NE(e.find("robot.capacity: wrong type: expected an integer, got 'lots'"), std::string::npos) << e;
  const std::string e2 = errors_of(replace(kGood, "start: [1, 2, 0.5]", "start: 3"));
  EXPECT_NE(e2.find("robot.start: wrong type: expected a list of 3 numbers"), std::string::npos) << e2;
  const std::string e3 = errors_of(replace(kGood, "joseph: true", "joseph: maybe"));
  EXPECT_NE(e3.find("robot.joseph: wrong type: expected true or false"), std::string::npos) << e3;
}

TEST(Config, OutOfRangeNamed) {
  const std::string e = errors_of(replace(kGood, "sigma_m: 0.1", "sigma_m: -1"));
  EXPECT_NE(e.find("robot.sigma_m: out of range: got -1, expected a value in [1e-06, 10]"), std::string::npos)
      << e;
  const std::string e2 = errors_of(replace(kGood, "sigma_m: 0.1", "sigma_m: .nan"));
  EXPECT_NE(e2.find("robot.sigma_m: out of range"), std::string::npos) << e2;
  const std::string e3 = errors_of(replace(kGood, "{id: 2}", "{id: 9}"));
  EXPECT_NE(e3.find("robot.robots[1].id: out of range: got 9"), std::string::npos) << e3;
}

TEST(Config, UnknownKeyAndSectionNamed) {
  const std::string e = errors_of(replace(kGood, "  joseph: true\n", "  joseph: true\n  josef: true\n"));
  EXPECT_NE(e.find("robot.josef: unknown key"), std::string::npos) << e;
  const std::string e2 = errors_of(std::string(kGood) + "extra:\n  a: 1\n");
  EXPECT_NE(e2.find("extra: unknown section"), std::string::npos) << e2;
  const std::string e3 = errors_of(replace(kGood, "{id: 2}", "{id: 2, speed: 1}"));
  EXPECT_NE(e3.find("robot.robots[1].speed: unknown key"), std::string::npos) << e3;
}

TEST(Config, BadEnumListsChoices) {
  const std::string e = errors_of(replace(kGood, "mode: gated", "mode: fast"));
  EXPECT_NE(e.find("robot.mode: invalid value 'fast', expected one of: ekf, gated"), std::string::npos) << e;
}

TEST(Config, MalformedYamlGivesLine) {
  const std::string e = errors_of("robot:\n  sigma_m: [0.1\n  capacity: 3\n");
  EXPECT_NE(e.find("test.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("malformed YAML at line"), std::string::npos) << e;
}

TEST(Config, AllErrorsReportedAtOnce) {
  std::string text = replace(kGood, "sigma_m: 0.1", "sigma_m: 50");
  text = replace(text, "capacity: 128", "capacity: x");
  text = replace(text, "mode: gated", "mode: y");
  try {
    Document doc = Document::from_string(text, "test.yaml");
    Opts o;
    doc.section("robot", [&](Reader& r) { parse(r, &o); });
    doc.finish();
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.problems().size(), 3u) << e.what();
    EXPECT_NE(std::string(e.what()).find("test.yaml: 3 configuration problems"), std::string::npos);
  }
}

TEST(Config, MissingSectionAndMissingFile) {
  EXPECT_NE(errors_of("other: {}\n").find("robot: missing (required section)"), std::string::npos);
  try {
    Document::from_file("/nonexistent/elaslam.yaml");
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/elaslam.yaml: 1 configuration problem"),
              std::string::npos);
  }
}

TEST(Config, FromFileReadsAFile) {
  const std::string path = ::testing::TempDir() + "/elaslam_cfg_test.yaml";
  {
    std::ofstream out(path);
    out << kGood;
  }
  Opts o;
  Document doc = Document::from_file(path);
  doc.section("robot", [&](Reader& r) { parse(r, &o); });
  EXPECT_NO_THROW(doc.finish());
  EXPECT_EQ(o.capacity, 128);
  std::remove(path.c_str());
}

}  // namespace
}  // namespace elaslam::config

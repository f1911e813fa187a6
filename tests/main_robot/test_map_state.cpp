// SPDX-License-Identifier: Apache-2.0
// main_robot's state file (map_state.hpp): sealed, bounded, checked; a refused file
// is moved aside to PATH.corrupt and main starts fresh. Each case of the review
// (docs/security.md, "main_robot's state file") against the file functions the process calls.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>

#include <nlohmann/json.hpp>

#include "elaslam/landmark_event_t.hpp"
#include "elaslam/main_robot/map_state.hpp"
#include "global_event.hpp"
#include "../support/read_file.hpp"

// The largest single heap allocation since reset_largest_allocation()
// (largest_allocation.cpp: a counting operator new).
std::size_t largest_allocation();
void reset_largest_allocation();

namespace elaslam {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using test::read_file;

GlobalMapOptions options() {
  GlobalMapOptions o;
  o.max_landmark_id = 32;
  return o;
}

GlobalEvent ev(int robot, std::int64_t seq, int kind, int id, double x, double y, int frame) {
  Eigen::Matrix2d cov;
  cov << 0.02, 0.003, 0.003, 0.01;
  return test::global_event(robot, seq, kind, id, {x, y}, cov, frame);
}

// A map with a bit of everything: three robots with incarnations, fused and single
// estimates, a moving landmark, an unconfirmed moving one, a pending gap repair.
GlobalMap team_map() {
  GlobalMap m(options());
  std::vector<Notice> n;
  for (int r = 1; r <= 3; ++r) m.observe_incarnation(r, 1700000000000000 + r, 0);
  m.apply(ev(1, 1, landmark_event_t::ADD, 2, 1.0, 1.5, 3), &n);
  m.apply(ev(2, 1, landmark_event_t::ADD, 2, 1.1, 1.4, 3), &n);
  m.apply(ev(2, 2, landmark_event_t::ADD, 9, -3.0, 4.0, 4), &n);
  m.apply(ev(3, 1, landmark_event_t::ADD, 17, 7.25, -2.5, 5), &n);
  m.apply(ev(1, 2, landmark_event_t::MOVING, 9, 0.0, 0.0, 6), &n);
  m.apply_snapshot(3, 4, 8, {{17, RobotEstimate{true, {7.3, -2.5}, Eigen::Matrix2d::Identity() * 0.01, 8}}}, {5}, &n);
  m.apply(ev(1, 5, landmark_event_t::ADD, 20, 0.5, 0.5, 9), &n);  // seq 3, 4 lost: a gap
  EXPECT_TRUE(m.stream(1).gap_pending);
  EXPECT_TRUE(m.entry(5).moving_unconfirmed);
  return m;
}

StateKey key_of(std::uint8_t fill) {
  StateKey k;
  k.fill(fill);
  k[0] = 0x5a;
  return k;
}

void write_file(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f << text;
}

// A hand edit: the body taken out of a sealed file (opened with `key`), changed by
// `edit`, and sealed again with `reseal_key` (nullptr: the unkeyed hash anyone can
// recompute).
std::string hand_edited(const std::string& sealed, const StateKey* key, const std::function<void(json&)>& edit,
                        const StateKey* reseal_key = nullptr) {
  std::string_view body;
  std::string why;
  EXPECT_TRUE(open_state(sealed, kMapStateFormat, kMapStateVersion, key, &body, &why)) << why;
  json j = json::parse(body);
  edit(j);
  return seal_state(kMapStateFormat, kMapStateVersion, j.dump(1), reseal_key);
}

class MapStateFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           ("map_state_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    path_ = (dir_ / "global_map.json").string();
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Loads path_ into a fresh map: the outcome, and the map in *out.
  MapStateLoad load(const StateKey* key, GlobalMap* out) { return load_map_state(path_, key, out); }

  // GIVEN `text` at path_ WHEN main starts THEN it starts fresh, the file moved aside
  // as it was, and `why` names the problem.
  void expect_refused(const std::string& text, const StateKey* key, const std::string& why_has) {
    write_file(path_, text);
    GlobalMap m(options());
    const MapStateLoad r = load(key, &m);
    EXPECT_EQ(r.outcome, MapStateOutcome::kFreshAfterDamage) << r.line;
    EXPECT_NE(r.why.find(why_has), std::string::npos) << r.why;
    EXPECT_EQ(m.to_json(), GlobalMap(options()).to_json());  // fresh: nothing of the file
    EXPECT_FALSE(fs::exists(path_));
    EXPECT_EQ(r.aside, path_ + ".corrupt");
    EXPECT_EQ(read_file(path_ + ".corrupt"), text);
    EXPECT_NE(r.line.find("moved aside to " + path_ + ".corrupt"), std::string::npos) << r.line;
  }

  fs::path dir_;
  std::string path_;
};

TEST_F(MapStateFile, ARoundTripGivesTheSameMapKeyedAndUnkeyed) {
  const GlobalMap saved = team_map();
  const StateKey key = key_of(7);
  for (const StateKey* k : {static_cast<const StateKey*>(nullptr), &key}) {
    std::string why;
    ASSERT_TRUE(save_map_state(path_, saved, k, &why)) << why;
    EXPECT_EQ(read_file(path_).rfind(std::string("{\"format\":\"elaslam.global_map\",\"version\":2,\"seal\":\"") +
                                         (k ? "blake2b-256-keyed" : "blake2b-256") + "\"",
                                     0),
              0u);
    GlobalMap loaded(options());
    const MapStateLoad r = load(k, &loaded);
    ASSERT_EQ(r.outcome, MapStateOutcome::kResumed) << r.line;
    EXPECT_NE(r.line.find("resumed from " + path_), std::string::npos) << r.line;
    EXPECT_EQ(loaded.to_json(), saved.to_json());
    EXPECT_EQ(loaded.version(), saved.version());
    for (int robot = 1; robot <= 3; ++robot) {
      EXPECT_EQ(loaded.stream(robot).incarnation, saved.stream(robot).incarnation);
      EXPECT_EQ(loaded.stream(robot).last_seq, saved.stream(robot).last_seq);
    }
    EXPECT_TRUE(loaded.stream(1).gap_pending);
    EXPECT_TRUE(loaded.entry(2).fused.isApprox(saved.entry(2).fused, 1e-15));
    EXPECT_TRUE(loaded.entry(5).moving_unconfirmed);
  }
  // The file stays one JSON document: a tool reads the map under "state".
  const json doc = json::parse(read_file(path_));
  EXPECT_EQ(doc.at("state").at("version"), saved.version());
}

// Every landmark shifted 5 m consistently and the hash recomputed: with a state key
// the file is refused (an unkeyed hash, or one keyed with another key, cannot pass);
// without one it loads — the documented limit of an unkeyed seal.
TEST_F(MapStateFile, AConsistentFiveMetreShiftIsRefusedWithAKey) {
  const StateKey key = key_of(7), forger = key_of(8);
  std::string why;
  ASSERT_TRUE(save_map_state(path_, team_map(), &key, &why)) << why;
  const std::string good = read_file(path_);
  const auto shift = [](json& j) {
    for (json& l : j["landmarks"]) {
      for (json& e : l["estimates"]) e["x"] = e["x"].get<double>() + 5.0;
      if (l.contains("fused")) l["fused"]["x"] = l["fused"]["x"].get<double>() + 5.0;
    }
  };
  expect_refused(hand_edited(good, &key, shift), &key, "sealed without a key while a state key is configured");
  expect_refused(hand_edited(good, &key, shift, &forger), &key, "the MAC does not verify");
  // The same edit of an unkeyed file, with no key configured: accepted (docs/security.md, "main_robot's state file").
  ASSERT_TRUE(save_map_state(path_, team_map(), nullptr, &why)) << why;
  write_file(path_, hand_edited(read_file(path_), nullptr, shift));
  GlobalMap m(options());
  ASSERT_EQ(load(nullptr, &m).outcome, MapStateOutcome::kResumed);
  EXPECT_NEAR(m.entry(2).fused.x(), team_map().entry(2).fused.x() + 5.0, 1e-9);
}

// One bit flipped anywhere in the file — header, MAC, body, closing line — and the
// file does not open; the map is left as it was.
TEST_F(MapStateFile, ABitFlipAnywhereIsRefused) {
  const StateKey key = key_of(3);
  for (const StateKey* k : {static_cast<const StateKey*>(nullptr), &key}) {
    GlobalMap small(options());
    small.apply(ev(1, 1, landmark_event_t::ADD, 4, 2.0, 3.0, 1), nullptr);
    std::string text, why;
    ASSERT_TRUE(seal_map_state(small, k, &text, &why)) << why;
    GlobalMap target(options());
    const std::string before = target.to_json();
    int opened = 0;
    for (std::size_t at = 0; at < text.size(); ++at) {
      for (int bit = 0; bit < 8; ++bit) {
        std::string flipped = text;
        flipped[at] = static_cast<char>(flipped[at] ^ (1 << bit));
        opened += open_map_state(flipped, k, &target, &why);
      }
    }
    EXPECT_EQ(opened, 0) << "of " << 8 * text.size() << " flips";
    EXPECT_EQ(target.to_json(), before);
    ASSERT_TRUE(open_map_state(text, k, &target, &why)) << why;  // the unflipped file opens
  }
  // Through the file: moved aside, fresh start.
  ASSERT_TRUE(save_map_state(path_, team_map(), &key, nullptr));
  std::string damaged = read_file(path_);
  damaged[damaged.size() / 2] ^= 0x10;
  expect_refused(damaged, &key, "the MAC does not verify");
}

// A seq or incarnation of 2^62 in the file made main refuse the robot's real events
// as old (a lock-out). Beyond the file's bounds now: refused, fresh start, the
// robot's events apply. The bounds themselves load.
TEST_F(MapStateFile, ASeqOrIncarnationBeyondTheFileBoundsIsRefused) {
  std::string why;
  ASSERT_TRUE(save_map_state(path_, team_map(), nullptr, &why)) << why;
  const std::string good = read_file(path_);
  const auto set = [](const char* key, std::int64_t v) { return [=](json& j) { j["robots"][1][key] = v; }; };
  const std::int64_t int64_max = std::numeric_limits<std::int64_t>::max();
  expect_refused(hand_edited(good, nullptr, set("last_seq", std::int64_t{1} << 62)), nullptr, "robot 2's seq");
  expect_refused(hand_edited(good, nullptr, set("snapshot_seq", (std::int64_t{1} << 40) + 1)), nullptr, "snapshot seq");
  expect_refused(hand_edited(good, nullptr, set("incarnation", int64_max)), nullptr, "robot 2's incarnation");
  expect_refused(hand_edited(good, nullptr, set("incarnation", 0)), nullptr, "incarnation not in [1, ");
  expect_refused(hand_edited(good, nullptr, set("last_frame", -2)), nullptr, "last_frame not in [-1, ");
  expect_refused(hand_edited(good, nullptr, [](json& j) { j["landmarks"][0]["status_frame"] = -1; }), nullptr,
                 "status_frame not in [0, ");
  expect_refused(hand_edited(good, nullptr, [](json& j) { j["version"] = (std::int64_t{1} << 62) + 1; }), nullptr,
                 "version is not an integer in [0, 4611686018427387904]");
  // After the refusal the robot's real stream goes on.
  GlobalMap fresh(options());
  EXPECT_EQ(fresh.apply(ev(2, 3, landmark_event_t::ADD, 6, 1.0, 1.0, 12), nullptr), EventResult::kAppliedAfterGap);
  // At the bounds: loads.
  write_file(path_, hand_edited(good, nullptr, [](json& j) {
               j["robots"][1]["last_seq"] = std::int64_t{1} << 40;
               j["robots"][1]["incarnation"] = std::int64_t{1} << 62;
             }));
  GlobalMap m(options());
  ASSERT_EQ(load(nullptr, &m).outcome, MapStateOutcome::kResumed);
  EXPECT_EQ(m.stream(2).last_seq, std::int64_t{1} << 40);
}

// A map that messages pushed beyond the file's bounds is not saved: the file there
// stays one the loader accepts.
TEST_F(MapStateFile, AMapBeyondTheFileBoundsIsNotSaved) {
  std::string why;
  ASSERT_TRUE(save_map_state(path_, team_map(), nullptr, &why)) << why;
  const std::string before = read_file(path_);
  GlobalMap m = team_map();
  m.apply(ev(2, (std::int64_t{1} << 40) + 1, landmark_event_t::ADD, 6, 1.0, 1.0, 12), nullptr);
  EXPECT_FALSE(save_map_state(path_, m, nullptr, &why));
  EXPECT_NE(why.find("robot 2's seq 1099511627777 is beyond 2^40"), std::string::npos) << why;
  EXPECT_EQ(read_file(path_), before);
  GlobalMap n = team_map();
  n.observe_incarnation(3, (std::int64_t{1} << 62) + 1, 20);
  EXPECT_FALSE(save_map_state(path_, n, nullptr, &why));
  EXPECT_NE(why.find("incarnation"), std::string::npos) << why;
  // A save that cannot be written says why and leaves nothing.
  EXPECT_FALSE(save_map_state((dir_ / "no_such_dir" / "m.json").string(), team_map(), nullptr, &why));
  EXPECT_NE(why.find("cannot create a temporary file"), std::string::npos) << why;
}

// A landmark id listed twice merged two landmarks' estimates into one. Refused now,
// and so is a robot's estimate listed twice in one landmark.
TEST_F(MapStateFile, ADuplicatedLandmarkIdIsRefusedNotMerged) {
  std::string why;
  ASSERT_TRUE(save_map_state(path_, team_map(), nullptr, &why)) << why;
  const std::string good = read_file(path_);
  const auto twice = [](json& j) {
    json copy = j["landmarks"][2];  // another landmark, now under the id of the first
    copy["id"] = j["landmarks"][0]["id"];
    j["landmarks"].push_back(copy);
  };
  expect_refused(hand_edited(good, nullptr, twice), nullptr, "listed twice (refused, not merged)");
  const auto robot_twice = [](json& j) {
    json& est = j["landmarks"][0]["estimates"];
    est.push_back(est[0]);
  };
  expect_refused(hand_edited(good, nullptr, robot_twice), nullptr, "robot 1: listed twice");
}

// A 50 MB file took 213 MB to load. Refused now by its size alone, before any of it
// is read: no allocation near its size (a sparse file: no disk used).
TEST_F(MapStateFile, AFileBeyondTheSizeBoundIsRefusedWithoutReadingIt) {
  const off_t big = 50 * 1000 * 1000;
  {
    const int fd = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::ftruncate(fd, big), 0);
    ::close(fd);
  }
  GlobalMap m(options());
  reset_largest_allocation();
  const MapStateLoad r = load(nullptr, &m);
  const std::size_t largest = largest_allocation();
  EXPECT_EQ(r.outcome, MapStateOutcome::kFreshAfterDamage);
  EXPECT_NE(r.why.find("is 50000000 bytes, more than the " + std::to_string(max_map_state_bytes(options())) + " accepted"),
            std::string::npos)
      << r.why;
  EXPECT_LT(largest, std::size_t{64} * 1024) << "the file was read";
  EXPECT_EQ(fs::file_size(path_ + ".corrupt"), static_cast<std::uintmax_t>(big));
  // One byte over the bound is refused; the bound itself is read.
  const std::size_t bound = max_map_state_bytes(options());
  write_file(path_, std::string(bound + 1, ' '));
  EXPECT_EQ(load(nullptr, &m).outcome, MapStateOutcome::kFreshAfterDamage);
  write_file(path_, std::string(bound, ' '));
  const MapStateLoad at = load(nullptr, &m);
  EXPECT_EQ(at.outcome, MapStateOutcome::kFreshAfterDamage);
  EXPECT_NE(at.why.find("no seal header"), std::string::npos) << at.why;  // read, then refused for what it is
}

// The bound is not tighter than the largest map the configuration allows: every id,
// every robot's estimate, every number at its longest, every frame 2147483647.
TEST_F(MapStateFile, TheSizeBoundHoldsTheLargestMap) {
  GlobalMapOptions o = options();
  o.max_landmark_id = 8;
  const double longest = -1.2345678901234567e-300;  // 24 characters
  json j = json::parse(GlobalMap(o).to_json());
  j["version"] = std::int64_t{1} << 62;
  j["newest_frame"] = 2147483647;
  for (json& r : j["robots"]) {
    r = {{"last_seq", std::int64_t{1} << 40}, {"last_frame", 2147483647}, {"incarnation", std::int64_t{1} << 62},
         {"snapshot_seq", std::int64_t{1} << 40}, {"snapshot_frame", 2147483647}, {"repair_seq", std::int64_t{1} << 40}};
  }
  for (int id = 0; id < o.max_landmark_id; ++id) {
    json est = json::array();
    for (int r = 1; r <= kMaxTeamRobots; ++r)
      est.push_back({{"robot", r}, {"frame", 2147483647}, {"x", longest}, {"y", longest},
                     {"cov", {1.2345678901234567e-05, longest, longest, 1.2345678901234567e-05}}});
    j["landmarks"].push_back({{"id", id}, {"status", 1}, {"status_frame", 2147483647}, {"moving_by", 16},
                              {"estimates", est}, {"history_unknown", true}});
  }
  GlobalMap m(o), one_less(o);
  std::string why, text;
  ASSERT_TRUE(m.from_json(j.dump(1), &why)) << why;
  ASSERT_TRUE(seal_map_state(m, nullptr, &text, &why)) << why;
  EXPECT_LE(text.size(), max_map_state_bytes(o));
  j["landmarks"].erase(j["landmarks"].size() - 1);
  ASSERT_TRUE(one_less.from_json(j.dump(1), &why)) << why;
  const std::size_t per_landmark = m.to_json().size() - one_less.to_json().size();
  EXPECT_GT(per_landmark, 4000u);
  EXPECT_LE(per_landmark * 5 / 4, kMaxLandmarkRecordBytes) << per_landmark << " bytes a landmark: the margin is gone";
  GlobalMap back(o);
  EXPECT_TRUE(open_map_state(text, nullptr, &back, &why)) << why;
  // The figures map_state.hpp states.
  o.max_landmark_id = 256;
  EXPECT_EQ(max_map_state_bytes(o), 1578146u);
  EXPECT_EQ(max_map_state_bytes(options()), 201890u);
}

// A link planted at PATH.corrupt is replaced, never written through.
TEST_F(MapStateFile, ASymlinkAtTheCorruptNameIsNotFollowed) {
  const std::string victim = (dir_ / "victim").string();
  write_file(victim, "precious\n");
  ASSERT_EQ(::symlink(victim.c_str(), (path_ + ".corrupt").c_str()), 0);
  expect_refused("{\"format\": \"elaslam.global_map.v1\"}\n", nullptr, "no seal header");
  EXPECT_EQ(read_file(victim), "precious\n");
  struct stat st{};
  ASSERT_EQ(::lstat((path_ + ".corrupt").c_str(), &st), 0);
  EXPECT_TRUE(S_ISREG(st.st_mode));
  // An existing PATH.corrupt (a refusal before) is replaced the same way.
  expect_refused("second\n", nullptr, "no seal header");
}

TEST_F(MapStateFile, AMissingFileStartsFreshWithoutComplaint) {
  GlobalMap m(options());
  const MapStateLoad r = load(nullptr, &m);
  EXPECT_EQ(r.outcome, MapStateOutcome::kMissing);
  EXPECT_TRUE(r.why.empty()) << r.why;
  EXPECT_NE(r.line.find("no state file"), std::string::npos) << r.line;
  EXPECT_FALSE(fs::exists(path_ + ".corrupt"));
  EXPECT_EQ(m.version(), 0);
}

TEST_F(MapStateFile, AFileSavedWithOneKeyIsRefusedWithAnother) {
  const StateKey a = key_of(1), b = key_of(2);
  std::string why;
  ASSERT_TRUE(save_map_state(path_, team_map(), &a, &why)) << why;
  expect_refused(read_file(path_), &b, "the MAC does not verify: the file was altered or damaged (or sealed with another state key)");
  ASSERT_TRUE(save_map_state(path_, team_map(), &a, &why)) << why;
  expect_refused(read_file(path_), nullptr, "sealed with a state key, and none is configured here");
}

// The file of before the seal (the bare JSON document), a truncated file, a
// directory at PATH: refused and moved aside, never an exit.
TEST_F(MapStateFile, AnUnsealedTruncatedOrUnreadableFileStartsFresh) {
  std::string why;
  expect_refused(team_map().to_json(), nullptr, "no seal header");
  ASSERT_TRUE(save_map_state(path_, team_map(), nullptr, &why)) << why;
  const std::string good = read_file(path_);
  expect_refused(good.substr(0, good.size() - 1), nullptr, "does not end with");
  expect_refused(good.substr(0, good.size() / 2), nullptr, "does not end with");
  expect_refused("", nullptr, "no seal header");
  fs::remove(path_ + ".corrupt");  // rename(2) does not put a directory over a file
  fs::create_directory(path_);
  GlobalMap m(options());
  const MapStateLoad r = load(nullptr, &m);
  EXPECT_EQ(r.outcome, MapStateOutcome::kFreshAfterDamage);
  EXPECT_NE(r.why.find("is not a regular file"), std::string::npos) << r.why;
  EXPECT_TRUE(fs::is_directory(path_ + ".corrupt"));
}

// The fuzz corpus's main state file (fuzz/corpus/fuzz_state/seed02: the selector
// byte 2, then the file) is one main_robot opens: the fuzzer starts past the seal.
TEST(MapState, TheFuzzCorpusHoldsAMainStateFileThatOpens) {
  const std::string seed = read_file(ELASLAM_SOURCE_DIR "/fuzz/corpus/fuzz_state/seed02");
  ASSERT_GT(seed.size(), 1u);
  ASSERT_EQ(seed[0], '\x02');
  GlobalMapOptions o;  // config/paper.yaml's main: 256 ids, every robot
  GlobalMap m(o);
  std::string why;
  ASSERT_TRUE(open_map_state(seed.substr(1), nullptr, &m, &why)) << why;
  EXPECT_GT(m.count(GlobalStatus::kStatic), 0);
  EXPECT_GT(m.stream(1).incarnation, 0);
}

}  // namespace
}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// The MRCLAM importer: a hand-written tiny dataset (tests/dataset/data/tiny, every
// expected value computed by hand in the comments), malformed files, and the real
// dataset6 when it is present.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <string>

#include <unistd.h>

#include <gtest/gtest.h>

#include "elaslam/dataset/mrclam.hpp"
#include "../support/expect_has.hpp"

namespace elaslam::mrclam {
namespace {

namespace fs = std::filesystem;
const std::string kTiny = std::string(ELASLAM_SOURCE_DIR) + "/tests/dataset/data/tiny";

Options tiny_options(bool with_robot_barcodes = false) {
  Options o;
  o.robots = {1, 2};
  o.rate_hz = 10.0;
  o.with_robot_barcodes = with_robot_barcodes;
  o.odom_var_trans_per_m = 0.01;
  o.odom_var_rot_per_rad = 0.02;
  o.odom_var_rot_per_m = 0.03;
  return o;
}

struct Frame {
  ground_truth_t gt{};
  std::vector<sensor_frame_t> s;
};

Frame frame(const FrameSource& src, int k) {
  Frame f;
  src.frame(k, &f.gt, &f.s);
  return f;
}

std::vector<int> ids(const sensor_frame_t& m) {
  std::vector<int> v;
  for (int i = 0; i < m.num_obs; ++i) v.push_back(m.obs[i].landmark_id);
  return v;
}

// A robot's measurement lines by what became of them, and its odometry gaps.
struct Counts {
  long measurements, used, misreads, robot_barcodes, duplicates, odometry_gaps;
  bool operator==(const Counts& o) const {
    return measurements == o.measurements && used == o.used && misreads == o.misreads &&
           robot_barcodes == o.robot_barcodes && duplicates == o.duplicates && odometry_gaps == o.odometry_gaps;
  }
};

std::ostream& operator<<(std::ostream& out, const Counts& c) {
  return out << "measurements " << c.measurements << ", used " << c.used << ", misreads " << c.misreads
             << ", robot_barcodes " << c.robot_barcodes << ", duplicates " << c.duplicates << ", odometry_gaps "
             << c.odometry_gaps;
}

Counts counts(const RobotStats& r) {
  return {r.measurements, r.used, r.misreads, r.robot_barcodes, r.duplicates, r.odometry_gaps};
}

// ---- frame times -----------------------------------------------------------------

TEST(Mrclam, FrameTimesFromTheCommonStartToTheCommonEnd) {
  // GIVEN first times: R1 odometry 1000.000, R1 Vicon 1000.000, R2 odometry 1000.050,
  // R2 Vicon 999.900 -> T0 = 1000.050; last: R1 2002.0 / 1002.0, R2 odometry 1001.950
  // -> end = 1001.950: frames k = 0..19 at T0 + k / 10.
  const Dataset d = Dataset::load(kTiny, {1, 2});
  const FrameSource src(d, tiny_options());
  EXPECT_EQ(src.num_frames(), 20);
  EXPECT_DOUBLE_EQ(src.dt_s(), 0.1);
  EXPECT_EQ(src.common_start_utime(), 1000050000LL);
  EXPECT_EQ(src.common_end_utime(), 1001950000LL);
  EXPECT_EQ(src.frame_utime(0), 1000050000LL);
  EXPECT_EQ(src.frame_utime(7), 1000750000LL);
  EXPECT_EQ(src.frame_utime(19), 1001950000LL);
  EXPECT_EQ(src.stats().frames, 20);
  EXPECT_DOUBLE_EQ(src.stats().start_time, 1000.05);
  EXPECT_DOUBLE_EQ(src.stats().end_time, 1001.95);
  const Frame f = frame(src, 7);
  EXPECT_EQ(f.gt.frame, 7);
  EXPECT_EQ(f.gt.utime, 1000750000LL);
  ASSERT_EQ(f.s.size(), 2u);
  EXPECT_EQ(f.s[0].robot_id, 1);
  EXPECT_EQ(f.s[1].robot_id, 2);
  EXPECT_EQ(f.s[1].frame, 7);
  EXPECT_EQ(f.s[1].utime, 1000750000LL);
  EXPECT_EQ(f.s[0].odom_var_trans_per_m, 0.01);
  EXPECT_EQ(f.s[0].odom_var_rot_per_rad, 0.02);
  EXPECT_EQ(f.s[0].odom_var_rot_per_m, 0.03);
}

TEST(Mrclam, StartAndDurationSelectAWindow) {
  const Dataset d = Dataset::load(kTiny, {1, 2});
  Options o = tiny_options();
  o.start_s = 0.5;
  o.duration_s = 1.0;  // k / 10 < 1.0: 10 frames
  const FrameSource src(d, o);
  EXPECT_EQ(src.num_frames(), 10);
  EXPECT_EQ(src.frame_utime(0), 1000550000LL);
  o.duration_s = 5.0;  // longer than the data: to the common end (1001.95 - 1000.55 = 1.4 s)
  EXPECT_EQ(FrameSource(d, o).num_frames(), 15);
  o.rate_hz = 4.0;  // 1000.55 + k / 4 <= 1001.95: k <= 5.6
  EXPECT_EQ(FrameSource(d, o).num_frames(), 6);
}

TEST(Mrclam, OnlyRobot1UsesItsOwnWindow) {
  // Robot 1 alone: T0 = 1000.000, end = 1002.000: 21 frames.
  const Dataset d = Dataset::load(kTiny, {1});
  Options o = tiny_options();
  o.robots = {1};
  EXPECT_EQ(FrameSource(d, o).num_frames(), 21);
}

TEST(Mrclam, BadOptionsAreNamed) {
  const Dataset d = Dataset::load(kTiny, {1});
  auto message = [&](Options o) {
    try {
      FrameSource src(d, o);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  Options o = tiny_options();
  o.robots = {1};
  Options b = o;
  b.rate_hz = 0.0;
  EXPECT_NE(message(b).find("rate_hz"), std::string::npos);
  b = o;
  b.robots = {1, 2};  // robot 2 not loaded
  EXPECT_NE(message(b).find("robots"), std::string::npos);
  b = o;
  b.start_s = 10.0;
  EXPECT_NE(message(b).find("start_s"), std::string::npos);
  b = o;
  b.duration_s = -1.0;
  EXPECT_NE(message(b).find("duration_s"), std::string::npos);
}

// ---- odometer ----------------------------------------------------------------------

TEST(Mrclam, OdometerStraightLineAcrossAGap) {
  // Robot 1 starts at its Vicon pose at T0 = 1000.05: halfway... (0,0,0)@1000.0 and
  // (0.25,0,0)@1000.5 -> (0.025, 0, 0). 0.5 m/s holds until 1001.1 (also over the file's
  // 0.7 s gap), then 0: x_k = 0.025 + 0.5 min(t_k - 1000.05, 1.05).
  const Dataset d = Dataset::load(kTiny, {1, 2});
  const FrameSource src(d, tiny_options());
  const Frame f0 = frame(src, 0), f5 = frame(src, 5), f10 = frame(src, 10), f19 = frame(src, 19);
  EXPECT_NEAR(f0.s[0].odom_x, 0.025, 1e-12);
  EXPECT_NEAR(f0.s[0].odom_y, 0.0, 1e-12);
  EXPECT_NEAR(f0.s[0].odom_theta, 0.0, 1e-12);
  EXPECT_NEAR(f5.s[0].odom_x, 0.275, 1e-12);  // t = 1000.55, inside the gap
  EXPECT_NEAR(f10.s[0].odom_x, 0.525, 1e-12);
  EXPECT_NEAR(f19.s[0].odom_x, 0.55, 1e-12);  // stopped at 1001.1
  EXPECT_NEAR(f19.s[0].odom_y, 0.0, 1e-12);
}

TEST(Mrclam, OdometerConstantTurnIsAnExactArc) {
  // Robot 2: start pose = Vicon at 1000.05 between (1,1,0)@999.9 and (1.2,1,0.5)@1000.9:
  // f = 0.15 -> (1.03, 1.0, 0.075). v = 0.2, w = 0.5, r = v / w = 0.4:
  //   theta = 0.075 + 0.5 dt, x = 1.03 + 0.4 (sin theta - sin 0.075),
  //   y = 1.0 - 0.4 (cos theta - cos 0.075).
  const Dataset d = Dataset::load(kTiny, {1, 2});
  const FrameSource src(d, tiny_options());
  const Frame f0 = frame(src, 0), f10 = frame(src, 10), f19 = frame(src, 19);
  EXPECT_NEAR(f0.s[1].odom_x, 1.03, 1e-12);
  EXPECT_NEAR(f0.s[1].odom_y, 1.0, 1e-12);
  EXPECT_NEAR(f0.s[1].odom_theta, 0.075, 1e-12);
  EXPECT_NEAR(f10.s[1].odom_x, 1.217562033364, 1e-10);  // dt = 1.0
  EXPECT_NEAR(f10.s[1].odom_y, 1.063198606277, 1e-10);
  EXPECT_NEAR(f10.s[1].odom_theta, 0.575, 1e-12);
  EXPECT_NEAR(f19.s[1].odom_x, 1.341913792881, 1e-10);  // dt = 1.9
  EXPECT_NEAR(f19.s[1].odom_y, 1.191235972512, 1e-10);
  EXPECT_NEAR(f19.s[1].odom_theta, 1.025, 1e-12);
}

TEST(Mrclam, IntegrateMatchesManySmallSteps) {
  const Pose2 p{0.3, -0.2, 3.0};
  Pose2 q = p;
  for (int i = 0; i < 100000; ++i) q = integrate(q, 0.7, -1.3, 2.0 / 100000);
  const Pose2 e = integrate(p, 0.7, -1.3, 2.0);
  EXPECT_NEAR(e.x, q.x, 1e-9);
  EXPECT_NEAR(e.y, q.y, 1e-9);
  EXPECT_NEAR(wrap_angle(e.theta - q.theta), 0.0, 1e-9);
  EXPECT_GE(e.theta, -kPi);
  EXPECT_LT(e.theta, kPi);
}

// ---- ground truth --------------------------------------------------------------------

TEST(Mrclam, GroundTruthInterpolatesTheShortWay) {
  // Robot 1 Vicon: (0.5,0,3.0)@1001.0 and (0.6,0.2,-3.0)@1002.0: the short way from
  // 3.0 to -3.0 is +0.2832 rad through pi.
  //   k = 12 (1001.25, f = 0.25): (0.525, 0.05, 3.0 + 0.25 * 0.28319 = 3.07080)
  //   k = 19 (1001.95, f = 0.95): theta = 3.26903 -> wrapped -3.01416
  // Robot 2 Vicon: (1.2,1,0.5)@1000.9 and (1.2,1.4,1.0)@1002.1; k = 10 (1001.05,
  // f = 0.125): (1.2, 1.05, 0.5625).
  const Dataset d = Dataset::load(kTiny, {1, 2});
  const FrameSource src(d, tiny_options());
  const Frame f12 = frame(src, 12), f19 = frame(src, 19), f10 = frame(src, 10);
  ASSERT_EQ(f12.gt.num_robots, 2);
  EXPECT_EQ(f12.gt.robot_ids[0], 1);
  EXPECT_EQ(f12.gt.robot_ids[1], 2);
  EXPECT_NEAR(f12.gt.robots[0].x, 0.525, 1e-12);
  EXPECT_NEAR(f12.gt.robots[0].y, 0.05, 1e-12);
  EXPECT_NEAR(f12.gt.robots[0].theta, 3.0707963267948966, 1e-12);
  EXPECT_NEAR(f19.gt.robots[0].theta, -3.0141592653589795, 1e-12);
  EXPECT_NEAR(f10.gt.robots[1].x, 1.2, 1e-12);
  EXPECT_NEAR(f10.gt.robots[1].y, 1.05, 1e-12);
  EXPECT_NEAR(f10.gt.robots[1].theta, 0.5625, 1e-12);
}

TEST(Mrclam, GroundTruthLandmarks) {
  const Dataset d = Dataset::load(kTiny, {1, 2});
  const Frame f = frame(FrameSource(d, tiny_options()), 12);
  ASSERT_EQ(f.gt.num_landmarks, 3);
  EXPECT_EQ(f.gt.landmarks[0].id, 6);
  EXPECT_EQ(f.gt.landmarks[1].id, 7);
  EXPECT_EQ(f.gt.landmarks[2].id, 8);
  EXPECT_EQ(f.gt.landmarks[2].x, -1.0);
  EXPECT_EQ(f.gt.landmarks[2].y, -1.0);
  EXPECT_FALSE(f.gt.landmarks[0].moving);
  // With robot barcodes the selected robots are moving landmarks at their true positions.
  const Frame g = frame(FrameSource(d, tiny_options(true)), 12);
  ASSERT_EQ(g.gt.num_landmarks, 5);
  EXPECT_EQ(g.gt.landmarks[3].id, 1);
  EXPECT_TRUE(g.gt.landmarks[3].moving);
  EXPECT_NEAR(g.gt.landmarks[3].x, 0.525, 1e-12);
  EXPECT_NEAR(g.gt.landmarks[3].y, 0.05, 1e-12);
  EXPECT_EQ(g.gt.landmarks[4].id, 2);
  EXPECT_TRUE(g.gt.landmarks[4].moving);
}

// ---- observations ------------------------------------------------------------------

TEST(Mrclam, ObservationsBinnedFilteredAndDeduplicated) {
  // Robot 1's lines (barcode -> subject: 63 -> 6, 81 -> 7, 7 -> 8, 14 -> robot 2, 5 = own):
  //   999.900 before (t_0 - 0.1, t_0]: not read;  1000.000 63 -> frame 0
  //   1000.120 81, 1000.150 99 (misread; on t_1 itself: frame 1) -> frame 1 {7}
  //   1000.250 14 -> frame 2, robot barcode (dropped)
  //   1000.300 63, 1000.320 7, 1000.340 63 -> frame 3 {8, 6 (the later, range 1.8)}
  //   1000.400 5 (own: misread) -> frame 4 {}
  //   1000.500 81 bearing 3.5 -> frame 5 {7, bearing 3.5 - 2 pi}
  //   1000.600 81 range 0 (misread) -> frame 6 {};  1002.500 after the end: not read
  const Dataset d = Dataset::load(kTiny, {1, 2});
  const FrameSource src(d, tiny_options());
  EXPECT_EQ(ids(frame(src, 0).s[0]), (std::vector<int>{6}));
  EXPECT_EQ(ids(frame(src, 1).s[0]), (std::vector<int>{7}));
  EXPECT_EQ(ids(frame(src, 2).s[0]), (std::vector<int>{}));
  const Frame f3 = frame(src, 3);
  ASSERT_EQ(ids(f3.s[0]), (std::vector<int>{8, 6}));
  EXPECT_DOUBLE_EQ(f3.s[0].obs[0].range, 1.5);
  EXPECT_DOUBLE_EQ(f3.s[0].obs[0].bearing, -2.5);
  EXPECT_DOUBLE_EQ(f3.s[0].obs[1].range, 1.8);
  EXPECT_DOUBLE_EQ(f3.s[0].obs[1].bearing, 0.12);
  EXPECT_EQ(ids(frame(src, 4).s[0]), (std::vector<int>{}));
  const Frame f5 = frame(src, 5);
  ASSERT_EQ(ids(f5.s[0]), (std::vector<int>{7}));
  EXPECT_NEAR(f5.s[0].obs[0].bearing, -2.7831853071795862, 1e-12);
  EXPECT_EQ(ids(frame(src, 6).s[0]), (std::vector<int>{}));
  // Robot 2: 1000.060 robot 1's barcode (frame 1, dropped), 1000.700 81 (frame 7),
  // 1001.000 63 (frame 10).
  EXPECT_EQ(ids(frame(src, 1).s[1]), (std::vector<int>{}));
  EXPECT_EQ(ids(frame(src, 7).s[1]), (std::vector<int>{7}));
  EXPECT_EQ(ids(frame(src, 10).s[1]), (std::vector<int>{6}));

  const Stats& st = src.stats();
  ASSERT_EQ(st.robots.size(), 2u);
  const RobotStats& r1 = st.robots[0];
  EXPECT_EQ(r1.id, 1);
  EXPECT_EQ(counts(r1), (Counts{10, 5, 3, 1, 1, 1}));  // the odometry gap: 1000.3 -> 1001.0
  EXPECT_NEAR(r1.max_odometry_gap_s, 0.7, 1e-9);
  EXPECT_EQ(counts(st.robots[1]), (Counts{3, 2, 0, 1, 0, 0}));
}

TEST(Mrclam, RobotBarcodesKeptWhenAsked) {
  const Dataset d = Dataset::load(kTiny, {1, 2});
  const FrameSource src(d, tiny_options(true));
  const Frame f2 = frame(src, 2);
  ASSERT_EQ(ids(f2.s[0]), (std::vector<int>{2}));
  EXPECT_DOUBLE_EQ(f2.s[0].obs[0].range, 1.2);
  const Frame f1 = frame(src, 1);
  EXPECT_EQ(ids(f1.s[1]), (std::vector<int>{1}));
  EXPECT_EQ(ids(f1.s[0]), (std::vector<int>{7}));
  EXPECT_EQ(src.stats().robots[0].used, 6);
  EXPECT_EQ(src.stats().robots[0].robot_barcodes, 1);
  EXPECT_EQ(src.stats().robots[1].used, 3);
}

TEST(Mrclam, BarcodeMap) {
  const Dataset d = Dataset::load(kTiny, {2});
  EXPECT_EQ(d.subject_of_barcode(63), 6);
  EXPECT_EQ(d.subject_of_barcode(99), 0);
  EXPECT_EQ(d.barcode_of_subject(2), 14);
  EXPECT_TRUE(d.has_robot(2));
  EXPECT_FALSE(d.has_robot(1));
  EXPECT_THROW(d.robot(1), std::out_of_range);
  EXPECT_THROW(Dataset::load(kTiny, {6}), DatasetError);
}

// ---- options -------------------------------------------------------------------------

TEST(Mrclam, OptionsFromYamlWithOtherSections) {
  const fs::path p = fs::temp_directory_path() / ("test_mrclam_opts_" + std::to_string(::getpid()) + ".yaml");
  std::ofstream(p) << "dataset:\n  rate_hz: 5\n  robots: \"2, 4\"\n  with_robot_barcodes: true\n"
                      "  start_s: 1.5\n  duration_s: 60\n  odom_var_trans_per_m: 0.1\n"
                      "  odom_var_rot_per_rad: 0.2\n  odom_var_rot_per_m: 0.3\nrobot: {mode: ela}\nmain: {}\n";
  const Options o = load_options(p.string());
  EXPECT_EQ(o.rate_hz, 5.0);
  EXPECT_EQ(o.robots, (std::vector<int>{2, 4}));
  EXPECT_TRUE(o.with_robot_barcodes);
  EXPECT_EQ(o.start_s, 1.5);
  EXPECT_EQ(o.duration_s, 60.0);
  EXPECT_EQ(o.odom_var_rot_per_m, 0.3);
  std::ofstream(p) << "dataset:\n  rate_hz: -5\n  robots: \"2,9\"\n  with_robot_barcodes: true\n"
                      "  start_s: 0\n  duration_s: 0\n  odom_var_trans_per_m: 0.1\n"
                      "  odom_var_rot_per_rad: 0.2\n  odom_var_rot_per_m: 0.3\n  extra: 1\n";
  try {
    load_options(p.string());
    ADD_FAILURE() << "no ConfigError";
  } catch (const config::ConfigError& e) {
    const std::string m = e.what();
    EXPECT_HAS(m, "dataset.rate_hz");
    EXPECT_HAS(m, "dataset.robots");
    EXPECT_HAS(m, "dataset.extra");
  }
  fs::remove(p);
  // The repository's config parses.
  EXPECT_NO_THROW(load_options(std::string(ELASLAM_SOURCE_DIR) + "/config/mrclam.yaml"));
}

TEST(Mrclam, RobotList) {
  std::vector<int> v;
  std::string why;
  EXPECT_TRUE(parse_robot_list("1,2,3,4,5", &v, &why));
  EXPECT_EQ(v, (std::vector<int>{1, 2, 3, 4, 5}));
  EXPECT_FALSE(parse_robot_list("1,,2", &v, &why));
  EXPECT_FALSE(parse_robot_list("1,1", &v, &why));
  EXPECT_FALSE(parse_robot_list("0", &v, &why));
  EXPECT_FALSE(parse_robot_list("x", &v, &why));
  EXPECT_FALSE(parse_robot_list("", &v, &why));
}

// ---- malformed files -----------------------------------------------------------------

class MrclamMalformed : public ::testing::Test {
 protected:
  void SetUp() override {
    // One directory per test; a parameterised test's name has a '/'.
    std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    std::replace(name.begin(), name.end(), '/', '_');
    dir_ = fs::temp_directory_path() / ("test_mrclam_" + std::to_string(::getpid()) + "_" + name);
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    for (const auto& e : fs::directory_iterator(kTiny)) fs::copy_file(e.path(), dir_ / e.path().filename());
  }
  void TearDown() override { fs::remove_all(dir_); }
  /// Append a line to a file; returns its line number.
  int append(const std::string& file, const std::string& line) {
    std::ifstream in(dir_ / file);
    int n = 0;
    for (std::string l; std::getline(in, l);) ++n;
    std::ofstream(dir_ / file, std::ios::app) << line << "\n";
    return n + 1;
  }
  std::string error() {
    try {
      Dataset::load(dir_.string(), {1, 2});
    } catch (const DatasetError& e) {
      return e.what();
    }
    return "no DatasetError";
  }
  /// The load's error after `row` is appended to `file`: it must name the file and the
  /// row's line number.
  std::string error_at(const std::string& file, const std::string& row) {
    const int line = append(file, row);
    const std::string m = error();
    EXPECT_NE(m.find(file + ":" + std::to_string(line) + ":"), std::string::npos) << m;
    return m;
  }
  fs::path dir_;
};

// A row appended to a file of the tiny dataset, and what the load's error then says
// besides the file and the line (nothing more when `says` is empty).
struct BadRow {
  const char* name;
  const char* file;
  const char* row;
  const char* says;
};

void PrintTo(const BadRow& b, std::ostream* out) { *out << b.file << ": " << b.row; }

class MrclamBadRow : public MrclamMalformed, public ::testing::WithParamInterface<BadRow> {};

TEST_P(MrclamBadRow, ErrorNamesTheFileAndTheLine) {
  const BadRow& b = GetParam();
  const std::string m = error_at(b.file, b.row);
  if (*b.says != '\0') {
    EXPECT_HAS(m, b.says);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Mrclam, MrclamBadRow,
    ::testing::Values(BadRow{"WrongColumnCount", "Robot2_Odometry.dat", "1002.000 0.2 0.5 7", "column count"},
                      BadRow{"TextInANumber", "Robot1_Measurement.dat", "1003.000 63 abc 0.1",
                             "column 3 ('abc') is not a number"},
                      BadRow{"NotFinite", "Robot1_Groundtruth.dat", "1003.000 nan 0.0 0.0", "not finite"},
                      BadRow{"TimeGoingBackwards", "Robot1_Groundtruth.dat", "1001.500 0.0 0.0 0.0", "backwards"},
                      BadRow{"MeasurementTimeGoingBackwards", "Robot2_Measurement.dat", "1000.000 63 1.0 0.0", ""},
                      BadRow{"NonIntegerBarcode", "Barcodes.dat", "9 3.5", ""}),
    [](const ::testing::TestParamInfo<BadRow>& info) { return std::string(info.param.name); });

TEST_F(MrclamMalformed, MissingFile) {
  fs::remove(dir_ / "Robot2_Groundtruth.dat");
  const std::string m = error();
  EXPECT_HAS(m, "Robot2_Groundtruth.dat");
  EXPECT_HAS(m, "cannot open");
}

// ---- the real dataset ------------------------------------------------------------------

TEST(MrclamReal, Dataset6Robots12FirstMinute) {
  const std::string dir = ELASLAM_MRCLAM_DATASET6;
  if (!fs::exists(dir + "/Barcodes.dat")) GTEST_SKIP() << "no dataset at " << dir;
  // GIVEN robots 1 and 2, 60 s from the common start at 10 Hz
  const Dataset d = Dataset::load(dir, {1, 2});
  Options o;
  o.robots = {1, 2};
  o.duration_s = 60.0;
  const FrameSource src(d, o);
  // THEN 600 frames, T0 = robot 2's first odometry line (1248444188.949)
  ASSERT_EQ(src.num_frames(), 600);
  EXPECT_EQ(src.common_start_utime(), 1248444188949000LL);
  EXPECT_EQ(src.frame_utime(599) - src.frame_utime(0), 59900000LL);
  // Dead reckoning after 60 s: measured 0.50 m (robot 1) and 1.06 m (robot 2); bound 2 m.
  ground_truth_t gt{};
  std::vector<sensor_frame_t> s;
  src.frame(599, &gt, &s);
  for (int i = 0; i < 2; ++i) {
    const double err = std::hypot(s[i].odom_x - gt.robots[i].x, s[i].odom_y - gt.robots[i].y);
    EXPECT_LT(err, 2.0) << "robot " << s[i].robot_id;
    EXPECT_GT(err, 0.0);
  }
  // Frame 0 odometer = Vicon pose.
  src.frame(0, &gt, &s);
  EXPECT_DOUBLE_EQ(s[0].odom_x, gt.robots[0].x);
  EXPECT_DOUBLE_EQ(s[1].odom_theta, gt.robots[1].theta);
  EXPECT_EQ(gt.num_landmarks, 15);
  // Observation counts add up, and are plausible: measured 202 read / 171 used (robot 1),
  // 49 / 49 (robot 2), none misread in this minute; the camera reports ~1-4 per second.
  for (const RobotStats& r : src.stats().robots) {
    EXPECT_EQ(r.measurements, r.used + r.misreads + r.robot_barcodes + r.duplicates) << "robot " << r.id;
    EXPECT_GT(r.used, 20) << "robot " << r.id;
    EXPECT_LT(r.used, 600) << "robot " << r.id;
  }
  long obs = 0;
  for (int k = 0; k < src.num_frames(); ++k) {
    src.frame(k, nullptr, &s);
    for (const auto& m : s) {
      obs += m.num_obs;
      for (int j = 0; j < m.num_obs; ++j) {
        EXPECT_GE(m.obs[j].landmark_id, kFirstLandmarkSubject);
        EXPECT_GT(m.obs[j].range, 0.0);
        EXPECT_GE(m.obs[j].bearing, -kPi);
        EXPECT_LT(m.obs[j].bearing, kPi);
      }
    }
  }
  EXPECT_EQ(obs, src.stats().robots[0].used + src.stats().robots[1].used);
}

TEST(MrclamReal, Dataset6Robot1ShortensTheRun) {
  const std::string dir = ELASLAM_MRCLAM_DATASET6;
  if (!fs::exists(dir + "/Barcodes.dat")) GTEST_SKIP() << "no dataset at " << dir;
  const Dataset d = Dataset::load(dir, {1, 2, 3, 4, 5});
  Options o;
  const FrameSource all(d, o);
  o.robots = {2, 3, 4, 5};
  const FrameSource without1(d, o);
  // Robot1's Vicon ends at 1248444946.976; the others run to ~1248445075.1.
  EXPECT_EQ(all.common_end_utime(), 1248444946976000LL);
  EXPECT_EQ(all.num_frames(), 7560);
  EXPECT_GT(without1.num_frames() - all.num_frames(), 1200);
}

}  // namespace
}  // namespace elaslam::mrclam

// SPDX-License-Identifier: Apache-2.0
// sensor_driver: SENSOR_<r> frames from a real robot's readings, an example of the
// driver every robot needs in place of the simulator (docs/sensor_driver.md). It
// reads timestamped readings, one a line, from a file or standard input (the robot
// base's integrated wheel odometry and a detector's landmark sightings with ids,
// e.g. AprilTags), groups them into frames at the rate the robot_node expects and
// publishes each frame on LCM as soon as a later reading shows it complete:
//   odom T X Y THETA        T [s], the odometer's cumulative pose [m, m, rad]
//   det T ID RANGE BEARING  a landmark seen: id, range [m], bearing [rad], robot frame
//   sensor_driver --robot R [--rate F] [--input FILE] [--pace] [--lcm-url URL]
//                 [--max-landmark-id N] [--odom-var-trans-per-m V] [--odom-var-rot-per-rad V]
//                 [--odom-var-rot-per-m V]
// --pace: publish at the readings' own times (a file replayed as if live); without
// it a file is published as fast as it is read. Prints what it published and
// dropped, by reason, at the end. Exit 0; 1 when LCM cannot start or the input
// cannot be read; 2 for a bad command line.
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>
#include <thread>

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include "elaslam/common/channels.hpp"
#include "elaslam/common/cli.hpp"
#include "frame_assembler.hpp"

int main(int argc, char** argv) {
  using elaslam::examples::AssemblerOptions;
  namespace cli = elaslam::cli;
  AssemblerOptions o;
  std::string input, url;
  bool pace = false;
  CLI::App app{"elaslam sensor_driver: SENSOR_<r> frames from a real robot's odometry and landmark detections"};
  cli::add_version_flag(app, "sensor_driver");
  app.add_option("--robot", o.robot_id, "robot id (the channel SENSOR_<r>)")->required()->check(cli::range(1, 16));
  app.add_option("--rate", o.rate_hz, "frames per second (the team's frame rate)")->check(cli::range(0.1, 1000.0));
  app.add_option("--input", input, "readings file (default: standard input)");
  app.add_flag("--pace", pace, "publish at the readings' own times (replay a file as if live)");
  app.add_option("--lcm-url", url, "LCM URL (default: $LCM_DEFAULT_URL, else LCM's default)");
  app.add_option("--max-landmark-id", o.max_landmark_id, "ids at or above are dropped (robot.filter.max_landmark_id)")
      ->check(cli::range(1, 1 << 20));
  app.add_option("--odom-var-trans-per-m", o.odom_var_trans_per_m, "odometry variance [m^2 per m]")->check(cli::range(0.0, 1e3));
  app.add_option("--odom-var-rot-per-rad", o.odom_var_rot_per_rad, "odometry variance [rad^2 per rad]")->check(cli::range(0.0, 1e3));
  app.add_option("--odom-var-rot-per-m", o.odom_var_rot_per_m, "odometry variance [rad^2 per m]")->check(cli::range(0.0, 1e3));
  if (const int rc = cli::parse(app, argc, argv); rc >= 0) return rc;

  std::ifstream file;
  if (!input.empty()) {
    file.open(input);
    if (!file) {
      std::fprintf(stderr, "sensor_driver: cannot read --input %s\n", input.c_str());
      return 1;
    }
  }
  std::istream& in = input.empty() ? std::cin : file;
  lcm::LCM lcm(url);
  if (!lcm.good()) {
    std::fprintf(stderr, "sensor_driver: LCM did not start (URL '%s')\n", url.c_str());
    return 1;
  }
  const std::string channel = elaslam::channels::sensor(o.robot_id);
  bool first = true;
  double first_t = 0.0;
  const auto wall0 = std::chrono::steady_clock::now();
  elaslam::examples::FrameAssembler assembler(o, [&](const elaslam::sensor_frame_t& m) {
    if (pace) {  // the frame's end time after the first frame's, on the wall clock
      const double t = static_cast<double>(m.utime) * 1e-6;
      if (first) first = false, first_t = t;
      std::this_thread::sleep_until(wall0 + std::chrono::duration<double>(t - first_t));
    }
    lcm.publish(channel, &m);
  });
  std::string text;
  while (std::getline(in, text)) assembler.line(text);
  assembler.flush();
  const auto& c = assembler.counters();
  std::printf("sensor_driver: %lld frames on %s (%lld empty, %lld before any odometry), %lld detections; dropped: "
              "%lld unreadable lines, %lld out of order, %lld bad detections, %lld repeated in a frame, %lld over "
              "capacity\n",
              static_cast<long long>(c.frames), channel.c_str(), static_cast<long long>(c.empty_frames),
              static_cast<long long>(c.frames_without_odometry), static_cast<long long>(c.detections),
              static_cast<long long>(c.bad_lines), static_cast<long long>(c.out_of_order),
              static_cast<long long>(c.bad_detections), static_cast<long long>(c.repeated_in_frame),
              static_cast<long long>(c.over_capacity));
  return 0;
}

// SPDX-License-Identifier: Apache-2.0
// One robot's filter in one's own program (docs/embedding.md): the options from a
// config file's `robot:` section, a Robot, and ten frames of a made-up drive past six
// landmarks, each frame's summary and map events, then the pose.
//   embed_robot [CONFIG.yaml]     (no file: RobotOptions' defaults, mode ela)
// Exit 0 on success, 1 when the config is refused (every problem listed), 2 on a
// bad command line. Deterministic: the same output on every run and machine.
#include <cmath>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "elaslam/common/config.hpp"
#include "elaslam/common/geometry.hpp"
#include "elaslam/robot_node/models.hpp"
#include "elaslam/robot_node/robot.hpp"
#include "elaslam/robot_node/robot_options.hpp"

namespace {

constexpr int kFrames = 10;
constexpr double kPeriodS = 0.1;  // [s] 10 Hz

// The true pose at frame k: ahead at 0.5 m/s along a gentle left turn (0.2 rad/s).
elaslam::Pose2 truth_at(int k) {
  const double v = 0.5, w = 0.2, t = k * kPeriodS;
  return {v / w * std::sin(w * t), v / w * (1.0 - std::cos(w * t)), w * t};
}

// What the robot's odometer reports: the true motion 3 % long (a wheel a little
// too large), integrated from the start pose.
elaslam::Pose2 odometer_at(int k) {
  const elaslam::Pose2 p = truth_at(k);
  return {1.03 * p.x, 1.03 * p.y, p.theta};
}

// A deterministic stand-in for sensor noise, within the filter's sigmas.
double wobble(int k, int id, double sigma) { return 0.5 * sigma * std::sin(1.7 * k + 2.3 * id); }

}  // namespace

int main(int argc, char** argv) {
  if (argc > 2) {
    std::fprintf(stderr, "usage: embed_robot [CONFIG.yaml]\n");
    return 2;
  }
  // ---- start-up: everything is allocated here ----------------------------------
  elaslam::RobotOptions options;
  if (argc == 2) {
    try {
      options = elaslam::load_robot_options(argv[1]);  // the `robot:` section; throws listing every problem
    } catch (const elaslam::config::ConfigError& e) {
      std::fprintf(stderr, "embed_robot: %s\n", e.what());
      return 1;
    }
  }
  const int robot_id = 1;
  elaslam::Robot robot(options, robot_id);
  elaslam::FrameInput in(options.max_observations);  // room for the most observations a frame may carry
  const std::vector<Eigen::Vector2d> landmarks = {{1.5, 1.0}, {2.0, -1.0}, {0.5, 2.0},
                                                  {3.0, 0.5}, {-0.5, -1.5}, {1.0, -2.0}};
  std::printf("embed_robot: mode %s, filter capacity %d landmarks, sensor range %.1f m\n",
              elaslam::to_string(options.mode), options.ekf.capacity, options.sensor_range);

  // ---- the frame loop: no allocation from here on --------------------------------
  for (int k = 0; k < kFrames; ++k) {
    const elaslam::Pose2 truth = truth_at(k);
    in.frame = k;
    in.utime = 1'000'000 + static_cast<std::int64_t>(k) * 100'000;  // [us]
    in.odometer = odometer_at(k);
    in.noise = {1e-3, 1e-3, 1e-3};  // [m^2/m], [rad^2/rad], [rad^2/m]
    in.reanchor = false;
    in.num_obs = 0;
    for (std::size_t id = 0; id < landmarks.size() && in.num_obs < options.max_observations; ++id) {
      elaslam::RangeBearing z = elaslam::observe(truth, landmarks[id]);
      if (z.range > options.sensor_range) continue;
      z.range += wobble(k, static_cast<int>(id), options.ekf.range_sigma);
      z.bearing = elaslam::wrap_angle(z.bearing + wobble(k, static_cast<int>(id) + 7, options.ekf.bearing_sigma));
      in.obs[static_cast<std::size_t>(in.num_obs++)] = {static_cast<int>(id), z};
    }
    const elaslam::FrameSummary s = robot.process(in);
    std::printf("frame %d: %d observations, %d accepted, %d rejected, %d added, %d moving;", k, s.num_obs,
                s.num_accepted, s.num_rejected, s.num_added, s.num_moving);
    for (const elaslam::MapEvent& e : robot.events())
      std::printf(" %s %d", elaslam::to_string(e.kind), e.landmark_id);
    std::printf("\n");
  }

  // ---- the result: the robot's best estimate (POSE's) ------------------------------
  const elaslam::EkfSlam& est = robot.estimate();
  const elaslam::Pose2 pose = est.pose();
  const elaslam::Pose2 truth = truth_at(kFrames - 1);
  const Eigen::Matrix3d P = est.pose_cov();
  std::printf("frames %d, landmarks %d\n", robot.last_frame() + 1, est.num_landmarks());
  std::printf("pose %.9f %.9f %.9f\n", pose.x, pose.y, pose.theta);
  std::printf("sigma %.6f %.6f %.6f\n", std::sqrt(P(0, 0)), std::sqrt(P(1, 1)), std::sqrt(P(2, 2)));
  std::printf("error %.4f m (odometer alone %.4f m)\n", std::hypot(pose.x - truth.x, pose.y - truth.y),
              std::hypot(odometer_at(kFrames - 1).x - truth.x, odometer_at(kFrames - 1).y - truth.y));
  return 0;
}

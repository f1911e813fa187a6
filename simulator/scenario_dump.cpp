// SPDX-License-Identifier: Apache-2.0
// scenario_dump: the ground truth of a whole run as CSV, for plots
// (tools/plot_scenario.py) and for eyeballing a scenario without LCM.
//
//   scenario_dump --config config/paper.yaml [--dynamism P] [--speed V] [--seed S] [--check] --out FILE.csv
//
// Output: '#' lines with key=value metadata (world bounds, D, rate, the mover
// kinds, ...), then rows "frame,kind,id,x,y,theta,moving,motion" with kind robot
// (pose T_WB, theta [rad]), landmark (theta empty; motion: static, oscillating,
// constant_velocity or stop_and_go) or obs (robot id; x, y = the noisy
// observation's landmark position in W computed from the TRUE pose, to visualise
// the field of view; moving = the landmark's id). motion is empty but for landmarks.
// Exit codes: 0 ok, 1 cannot write, 2 bad command line or configuration.
#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>

#include <CLI/CLI.hpp>

#include "elaslam/common/cli.hpp"

#include "elaslam/common/config.hpp"
#include "elaslam/simulator/scenario.hpp"
#include "elaslam/simulator/world.hpp"

namespace {

void write_frame(std::FILE* f, const elaslam::sim::World& w) {
  const int k = w.frame();
  for (int r = 0; r < w.num_robots(); ++r) {
    const auto& T = w.robot_pose(r);
    const int id = w.options().robots[static_cast<std::size_t>(r)].id;
    std::fprintf(f, "%d,robot,%d,%.9g,%.9g,%.9g,0,\n", k, id, T.x, T.y, T.theta);
    const auto& sf = w.sensor_frame(r);
    for (int i = 0; i < sf.num_obs; ++i) {
      const auto& z = sf.obs[static_cast<std::size_t>(i)];
      const double a = T.theta + z.bearing_rad;
      std::fprintf(f, "%d,obs,%d,%.9g,%.9g,,%d,\n", k, id, T.x + z.range_m * std::cos(a),
                   T.y + z.range_m * std::sin(a), z.landmark_id);
    }
  }
  const auto& p = w.landmark_positions();
  for (int i = 0; i < w.num_landmarks(); ++i)
    std::fprintf(f, "%d,landmark,%d,%.9g,%.9g,,%d,%s\n", k, i, p[static_cast<std::size_t>(i)].x(),
                 p[static_cast<std::size_t>(i)].y(), w.is_moving(i) ? 1 : 0,
                 elaslam::sim::motion_kind_name(w.kind(i)));
}

int dump_main(int argc, char** argv) {
  namespace cli = elaslam::cli;
  namespace lim = elaslam::sim::limits;
  CLI::App app{"elaslam scenario_dump: ground truth of a whole run as CSV"};
  std::string config, out;
  double dynamism = 0.0, speed = 0.0;
  int seed = 0;
  bool check = false;
  cli::add_version_flag(app, "scenario_dump");
  cli::add_config_option(app, &config, "its scenario: section");
  // The simulator's ranges (sim::limits): the same override means the same here.
  auto* o_dyn = app.add_option("--dynamism", dynamism, "override scenario.dynamism_percent [%]")
                    ->check(cli::range(0.0, lim::kDynamismMaxPercent));
  auto* o_speed = app.add_option("--speed", speed, "override scenario.landmark_speed_mps [m/s]")
                      ->check(cli::range(0.0, lim::kLandmarkSpeedMaxMps));
  auto* o_seed = app.add_option("--seed", seed, "override scenario.seed")->check(cli::range(0, lim::kSeedMax));
  app.add_option("--out", out, "output CSV file")->required();
  app.add_flag("--check", check, "check the configuration with the overrides and exit (0: valid); writes nothing");
  if (const int rc = cli::parse(app, argc, argv); rc >= 0) return rc;
  const std::string path = cli::find_config(config).path;  // a ConfigError: exit 2 (guarded_main)
  elaslam::sim::ScenarioOptions o = elaslam::sim::load_scenario(path);
  if (o_dyn->count()) o.dynamism_percent = dynamism;
  if (o_speed->count()) o.landmark_speed_mps = speed;
  if (o_seed->count()) o.seed = seed;
  const auto problems = elaslam::sim::check_scenario(o);
  for (const auto& p : problems)
    std::cerr << "scenario_dump: " << path << " with command-line overrides: scenario." << p.key << ": " << p.what
              << "\n";
  if (!problems.empty()) return cli::kExitBadInput;
  if (check) {
    std::cout << "scenario_dump: " << path << ": valid\n";
    return 0;
  }

  std::FILE* f = std::fopen(out.c_str(), "w");
  if (!f) {
    std::cerr << "scenario_dump: cannot write " << out << "\n";
    return cli::kExitFailure;
  }
  std::fprintf(f, "# x_min_m=%g\n# x_max_m=%g\n# y_min_m=%g\n# y_max_m=%g\n# fov_diameter_m=%g\n", o.world.x_min_m,
               o.world.x_max_m, o.world.y_min_m, o.world.y_max_m, o.sensor.fov_diameter_m);
  std::fprintf(f, "# frames=%d\n# rate_hz=%g\n# seed=%d\n# dynamism_percent=%g\n# landmark_speed_mps=%g\n", o.frames,
               o.rate_hz, o.seed, o.dynamism_percent, o.landmark_speed_mps);
  // The mover kinds in the order the moving ids take them in turn (scenario.movers).
  std::string kinds;
  for (const auto kind : o.movers.kinds)
    kinds += (kinds.empty() ? "" : ",") + std::string(elaslam::sim::motion_kind_name(kind));
  std::fprintf(f, "# movers=%s\n# reversal_period_frames=%d\n", kinds.c_str(), o.reversal_period_frames);
  if (o.movers.uses(elaslam::sim::MotionKind::kStopAndGo))
    std::fprintf(f, "# stop_and_go_move_frames=%d\n# stop_and_go_stop_frames=%d\n", o.stop_and_go_move_frames(),
                 o.stop_and_go_stop_frames());
  std::fprintf(f, "frame,kind,id,x,y,theta,moving,motion\n");
  elaslam::sim::World w(o);
  for (int k = 0; k < o.frames; ++k) {
    if (k > 0) w.step();
    write_frame(f, w);
  }
  const bool ok = std::fclose(f) == 0;
  if (!ok) std::cerr << "scenario_dump: error writing " << out << "\n";
  return ok ? 0 : cli::kExitFailure;
}

}  // namespace

int main(int argc, char** argv) {
  return elaslam::cli::guarded_main("scenario_dump", [&] { return dump_main(argc, argv); });
}

// SPDX-License-Identifier: Apache-2.0
// evaluate: the metrics of a recorded run (an LCM log of the live team, made by
// lcm-logger) against its ground truth, with the same definitions and output files
// as run_scenario, plus latency and frame accounting (eval/log_frames.hpp says how).
//   evaluate --log FILE [--out DIR] [--config FILE] [--baseline MODE] [--quiet]
//            [--channel-suffix S] [--mode M] [--dynamism P] [--speed V] [--seed S]
//
// What the run was comes from the log: RUN_INFO (the frame source's scenario, seed,
// dynamism, speed, rate, frames, effective config) and the robots' STATUS (their
// mode). --mode / --dynamism / --speed / --seed are fallbacks for logs without them.
// --config FILE: the team's config file; with RUN_INFO's values over it, it becomes
// the effective config echoed into metrics.json (without it only the frame source's
// section is known). --baseline MODE (needs --config): the same scenario and seed in
// process with MODE (e.g. plain ekf), side by side with the live run.
#include <cstdio>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "elaslam/common/cli.hpp"
#include "elaslam/eval/log_frames.hpp"
#include "elaslam/eval/report.hpp"
#include "elaslam/logs/log_auth.hpp"
#include "elaslam/simulator/scenario.hpp"
#include "elaslam/team/baseline.hpp"
#include "elaslam/team/team_config.hpp"

namespace elaslam {
namespace {

struct Args {
  std::string log_path, out_dir, config, baseline, channel_suffix, mission, roster;
  RunFallbacks fallbacks;  // --mode, --dynamism, --speed, --seed
  bool quiet = false;
};

/// -1 to go on, else the exit code.
int parse_args(int argc, char** argv, Args* a) {
  namespace lim = sim::limits;
  CLI::App app{"elaslam evaluate: metrics of a recorded LCM log against its ground truth"};
  cli::add_version_flag(app, "evaluate");
  app.add_option("--log", a->log_path, "LCM log (lcm-logger)")->required();
  app.add_option("--out", a->out_dir, "directory for metrics.json, frames.csv, trajectories/");
  app.add_option("--config", a->config, "the team's config file: its sections with the log's run facts become the "
                                        "effective config in metrics.json");
  app.add_option("--baseline", a->baseline, "also run this mode in process on the same scenario and seed and compare "
                                            "(needs --config)")
      ->check(CLI::IsMember({"ekf", "gated", "ela", "consensus"}));
  app.add_flag("--quiet", a->quiet, "no summary on stdout");
  app.add_option("--channel-suffix", a->channel_suffix, "the team's channel suffix (its processes' --channel-suffix)");
  app.add_option("--roster", a->roster, "the team's roster file (elaslam-keys team): every event is verified as the "
                                        "nodes do and what they would refuse is left out (default: the config's "
                                        "team: section; none: the log is trusted)");
  app.add_option("--mission", a->mission, "the mission to verify the events of (default: the roster's)");
  // Fallbacks for logs without RUN_INFO / STATUS_ROBOT (recorded before they existed),
  // in the simulator's ranges.
  app.add_option("--mode", a->fallbacks.mode, "mode to record when the robots' STATUS does not say");
  app.add_option("--dynamism", a->fallbacks.dynamism, "dynamism [%] to record when the log has no RUN_INFO "
                                                      "(default: from the ground truth's moving flags)")
      ->check(cli::range(0.0, lim::kDynamismMaxPercent));
  app.add_option("--speed", a->fallbacks.speed, "landmark speed [m/s] to record when the log has no RUN_INFO")
      ->check(cli::range(0.0, lim::kLandmarkSpeedMaxMps));
  app.add_option("--seed", a->fallbacks.seed, "seed to record when the log has no RUN_INFO")
      ->check(cli::range(0, lim::kSeedMax));
  if (const int rc = cli::parse(app, argc, argv); rc >= 0) return rc;
  if (!a->baseline.empty() && a->config.empty()) {
    std::fprintf(stderr, "evaluate: --baseline needs --config (the team's config file)\n");
    return cli::kExitBadInput;
  }
  return -1;
}

/// metrics.json of the log `d`: the run's figures, the log's and its frame accounts.
nlohmann::json metrics_of(const LogData& d, const AssembledRun& x, const RunInfo& info, bool have_config,
                          std::vector<RobotFrameAccount>* accounts) {
  nlohmann::json j = metrics_json(info, x.r);
  if (!have_config)
    j["config_note"] = d.run_info ? "the frame source's section only (RUN_INFO); pass --config for the nodes' sections"
                                  : "unknown: no RUN_INFO in the log and no --config";
  j["run_info"] = d.run_info ? run_info_json(*d.run_info) : nlohmann::json(nullptr);
  // The robots' tracks (TRACKS_<r>) and main's fused ones (GLOBAL_TRACKS): null when
  // the log has none.
  if (!x.r.metrics.tracks_scored) j["tracks"] = nullptr;
  if (!x.r.metrics.global_tracks_scored) j["global_tracks"] = nullptr;
  add_log_figures(d, x, &j);
  *accounts = account_run_frames(d, x, &j);
  return j;
}

int evaluate_main(int argc, char** argv) {
  Args a;
  if (const int rc = parse_args(argc, argv, &a); rc >= 0) return rc;
  // The config first: a bad one is refused (ConfigError, exit 2 through guarded_main)
  // before a long log is read.
  TeamConfig file_config;
  if (!a.config.empty()) file_config = load_team_config(a.config);
  LogData d;
  if (!open_log_auth(a.roster, a.mission, a.config, a.channel_suffix, "evaluate", &d.auth, &d.roster))
    return cli::kExitBadInput;
  std::string why;
  if (!read_log(a.log_path, a.channel_suffix, &d, &why)) {
    std::fprintf(stderr, "evaluate: %s\n", why.c_str());
    return cli::kExitBadInput;
  }
  const AssembledRun x = assemble_run(d);
  a.fallbacks.source = a.log_path;
  a.fallbacks.command_line = cli::command_line(argc, argv);
  std::vector<std::string> warnings;
  RunInfo info = run_facts(a.fallbacks, d, &warnings);
  for (const auto& w : warnings) std::fprintf(stderr, "evaluate: %s\n", w.c_str());
  TeamConfig team;
  if (!a.config.empty()) {
    try {
      team = team_config_of_run(file_config, info, d.run_info);
      info.effective_config = team.effective_yaml;
    } catch (const std::invalid_argument& e) {
      std::fprintf(stderr, "evaluate: --config %s with the log's run facts: %s\n", a.config.c_str(), e.what());
      return cli::kExitBadInput;
    }
  } else if (d.run_info) {
    info.effective_config = d.run_info->config_yaml;  // the frame source's section only
  }
  std::vector<RobotFrameAccount> accounts;
  nlohmann::json j = metrics_of(d, x, info, !a.config.empty(), &accounts);
  if (!a.quiet) print_log_report(std::cout, d, x, info, j, accounts);
  if (!a.baseline.empty())  // the same scenario and seed in process, with the baseline's mode
    j["baseline"] = run_baseline(team, a.config, a.baseline, info, x.r, a.quiet ? nullptr : &std::cout);
  if (!a.out_dir.empty()) {
    try {
      write_outputs(a.out_dir, j, x.r);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "evaluate: %s\n", e.what());
      return cli::kExitFailure;
    }
  }
  return 0;
}

}  // namespace
}  // namespace elaslam

int main(int argc, char** argv) {
  return elaslam::cli::guarded_main("evaluate", [&] { return elaslam::evaluate_main(argc, argv); });
}

// SPDX-License-Identifier: Apache-2.0
// What every program's command line shares: the one way out of main (exit codes,
// no exception escapes), parsing with numeric options that refuse nan and inf,
// --version, the config lookup rule, the command line as text (provenance in
// metrics.json), and where the installed data (configs, Python tools, message
// definitions) lives.
//
// Every program's main:
//   int main(int argc, char** argv) {
//     return elaslam::cli::guarded_main("simulator", [&] { return run(argc, argv); });
//   }
// and in run:
//   app.add_option("--speed", speed, "...")->check(cli::range(0.0, 1000.0));
//   if (const int rc = cli::parse(app, argc, argv); rc >= 0) return rc;
#pragma once

#include <functional>
#include <optional>
#include <string>

namespace CLI {
class App;
class Validator;
}  // namespace CLI

namespace elaslam::cli {

/// The exit codes of every program (docs/tools.md, "Exit codes").
inline constexpr int kExitOk = 0;
/// The input was valid and the run failed: LCM, a file that cannot be written, a
/// dataset that cannot be read, an internal error.
inline constexpr int kExitFailure = 1;
/// A bad command line or configuration: the message names the option, key path or file.
inline constexpr int kExitBadInput = 2;

/// The one way out of main: runs `body` (the program; it returns its exit code) so
/// that no exception escapes. One that does is printed as "<program>: <what>" on
/// stderr and exits kExitBadInput when it is about the input (config::ConfigError,
/// YAML::Exception, std::invalid_argument), else kExitFailure.
int guarded_main(const std::string& program, const std::function<int()>& body);

/// Parses the command line: -1 to go on, else the exit code: kExitOk after --help or
/// --version (printed), kExitBadInput for a bad command line, CLI11's message naming
/// the option on stderr. Every floating-point option refuses nan and inf here,
/// whether or not it has a range.
int parse(CLI::App& app, int argc, const char* const* argv);

/// The check of a numeric option: a finite number in [lo, hi], or the message
/// "--speed: nan is not a finite number" / "--speed: -5 is out of range: expected a
/// number in [0, 1000]". CLI::Range's replacement: it lets nan through (every
/// comparison with nan is false).
CLI::Validator range(double lo, double hi);
CLI::Validator range(int lo, int hi);

/// "<program> (elaslam <version>, git <commit>)".
std::string version_line(const std::string& program);

/// Adds --version (prints version_line(program) and exits 0).
void add_version_flag(CLI::App& app, const std::string& program);

/// Adds --config FILE into *path, its help naming what the program reads (`what`,
/// e.g. "its robot: section") and the lookup rule with the installed default's name.
void add_config_option(CLI::App& app, std::string* path, const std::string& what,
                       const std::string& default_name = "paper.yaml");

/// <prefix>/share/elaslam, where <prefix> is the parent of the running program's
/// directory (/proc/self/exe): /usr/share/elaslam for /usr/bin/elaslam-*, the same
/// under any `cmake --install --prefix` or `dpkg -x` root, and build/share/elaslam
/// for build/bin/* (the build mirrors the installed layout there).
std::string data_dir();

/// A Python tool shipped with the programs: data_dir()/tools/<name>. Executable; it
/// runs itself in the project's .venv when started from a source tree that has one.
std::string python_tool(const std::string& name);

constexpr const char* kSystemConfig = "/etc/elaslam/elaslam.yaml";
constexpr const char* kConfigEnv = "ELASLAM_CONFIG";

/// Where a program looks for its configuration (find_config's inputs).
struct ConfigPlaces {
  std::string given;                      // --config, "" when not given
  std::optional<std::string> env;         // $ELASLAM_CONFIG, nullopt when unset
  std::string system = kSystemConfig;     // the deployment's file
  std::string installed;                  // the installed default
};

struct ConfigChoice {
  std::string path;    // the file to read
  std::string origin;  // "--config", "$ELASLAM_CONFIG", "/etc/elaslam/elaslam.yaml", "installed default"
};

/// The one lookup rule of every program: --config, else $ELASLAM_CONFIG, else
/// /etc/elaslam/elaslam.yaml, else the installed default. A path that was asked
/// for (--config, the variable) must exist: it never falls through to the next
/// place. Throws config::ConfigError listing every place it looked when none applies.
ConfigChoice find_config(const ConfigPlaces& places);

/// find_config with this process's environment and data_dir()/config/<default_name>.
ConfigChoice find_config(const std::string& given, const std::string& default_name = "paper.yaml");

/// The command line as one shell-quoted string.
std::string command_line(int argc, const char* const* argv);

}  // namespace elaslam::cli

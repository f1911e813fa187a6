// What every program's command line shares: --version, the config lookup rule, the
// command line as text (provenance in metrics.json), and where the installed data
// (configs, Python tools, message definitions) lives.
#pragma once

#include <optional>
#include <string>

namespace CLI {
class App;
}

namespace elaslam::cli {

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

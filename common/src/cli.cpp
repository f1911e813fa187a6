// SPDX-License-Identifier: Apache-2.0
#include "elaslam/common/cli.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <new>
#include <stdexcept>
#include <system_error>
#include <vector>

#include <CLI/CLI.hpp>
#include <yaml-cpp/yaml.h>

#include "elaslam/common/config.hpp"
#include "elaslam/common/log.hpp"
#include "elaslam/common/version.hpp"

namespace elaslam::cli {
namespace {

bool is_file(const std::string& p) {
  std::error_code ec;
  return std::filesystem::is_regular_file(p, ec);
}

/// Why a path cannot be used, "" when it can.
std::string file_problem(const std::string& p) {
  std::error_code ec;
  const auto st = std::filesystem::status(p, ec);
  if (ec || !std::filesystem::exists(st)) return "no such file";
  if (!std::filesystem::is_regular_file(st)) return "not a regular file";
  return "";
}

std::string shell_quote(const std::string& s) {
  if (!s.empty() && s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-+=./,:@%") ==
                        std::string::npos)
    return s;
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

/// The number `text` holds, when all of it is one (strtod's syntax, as CLI11's).
bool to_number(const std::string& text, double* v) {
  if (text.empty()) return false;
  char* end = nullptr;
  *v = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size();
}

std::string shortest(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.15g", v);
  return buf;
}

CLI::Validator number_range(double lo, double hi, const char* type_name) {
  const std::string range = "[" + shortest(lo) + ", " + shortest(hi) + "]";
  return CLI::Validator(
      [lo, hi, range](std::string& text) {
        double v = 0.0;
        if (!to_number(text, &v)) return text + " is not a number";
        if (!std::isfinite(v)) return text + " is not a finite number";
        if (!(v >= lo && v <= hi)) return text + " is out of range: expected a number in " + range;
        return std::string();
      },
      std::string(type_name) + " in " + range);
}

}  // namespace

int guarded_main(const std::string& program, const std::function<int()>& body) {
  const auto say = [&](const std::string& what) {  // the program ends: err in the journal
    log::print(stderr, log::Priority::kErr, "%s: %s\n", program.c_str(), what.c_str());
  };
  try {
    return body();
  } catch (const config::ConfigError& e) {
    say(e.what());
    return kExitBadInput;
  } catch (const YAML::Exception& e) {  // the loader refuses what would throw this: a guard, not a path
    say(std::string("configuration: ") + e.what());
    return kExitBadInput;
  } catch (const std::invalid_argument& e) {  // the libraries' bad-argument errors name the value
    say(e.what());
    return kExitBadInput;
  } catch (const std::bad_alloc&) {
    say("out of memory");
    return kExitFailure;
  } catch (const std::exception& e) {
    say(std::string("error: ") + e.what());
    return kExitFailure;
  } catch (...) {
    say("error: an exception of unknown type");
    return kExitFailure;
  }
}

int parse(CLI::App& app, int argc, const char* const* argv) {
  try {
    app.parse(argc, argv);
    for (const CLI::Option* o : app.get_options()) {
      if (o->get_type_name().rfind("FLOAT", 0) != 0) continue;  // CLI11 names double options FLOAT
      for (const std::string& v : o->results()) {
        double x = 0.0;
        if (to_number(v, &x) && !std::isfinite(x))
          throw CLI::ValidationError(o->get_name(), v + " is not a finite number");
      }
    }
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? kExitOk : kExitBadInput;
  }
  return -1;
}

CLI::Validator range(double lo, double hi) { return number_range(lo, hi, "FLOAT"); }
CLI::Validator range(int lo, int hi) { return number_range(lo, hi, "INT"); }

std::string version_line(const std::string& program) {
  return program + " (elaslam " + version() + ", git " + git_commit() + ")";
}

void add_version_flag(CLI::App& app, const std::string& program) {
  app.set_version_flag("--version", version_line(program), "print the version and the source commit, then exit");
}

void add_config_option(CLI::App& app, std::string* path, const std::string& what, const std::string& default_name) {
  app.add_option("--config", *path,
                 "YAML config file, " + what + " (default: $" + std::string(kConfigEnv) + ", else " + kSystemConfig +
                     ", else the installed " + default_name + ")");
}

std::string data_dir() {
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return "/usr/share/elaslam";  // no /proc: the packaged location
  return (exe.parent_path().parent_path() / "share" / "elaslam").string();
}

std::string python_tool(const std::string& name) { return data_dir() + "/tools/" + name; }

ConfigChoice find_config(const ConfigPlaces& p) {
  if (!p.given.empty()) {
    const std::string why = file_problem(p.given);
    if (!why.empty()) throw config::ConfigError::not_found("--config " + p.given + ": " + why, {});
    return {p.given, "--config"};
  }
  if (p.env) {
    const std::string why = file_problem(*p.env);
    if (!why.empty())
      throw config::ConfigError::not_found(std::string("$") + kConfigEnv + "=" + *p.env + ": " + why + " (unset " +
                                               kConfigEnv + " or point it at a config file)",
                                           {});
    return {*p.env, std::string("$") + kConfigEnv};
  }
  if (is_file(p.system)) return {p.system, p.system};
  if (is_file(p.installed)) return {p.installed, "installed default"};
  throw config::ConfigError::not_found(
      "no configuration file; looked at, in this order:",
      {"--config: not given", std::string("$") + kConfigEnv + ": not set", p.system + ": " + file_problem(p.system),
       p.installed + " (installed default): " + file_problem(p.installed),
       "give one with --config FILE (config/paper.yaml in the source tree)"});
}

ConfigChoice find_config(const std::string& given, const std::string& default_name) {
  ConfigPlaces p;
  p.given = given;
  if (const char* env = std::getenv(kConfigEnv); env && *env) p.env = std::string(env);
  p.installed = data_dir() + "/config/" + default_name;
  return find_config(p);
}

std::string command_line(int argc, const char* const* argv) {
  std::string out;
  for (int i = 0; i < argc; ++i) out += (i ? " " : "") + shell_quote(argv[i]);
  return out;
}

}  // namespace elaslam::cli

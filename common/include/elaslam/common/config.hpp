// SPDX-License-Identifier: Apache-2.0
// Configuration loading (yaml-cpp): one options struct per component, every error
// collected with its key path and reported at once, ranges checked, unknown keys
// rejected, and the effective configuration recorded as it is read so that it can
// be printed or echoed into results.
//
// Usage, in a component's parse function (robot_node/src/robot_options.cpp):
//   void parse(config::Reader& r, RobotOptions* o) {
//     r.section("filter", [&](config::Reader& f) {
//       f.read("range_sigma_m", &o->ekf.range_sigma, 1e-6, 100.0);   // required, in range
//       f.read_optional("joseph", &o->ekf.joseph);                   // documented default
//     });
//     r.read_enum("mode", &mode, {"ekf", "gated", "ela", "consensus"});
//   }
// and at the top:
//   config::Document doc = config::Document::from_file(path);   // throws ConfigError
//   RobotOptions o = config::read_component<RobotOptions>(doc, "robot");  // throws ConfigError
// which reads the section with that parse(), allows the other components' sections
// and finishes the document (Document::section, allow_sections, finish).
#pragma once

#include <cstddef>
#include <functional>
#include <initializer_list>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

namespace elaslam::config {

/// The top-level sections of the one config file, and who reads them: scenario
/// (simulator), dataset (the MRCLAM importer, in place of scenario), robot (every
/// robot_node), main (main_robot), team (every process on LCM: the team key,
/// transport/process.hpp). Any other top-level key is an error.
inline constexpr const char* kSections[] = {"scenario", "dataset", "robot", "main", "team"};

/// What the loader accepts as a configuration file (Document::from_file): a regular
/// file of at most this many bytes (read with a bounded read, so that /dev/zero, a
/// FIFO or a runaway file is refused at once), UTF-8 text without NUL bytes, one
/// YAML document whose keys are plain names, each once per map, nested at most
/// kMaxDepth levels and with at most kMaxNodes values once aliases are expanded.
inline constexpr std::size_t kMaxFileBytes = std::size_t{1} << 20;  // 1 MiB; config/paper.yaml is 10 KB
inline constexpr int kMaxDepth = 64;
inline constexpr std::size_t kMaxNodes = 100000;

/// All problems found in a configuration, one per line, each naming its key path.
class ConfigError : public std::runtime_error {
 public:
  ConfigError(const std::string& source, std::vector<std::string> problems);
  /// A file that could not be found: `headline`, then one line per place looked at.
  static ConfigError not_found(const std::string& headline, std::vector<std::string> places);
  const std::vector<std::string>& problems() const { return problems_; }

 private:
  ConfigError(std::string message, std::vector<std::string> problems, int);
  std::vector<std::string> problems_;
};

/// Shared state of one parse: the problems found and the effective config.
struct ParseState {
  std::vector<std::string> problems;
  YAML::Node effective = YAML::Node(YAML::NodeType::Map);
};

/// A view of one YAML map at a key path. Every key read is remembered; finish()
/// (called by Document for each section) reports the keys nobody read as unknown.
class Reader {
 public:
  Reader(YAML::Node node, std::string path, std::shared_ptr<ParseState> state);

  /// Required scalars, with an inclusive range.
  void read(const std::string& key, double* out, double lo, double hi);
  void read(const std::string& key, int* out, int lo, int hi);
  void read(const std::string& key, bool* out);
  void read(const std::string& key, std::string* out);
  /// Optional scalars: *out keeps its value (the documented default) when absent;
  /// the default is recorded in the effective config either way.
  void read_optional(const std::string& key, double* out, double lo, double hi);
  void read_optional(const std::string& key, int* out, int lo, int hi);
  void read_optional(const std::string& key, bool* out);
  void read_optional(const std::string& key, std::string* out);
  /// A string that must be one of `allowed`.
  void read_enum(const std::string& key, std::string* out, std::initializer_list<const char*> allowed,
                 bool optional = false);
  /// A fixed-length list of numbers, each within [lo, hi].
  void read_vector(const std::string& key, std::vector<double>* out, std::size_t size, double lo, double hi);
  /// A list of min_items to max_items strings, each one of `allowed` (repeats allowed).
  /// Optional and absent: *out keeps its value (the documented default), echoed.
  void read_enum_list(const std::string& key, std::vector<std::string>* out,
                      std::initializer_list<const char*> allowed, std::size_t min_items, std::size_t max_items,
                      bool optional = false);

  /// Required nested map; the callback reads it. Unknown keys inside are reported.
  void section(const std::string& key, const std::function<void(Reader&)>& fn, bool optional = false);
  /// Required list of maps; the callback reads each (index given).
  void list(const std::string& key, const std::function<void(Reader&, std::size_t)>& fn,
            std::size_t min_items, std::size_t max_items);

  bool has(const std::string& key) const;
  /// Record a problem at this path (for cross-field checks).
  void fail(const std::string& key, const std::string& what);
  const std::string& path() const { return path_; }

  /// Report keys of this map that were never read.
  void finish();

 private:
  // A nested section's reader: its effective map is `effective`, the parent's child
  // (not found again from the root by `path`, which a list item's path cannot address).
  Reader(YAML::Node node, std::string path, std::shared_ptr<ParseState> state, YAML::Node effective);
  std::string key_path(const std::string& key) const;
  YAML::Node child(const std::string& key, bool optional, bool* present);
  template <typename T>
  bool scalar(const std::string& key, T* out, bool optional, const char* type_name);
  void record(const std::string& key, const YAML::Node& value);
  void check_range(const std::string& key, double v, double lo, double hi);  // finite and in [lo, hi]

  YAML::Node node_;
  std::string path_;
  std::shared_ptr<ParseState> state_;
  std::vector<std::string> seen_;
  YAML::Node effective_;  // this map's place in state_->effective
};

/// A whole configuration file. Sections are read by components; keys at the top
/// level that no component reads are reported by finish().
class Document {
 public:
  /// Throws ConfigError naming the file and every problem found: not a regular
  /// file, too large, not UTF-8 text, malformed YAML (with its line), more than one
  /// document, non-scalar or duplicate keys (with their key paths and lines).
  static Document from_file(const std::string& path);
  static Document from_string(const std::string& text, const std::string& source = "<string>");

  /// Read one top-level section with `fn`.
  void section(const std::string& key, const std::function<void(Reader&)>& fn, bool optional = false);
  /// Mark top-level keys as known without reading them (read by another component).
  void allow(std::initializer_list<const char*> keys);
  /// Allow every section of the one config file (kSections) that this reader does
  /// not read itself: a component ignores the others' sections, and only those.
  void allow_sections();
  /// Throws ConfigError with every problem found so far (unknown top-level keys too).
  void finish();

  /// The effective configuration read so far, as YAML text.
  std::string effective_yaml() const;
  const YAML::Node& effective() const { return state_->effective; }
  const std::string& source() const { return source_; }

 private:
  Document(YAML::Node root, std::string source);
  YAML::Node root_;
  std::string source_;
  std::shared_ptr<ParseState> state_;
  void know(const std::string& key);  // a section name accepted at the top level (once)
  std::vector<std::string> known_;
};

/// One component's options from `doc`: section `key` read into a fresh Options by the
/// component's parse(Reader&, Options*) (found by argument-dependent lookup), every
/// other section of the file allowed, the document finished. Throws ConfigError with
/// every problem found.
template <typename Options>
Options read_component(Document& doc, const std::string& key) {
  Options o;
  doc.section(key, [&](Reader& r) { parse(r, &o); });
  doc.allow_sections();
  doc.finish();
  return o;
}

/// An effective configuration (YAML text) with overrides written into it, so that
/// what a run records is what ran: `edit` gets the parsed root map. Text that is not
/// a map (a config built in code has none) is returned unchanged unless `create`,
/// then the edit starts from an empty map.
std::string edit_yaml(const std::string& text, const std::function<void(YAML::Node& root)>& edit, bool create = true);

}  // namespace elaslam::config

// SPDX-License-Identifier: Apache-2.0
// The configuration loader's input checks (config.cpp's Document::from_file and
// from_string), before any component reads a key: the file (config::kMaxFileBytes,
// regular files only), the bytes (UTF-8 text) and the document's shape (plain
// keys, each once per map; kMaxDepth, kMaxNodes). Each returns problems in the
// ConfigError style: "<key path>: <what>" or, for the file and text, "<what>".
#pragma once

#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

namespace elaslam::config::input {

/// The whole file into *text; false with *why when it is not a readable regular file
/// of at most kMaxFileBytes. Never blocks on a FIFO and never reads past the limit.
bool read_file(const std::string& path, std::string* text, std::string* why);

/// A NUL byte or bytes that are not UTF-8, with the line and column of the first
/// of each (a config is text; yaml-cpp would read past a NUL or mangle the bytes).
std::vector<std::string> text_problems(const std::string& text);

/// Keys that are not plain scalars (a list, a map or null as a key), keys given
/// twice in one map (yaml-cpp keeps the first silently), and a tree too deep or too
/// large (aliases expanded: the walk is bounded by kMaxNodes).
std::vector<std::string> structure_problems(const YAML::Node& root);

}  // namespace elaslam::config::input

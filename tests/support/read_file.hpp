// SPDX-License-Identifier: Apache-2.0
// The whole text of a file, for the tests that compare what a program wrote.
#pragma once

#include <fstream>
#include <sstream>
#include <string>

namespace elaslam::test {

/// The bytes of the file at `path` ("" when it cannot be read).
inline std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace elaslam::test

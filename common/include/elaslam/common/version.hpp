// SPDX-License-Identifier: Apache-2.0
// The build's version and source commit (generated at build time by
// cmake/version.cmake into the build tree).
#pragma once

namespace elaslam {

/// The project version, e.g. "0.2.0".
const char* version();
/// The source tree's git commit (12 hex digits, "-dirty" when tracked files were
/// changed), or "unknown" when built outside git.
const char* git_commit();

}  // namespace elaslam

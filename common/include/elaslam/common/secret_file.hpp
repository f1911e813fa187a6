// SPDX-License-Identifier: Apache-2.0
// Reading a secret from a file (a node's key, the viewer's access token): the checks
// both share. A secret file is refused unless it is a regular file (not a symbolic
// link, a directory, a FIFO or a device), owned by the running user or by root,
// without group or other permissions (0600 or 0400). A systemd credential
// ($CREDENTIALS_DIRECTORY/NAME: a copy systemd made readable by the service only) is
// exempt from the owner and mode checks. The bytes read are the caller's to wipe; a
// reason never holds them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace elaslam::files {

/// Is `path` a file directly in $CREDENTIALS_DIRECTORY?
bool in_credentials_directory(const std::string& path);

/// At most `capacity` bytes of the secret file at `path` into `out`, their count in
/// *n; *more when the file holds more. False with why (prefixed by `what`, e.g. "key
/// file PATH: ") when the file may not hold a secret (rules above) or cannot be read.
/// Opened with O_NOFOLLOW and O_NONBLOCK: a link or a FIFO put in its place after the
/// check is not followed or waited on.
bool read_secret_file(const std::string& path, const std::string& what, std::uint8_t* out, std::size_t capacity,
                      std::size_t* n, bool* more, std::string* why);

}  // namespace elaslam::files

// SPDX-License-Identifier: Apache-2.0
// The viewer's access token (docs/security.md, "The viewer as an HTTP service"): a peer that is not this
// machine's loopback must show it, as "Authorization: Bearer TOKEN" or "?token=TOKEN"
// (a browser's EventSource cannot set a header). The token is 32 or more random bytes
// written as hexadecimal in a file that only its owner may read, checked as the team
// key file is (transport/src/team_key.cpp).
#pragma once

#include <string>
#include <string_view>

namespace elaslam::viewer {

/// The token file's bounds: 32 to 128 random bytes, as 64 to 256 hexadecimal digits.
inline constexpr std::size_t kTokenMinHex = 64;
inline constexpr std::size_t kTokenMaxHex = 256;

/// Reads the token at `path` into *token (its hexadecimal text): a regular file, not
/// a symbolic link, owned by this user or root, with no permission for group or
/// others (0600, 0400), holding 64 to 256 hexadecimal digits (an even count, not all
/// zeros) and at most one final newline. A file in $CREDENTIALS_DIRECTORY (systemd's
/// LoadCredential=) is taken whatever its owner and mode, as the team key's is.
/// false and *why (naming the file and the fix) otherwise.
bool load_access_token(const std::string& path, std::string* token, std::string* why);

/// Makes a token file at `path`: 32 random bytes from the kernel (getrandom) as 64
/// hexadecimal digits and a newline, mode 0600. Never overwrites: an existing name
/// (a file, a directory, a symbolic link, even a dangling one) is refused and a link
/// is never followed (O_CREAT | O_EXCL). false and *why otherwise. The token is not
/// printed.
bool make_access_token(const std::string& path, std::string* why);

/// expected == given, in a time that depends on the given length only, never on
/// where the two first differ.
bool tokens_equal(std::string_view expected, std::string_view given);

/// The credential of "Bearer TOKEN" (the scheme in any case, spaces around the
/// token ignored); "" for any other Authorization value.
std::string_view bearer_token(std::string_view authorization);

/// Who may read the viewer: a loopback peer (is_loopback_address) always, another one
/// with the token. Without a token only loopback peers.
class AccessPolicy {
 public:
  explicit AccessPolicy(std::string token) : token_(std::move(token)) {}

  /// `authorization`: the request's Authorization header; `token_param`: its
  /// ?token= parameter (either may be empty).
  bool allows(std::string_view peer, std::string_view authorization, std::string_view token_param) const;
  bool has_token() const { return !token_.empty(); }

 private:
  std::string token_;
};

}  // namespace elaslam::viewer

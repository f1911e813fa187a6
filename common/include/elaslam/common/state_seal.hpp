// SPDX-License-Identifier: Apache-2.0
// The seal of a state file: a header line that names the file's format and its
// version and carries a MAC over every byte of the file, so that a damaged or
// hand-altered file is refused before any of it is parsed. The sealed file stays
// one JSON document (a tool can still json.load it and read "state"):
//
//   {"format":"<format>","version":<n>,"seal":"<seal>","mac":"<64 hex digits>","state":\n
//   <body, a JSON value>}\n
//
// <seal> is "blake2b-256-keyed" when a state key is given, else "blake2b-256". The
// MAC is BLAKE2b with a 32-byte output (libsodium crypto_generichash; RFC 7693),
// keyed with the 32-byte state key when one is given, over the whole file with its
// own 64 hex digits read as '0' (so the header's format, version and seal are
// covered as well as the body). Unkeyed, it finds damage (a flipped bit, a truncated
// write, a file of another format) but anyone who can write the file can recompute
// it; keyed, only a holder of the key can make a file that opens.
// docs/security.md, "main_robot's state file". No I/O: files::read_all and files::write_atomic move
// the text.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace elaslam {

/// A state key: 32 secret bytes (derived by the caller from the node's secret key).
using StateKey = std::array<std::uint8_t, 32>;

/// Bytes of the MAC (crypto_generichash_BYTES); 2x as many hex digits in the header.
constexpr std::size_t kStateMacBytes = 32;
/// The longest header line accepted (a format name of up to 64 characters and a
/// version of up to 9 digits take 207): a text without a '\n' in its first this many
/// bytes is not a sealed file, whatever follows.
constexpr std::size_t kMaxStateHeaderBytes = 256;
/// The longest format name; its characters are [a-z0-9._-] (no JSON escaping).
constexpr std::size_t kMaxStateFormatChars = 64;

/// The sealed file text of `body` (a JSON value, e.g. an object's dump): header line,
/// body, "}\n". `format`: [a-z0-9._-], 1 to kMaxStateFormatChars characters;
/// `version`: [0, 999999999]; both are the caller's constants. `key` nullptr:
/// unkeyed. Throws std::invalid_argument on a format or version outside those (a
/// programming error, never the data).
std::string seal_state(std::string_view format, int version, std::string_view body, const StateKey* key);

/// How many bytes seal_state adds to a body of this format (for size bounds).
std::size_t sealed_state_overhead(std::string_view format);

/// Opens a sealed text: the header must be exactly the one seal_state writes, with
/// `format` and `version`; its seal must match `key` (a keyed file needs the key, and
/// with a key an unkeyed file is refused: anyone can recompute an unkeyed hash); the
/// text must end with "}\n"; and the MAC must verify (compared in constant time).
/// Then true, and `*body` views the body within `text`. Else false, `*body`
/// untouched, and `why` (optional) says what was wrong and, where it helps, the
/// likely cause. Nothing of the body is parsed.
bool open_state(std::string_view text, std::string_view format, int version, const StateKey* key,
                std::string_view* body, std::string* why);

}  // namespace elaslam

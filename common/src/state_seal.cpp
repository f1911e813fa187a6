// SPDX-License-Identifier: Apache-2.0
#include "elaslam/common/state_seal.hpp"

#include <sodium.h>

#include <stdexcept>

namespace elaslam {
namespace {

constexpr const char* kSealKeyed = "blake2b-256-keyed";
constexpr const char* kSealUnkeyed = "blake2b-256";
constexpr std::size_t kMacHexChars = 2 * kStateMacBytes;
constexpr std::string_view kTrailer = "}\n";
constexpr int kMaxVersion = 999999999;  // 9 digits
static_assert(kStateMacBytes == crypto_generichash_BYTES && sizeof(StateKey) == crypto_generichash_KEYBYTES);

bool format_char(char c) { return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-'; }

bool valid_format(std::string_view f) {
  if (f.empty() || f.size() > kMaxStateFormatChars) return false;
  for (char c : f)
    if (!format_char(c)) return false;
  return true;
}

// The header line up to the MAC's digits, and after them (with the '\n').
std::string header_head(std::string_view format, int version, bool keyed) {
  return "{\"format\":\"" + std::string(format) + "\",\"version\":" + std::to_string(version) + ",\"seal\":\"" +
         (keyed ? kSealKeyed : kSealUnkeyed) + "\",\"mac\":\"";
}
constexpr std::string_view kHeaderTail = "\",\"state\":\n";

// BLAKE2b-256 of `text` with the kMacHexChars bytes at `mac_at` read as '0'.
std::array<std::uint8_t, kStateMacBytes> mac_of(std::string_view text, std::size_t mac_at, const StateKey* key) {
  static const int sodium_ready = sodium_init();  // 0 or 1 (already); -1 cannot happen on Linux with getrandom
  (void)sodium_ready;
  const std::string zeros(kMacHexChars, '0');
  crypto_generichash_state st;
  crypto_generichash_init(&st, key ? key->data() : nullptr, key ? key->size() : 0, kStateMacBytes);
  const auto feed = [&st](std::string_view part) {
    crypto_generichash_update(&st, reinterpret_cast<const unsigned char*>(part.data()), part.size());
  };
  feed(text.substr(0, mac_at));
  feed(zeros);
  feed(text.substr(mac_at + kMacHexChars));
  std::array<std::uint8_t, kStateMacBytes> out{};
  crypto_generichash_final(&st, out.data(), out.size());
  return out;
}

std::string hex(const std::array<std::uint8_t, kStateMacBytes>& mac) {
  std::string out(kMacHexChars + 1, '\0');
  sodium_bin2hex(out.data(), out.size(), mac.data(), mac.size());  // lowercase
  out.pop_back();
  return out;
}

bool fail(std::string* why, const std::string& what) {
  if (why) *why = what;
  return false;
}

// A strict reader of the header line: exactly the bytes seal_state writes.
struct HeaderReader {
  explicit HeaderReader(std::string_view l) : line(l) {}
  std::string_view line;
  std::size_t at = 0;
  std::string problem;

  bool expect(std::string_view literal) {
    if (line.substr(at, literal.size()) == literal) {
      at += literal.size();
      return true;
    }
    problem = "expected '" + std::string(literal) + "' at byte " + std::to_string(at);
    return false;
  }
  // Characters up to the next '"' that pass `ok`, at most `max`.
  bool token(std::size_t max, bool (*ok)(char), std::string_view* out) {
    const std::size_t start = at;
    while (at < line.size() && line[at] != '"' && at - start <= max && ok(line[at])) ++at;
    if (at == start || at - start > max || at >= line.size() || line[at] != '"') {
      problem = "a malformed field at byte " + std::to_string(start);
      return false;
    }
    *out = line.substr(start, at - start);
    return true;
  }
};

bool version_char(char c) { return c >= '0' && c <= '9'; }
bool seal_char(char c) { return format_char(c); }
bool hex_char(char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); }  // lowercase only: one form

}  // namespace

std::size_t sealed_state_overhead(std::string_view format) {
  return header_head(format, kMaxVersion, true).size() + kMacHexChars + kHeaderTail.size() + kTrailer.size();
}

std::string seal_state(std::string_view format, int version, std::string_view body, const StateKey* key) {
  if (!valid_format(format)) throw std::invalid_argument("seal_state: format \"" + std::string(format) + "\" is not [a-z0-9._-]{1,64}");
  if (version < 0 || version > kMaxVersion) throw std::invalid_argument("seal_state: version " + std::to_string(version) + " not in [0, 999999999]");
  const std::string head = header_head(format, version, key != nullptr);
  std::string text;
  text.reserve(head.size() + kMacHexChars + kHeaderTail.size() + body.size() + kTrailer.size());
  text.append(head).append(kMacHexChars, '0').append(kHeaderTail).append(body).append(kTrailer);
  text.replace(head.size(), kMacHexChars, hex(mac_of(text, head.size(), key)));
  return text;
}

bool open_state(std::string_view text, std::string_view format, int version, const StateKey* key,
                std::string_view* body, std::string* why) {
  // 1. The header line, read strictly (no JSON parser sees anything before the MAC holds).
  const std::string no_header = "no seal header: it does not start with '{\"format\":\"' and a '\\n' within " +
                                std::to_string(kMaxStateHeaderBytes) +
                                " bytes (a file of before the seal, of another program, or damaged)";
  const std::size_t nl = text.substr(0, kMaxStateHeaderBytes).find('\n');
  if (nl == std::string_view::npos) return fail(why, no_header);
  HeaderReader h(text.substr(0, nl + 1));
  std::string_view got_format, got_version, seal, mac_hex;
  if (!h.expect("{\"format\":\"")) return fail(why, no_header);
  if (!h.token(kMaxStateFormatChars, format_char, &got_format) || !h.expect("\",\"version\":"))
    return fail(why, "seal header: " + h.problem + " (damaged?)");
  // The version's digits end at ',' not '"': read them by hand.
  const std::size_t vstart = h.at;
  while (h.at < h.line.size() && version_char(h.line[h.at]) && h.at - vstart < 9) ++h.at;
  got_version = h.line.substr(vstart, h.at - vstart);
  if (got_version.empty() || (got_version.size() > 1 && got_version[0] == '0') || !h.expect(",\"seal\":\"") ||
      !h.token(32, seal_char, &seal) || !h.expect("\",\"mac\":\""))
    return fail(why, "seal header: " + (h.problem.empty() ? "a malformed version" : h.problem) + " (damaged?)");
  const std::size_t mac_at = h.at;
  if (!h.token(kMacHexChars, hex_char, &mac_hex) || mac_hex.size() != kMacHexChars || !h.expect(kHeaderTail) ||
      h.at != h.line.size())
    return fail(why, "seal header: the MAC is not " + std::to_string(kMacHexChars) +
                         " lowercase hex digits followed by ',\"state\":' (damaged?)");
  // 2. What the header says, against what the caller reads.
  if (got_format != format)
    return fail(why, "format \"" + std::string(got_format) + "\", expected \"" + std::string(format) + "\" (another program's file?)");
  if (std::stoi(std::string(got_version)) != version)
    return fail(why, "format version " + std::string(got_version) + ", this build reads version " + std::to_string(version));
  const bool keyed = seal == kSealKeyed;
  if (!keyed && seal != kSealUnkeyed)
    return fail(why, "seal \"" + std::string(seal) + "\", expected \"" + kSealUnkeyed + "\" or \"" + kSealKeyed + "\"");
  if (keyed && !key)
    return fail(why, "sealed with a state key, and none is configured here: it cannot be verified");
  if (!keyed && key)
    return fail(why, "sealed without a key while a state key is configured: an unkeyed hash anyone can recompute "
                     "is not accepted (altered, or written by a build without the key)");
  // 3. The body ends at the closing "}\n" of the document.
  if (text.size() < nl + 1 + kTrailer.size() || text.substr(text.size() - kTrailer.size()) != kTrailer)
    return fail(why, "the file does not end with \"}\\n\" (truncated?)");
  // 4. The MAC, in constant time.
  std::array<std::uint8_t, kStateMacBytes> stated{};
  if (sodium_hex2bin(stated.data(), stated.size(), mac_hex.data(), mac_hex.size(), nullptr, nullptr, nullptr) != 0)
    return fail(why, "seal header: the MAC is not hex");
  const auto computed = mac_of(text, mac_at, key);
  if (crypto_verify_32(stated.data(), computed.data()) != 0)
    return fail(why, std::string("the MAC does not verify: the file was altered or damaged") +
                         (keyed ? " (or sealed with another state key)" : ""));
  *body = text.substr(nl + 1, text.size() - nl - 1 - kTrailer.size());
  return true;
}

}  // namespace elaslam

// SPDX-License-Identifier: Apache-2.0
// The state files' seal (common/state_seal.hpp): the exact layout (a known answer
// any BLAKE2b can reproduce, e.g. Python's hashlib), keyed and unkeyed, and a strict
// header: every other form is refused before the body is looked at.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "elaslam/common/state_seal.hpp"

namespace elaslam {
namespace {

StateKey counting_key() {
  StateKey k;
  for (std::size_t i = 0; i < k.size(); ++i) k[i] = static_cast<std::uint8_t>(i);
  return k;
}

// hashlib.blake2b(text_with_64_zeros_for_the_mac, digest_size=32[, key=bytes(range(32))])
const std::string kUnkeyed =
    "{\"format\":\"elaslam.test\",\"version\":1,\"seal\":\"blake2b-256\",\"mac\":"
    "\"b10ff68bf195d56e65bf01a76748e161c386d4745489ff4268ff6b672394d659\",\"state\":\n{\"a\": 1}}\n";
const std::string kKeyed =
    "{\"format\":\"elaslam.test\",\"version\":1,\"seal\":\"blake2b-256-keyed\",\"mac\":"
    "\"40c5dde32bb4fcb0092626cace9e5b0653fa019d9f140c502041101acace1030\",\"state\":\n{\"a\": 1}}\n";

bool opens(const std::string& text, const StateKey* key, std::string* why = nullptr) {
  std::string_view body;
  return open_state(text, "elaslam.test", 1, key, &body, why);
}

TEST(StateSeal, TheLayoutAndMacAreExactlyTheDocumentedOnes) {
  const StateKey key = counting_key();
  EXPECT_EQ(seal_state("elaslam.test", 1, "{\"a\": 1}", nullptr), kUnkeyed);
  EXPECT_EQ(seal_state("elaslam.test", 1, "{\"a\": 1}", &key), kKeyed);
  std::string_view body;
  std::string why;
  ASSERT_TRUE(open_state(kKeyed, "elaslam.test", 1, &key, &body, &why)) << why;
  EXPECT_EQ(body, "{\"a\": 1}");
  ASSERT_TRUE(open_state(kUnkeyed, "elaslam.test", 1, nullptr, &body, &why)) << why;
  EXPECT_EQ(body, "{\"a\": 1}");
  const std::size_t body_bytes = std::string("{\"a\": 1}").size();
  EXPECT_EQ(sealed_state_overhead("elaslam.test"), kKeyed.size() - body_bytes + 8);  // the version counted at 9 digits
}

TEST(StateSeal, AKeyMismatchIsRefusedEitherWay) {
  const StateKey key = counting_key();
  StateKey other = key;
  other[31] ^= 1;
  std::string why;
  EXPECT_FALSE(opens(kKeyed, &other, &why));
  EXPECT_NE(why.find("the MAC does not verify"), std::string::npos) << why;
  EXPECT_FALSE(opens(kKeyed, nullptr, &why));
  EXPECT_NE(why.find("none is configured"), std::string::npos) << why;
  EXPECT_FALSE(opens(kUnkeyed, &key, &why));
  EXPECT_NE(why.find("sealed without a key"), std::string::npos) << why;
}

TEST(StateSeal, OnlyTheCanonicalHeaderOpens) {
  const auto with = [](std::string from, const std::string& to) {
    std::string t = kUnkeyed;
    t.replace(t.find(from), from.size(), to);
    return t;
  };
  struct Case {
    std::string text, why;
  };
  const Case cases[] = {
      {with("b10ff68b", "B10FF68B"), "lowercase hex"},  // the same MAC in upper case: one form only
      {with("\"version\":1", "\"version\":01"), "malformed version"},
      {with("\"version\":1", "\"version\":2"), "format version 2, this build reads version 1"},
      {with("elaslam.test", "elaslam.tesT"), "malformed field"},
      {with("elaslam.test", "elaslam.other"), "expected \"elaslam.test\""},
      {with("blake2b-256", "blake2b-512"), "seal \"blake2b-512\""},
      {with("{\"format\"", "{ \"format\""), "no seal header"},
      {with("\"state\":\n", "\"state\": \n"), "the MAC is not 64"},
      {kUnkeyed + " ", "does not end with"},
      {kUnkeyed.substr(0, kUnkeyed.size() - 1), "does not end with"},
      {std::string(300, '{'), "no seal header"},
      {"", "no seal header"},
  };
  for (const Case& c : cases) {
    std::string why;
    EXPECT_FALSE(opens(c.text, nullptr, &why)) << c.text;
    EXPECT_NE(why.find(c.why), std::string::npos) << c.text << ": " << why;
  }
}

TEST(StateSeal, AFlippedBitAnywhereIsRefused) {
  const StateKey key = counting_key();
  for (const std::string* text : {&kUnkeyed, &kKeyed}) {
    const StateKey* k = text == &kKeyed ? &key : nullptr;
    for (std::size_t at = 0; at < text->size(); ++at)
      for (int bit = 0; bit < 8; ++bit) {
        std::string t = *text;
        t[at] = static_cast<char>(t[at] ^ (1 << bit));
        EXPECT_FALSE(opens(t, k)) << "byte " << at << " bit " << bit;
      }
  }
}

TEST(StateSeal, AFormatOrVersionOutsideTheHeaderIsAProgrammingError) {
  EXPECT_THROW(seal_state("Elaslam", 1, "{}", nullptr), std::invalid_argument);
  EXPECT_THROW(seal_state("a\"b", 1, "{}", nullptr), std::invalid_argument);
  EXPECT_THROW(seal_state("", 1, "{}", nullptr), std::invalid_argument);
  EXPECT_THROW(seal_state("x", -1, "{}", nullptr), std::invalid_argument);
  EXPECT_THROW(seal_state("x", 1000000000, "{}", nullptr), std::invalid_argument);
  EXPECT_LE(seal_state(std::string(kMaxStateFormatChars, 'z'), 999999999, "{}", nullptr).find('\n') + 1,
            kMaxStateHeaderBytes);
}

}  // namespace
}  // namespace elaslam

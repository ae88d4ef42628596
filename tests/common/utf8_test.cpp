// common::is_utf8 decides whether outside text may go into the JSON files we write: it must
// accept exactly what nlohmann::json dumps without an error.
#include "common/utf8.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <random>
#include <string>

namespace {

using papersim::common::is_utf8;

bool nlohmann_dumps(const std::string& s) {
  try {
    (void)nlohmann::json(s).dump();
    return true;
  } catch (const nlohmann::json::type_error&) {
    return false;
  }
}

TEST(Utf8, BoundariesOfEachLength) {
  for (const char* good :
       {"", "plain ascii", "\x7f", "\xc2\x80", "\xdf\xbf", "\xe0\xa0\x80", "\xed\x9f\xbf",
        "\xee\x80\x80", "\xef\xbf\xbf", "\xf0\x90\x80\x80", "\xf4\x8f\xbf\xbf", "caf\xc3\xa9"})
    EXPECT_TRUE(is_utf8(good)) << good;
  for (const char* bad : {
           "\x80",              // a continuation byte alone
           "\xc0\xaf",          // overlong '/'
           "\xc1\xbf",          // overlong
           "\xe0\x9f\xbf",      // overlong 3-byte form
           "\xed\xa0\x80",      // surrogate U+D800
           "\xf0\x8f\xbf\xbf",  // overlong 4-byte form
           "\xf4\x90\x80\x80",  // above U+10FFFF
           "\xf5\x80\x80\x80",  // lead byte beyond F4
           "\xff",              // never in UTF-8
           "\xc3",              // cut short
           "\xe2\x82",          // cut short
           "ab\xc3(",           // a continuation byte missing
           "\xf0\x90\x80\x7f",  // the last byte not a continuation
       })
    EXPECT_FALSE(is_utf8(bad)) << bad;
  // '\0' is a character like any other.
  EXPECT_TRUE(is_utf8(std::string("a\0b", 3)));
}

// Random strings biased towards the bytes that matter (ASCII, continuation bytes, lead bytes
// near the boundaries): is_utf8 and nlohmann's dump agree on every one.
TEST(Utf8, AgreesWithWhatNlohmannDumps) {
  std::mt19937 rng(20261207);
  const unsigned char interesting[] = {0x00, 0x41, 0x7f, 0x80, 0x8f, 0x90, 0x9f, 0xa0, 0xbf,
                                       0xc0, 0xc1, 0xc2, 0xdf, 0xe0, 0xe1, 0xec, 0xed, 0xee,
                                       0xef, 0xf0, 0xf1, 0xf3, 0xf4, 0xf5, 0xfe, 0xff};
  std::uniform_int_distribution<int> length(0, 8), pick(0, sizeof interesting - 1), any(0, 255),
      coin(0, 3);
  int valid = 0, invalid = 0;
  for (int n = 0; n < 200000; ++n) {
    std::string s(static_cast<std::size_t>(length(rng)), '\0');
    for (char& c : s) c = static_cast<char>(coin(rng) == 0 ? any(rng) : interesting[pick(rng)]);
    const bool expected = nlohmann_dumps(s);
    ASSERT_EQ(is_utf8(s), expected) << "string #" << n << " of " << s.size() << " bytes";
    (expected ? valid : invalid)++;
  }
  // Both answers occur often, so the agreement says something about each.
  EXPECT_GT(valid, 10000);
  EXPECT_GT(invalid, 10000);
}

}  // namespace

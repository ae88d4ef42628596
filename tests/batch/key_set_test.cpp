// KeySet, the compact exact string set of dataset-stats, against std::unordered_set.
#include "batch/key_set.hpp"

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <unordered_set>

using papersim::batch::KeySet;

namespace {

/// A random key: sample-key-like ("meshes/<scenario>/<bucket>/<seed>") or random bytes of a
/// random length (0 to 40, '\0' included), drawn from a small alphabet so that keys repeat.
std::string random_key(std::mt19937_64& rng) {
  if (rng() % 2 == 0)
    return "meshes/fall-sphere/" + std::to_string(rng() % 300) + "/" + std::to_string(rng() % 3000);
  std::string key(rng() % 41, '\0');
  for (char& c : key) c = static_cast<char>("ab\0/"[rng() % 4]);
  return key;
}

/// `draws` inserts and lookups of random_key's keys into `set`: every answer must be
/// std::unordered_set's, and so must the size at the end.
void expect_standard_answers(KeySet& set, int draws, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::unordered_set<std::string> want;
  for (int n = 0; n < draws; ++n) {
    const std::string key = random_key(rng);
    ASSERT_EQ(set.insert(key), want.insert(key).second) << "insert #" << n;
    const std::string probe = random_key(rng);
    ASSERT_EQ(set.contains(probe), want.count(probe) > 0) << "lookup #" << n;
  }
  EXPECT_EQ(set.size(), want.size());
  for (const auto& key : want) ASSERT_TRUE(set.contains(key));
}

}  // namespace

// 400,000 inserts and lookups of keys drawn so that about half repeat, through many growths of
// the table: every answer must be std::unordered_set's.
TEST(KeySet, AnswersAsAStandardSetThroughGrowth) {
  KeySet set;
  expect_standard_answers(set, 400000, 7);
  EXPECT_GT(set.size(), 100000u);  // the table grew many times
}

// Keys that differ only in their last byte or in length, the empty key, keys with '\0' inside
// and keys on either side of the long-key limit (which go to a separate set) are all distinct.
TEST(KeySet, TellsApartKeysThatDifferInOneByteOrInLength) {
  KeySet set;
  const std::string prefix(KeySet::kLongKey - 1, 'k');
  const std::vector<std::string> keys = {
      "",           std::string(1, '\0'),   std::string(2, '\0'),   "a",
      "ab",         std::string("a\0b", 3), std::string("a\0c", 3), prefix,
      prefix + "x", prefix + "y",           prefix + "xy",          prefix + "xz"};
  for (const auto& key : keys) EXPECT_TRUE(set.insert(key)) << key.size();
  for (const auto& key : keys) EXPECT_FALSE(set.insert(key)) << key.size();
  for (const auto& key : keys) EXPECT_TRUE(set.contains(key)) << key.size();
  EXPECT_EQ(set.size(), keys.size());
  EXPECT_FALSE(set.contains("b"));
  EXPECT_FALSE(set.contains(std::string(3, '\0')));
  EXPECT_FALSE(set.contains(prefix + "z"));
  EXPECT_FALSE(set.contains(prefix + "xx"));
}

// With a hash that gives every key of a length the same value, every lookup walks a cluster of
// slots whose tags agree, and only the bytes tell the keys apart.
TEST(KeySet, ComparesTheBytesWhenHashesCollide) {
  const KeySet::Hash by_length = [](std::string_view key) -> std::uint64_t {
    return key.size() * 0x9E3779B97F4A7C15ULL;
  };
  KeySet set(by_length);
  expect_standard_answers(set, 20000, 11);
}

// A million sample keys of 30 bytes fit in the arena's bytes plus 8-byte slots at a load of at
// least 0.35: under 60 bytes a key, where a std::unordered_set<std::string> node alone is 64.
TEST(KeySet, AMillionSampleKeysTakeUnderSixtyBytesEach) {
  KeySet set;
  for (int seed = 0; seed < 1000000; ++seed)
    set.insert("meshes/fall-cylinder/" + std::to_string(seed / 1000) + "/" + std::to_string(seed));
  EXPECT_EQ(set.size(), 1000000u);
  const double per_key = static_cast<double>(set.memory_bytes()) / 1e6;
  EXPECT_LT(per_key, 60.0);
  EXPECT_GT(per_key, 30.0);  // at least the arena's 4 + 26..31 bytes a key
}

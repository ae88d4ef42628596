#pragma once
/// An exact set of strings that holds tens of millions of sample keys in under twice the memory of
/// their bytes: `papersim dataset-stats` keeps every finished sample's key to count it once.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <unordered_set>
#include <vector>

namespace papersim::batch {

/// A set of byte strings (any bytes, '\0' included). Keys are copied into an arena of fixed
/// blocks, each as a 4-byte length and its bytes; the table is open addressing with linear
/// probing over 8-byte slots, each the arena offset of a key (40 bits) and 24 bits of its hash.
/// Ten million sample keys of 29 bytes on average take 47 bytes each (0.47 GB; a
/// std::unordered_set<std::string> of them peaks at 1.34 GB). A key longer than kLongKey (not a
/// sample key, but possible in a hand-edited manifest) is kept in a std::unordered_set instead.
class KeySet {
 public:
  static constexpr std::size_t kLongKey = 4096;
  using Hash = std::uint64_t (*)(std::string_view);

  /// `hash` is std::hash's unless given (a test gives one that collides on purpose).
  explicit KeySet(Hash hash = nullptr);

  /// Add `key`: true when it was not in the set.
  bool insert(std::string_view key);
  /// Whether `key` is in the set.
  bool contains(std::string_view key) const;
  /// Keys in the set.
  std::size_t size() const { return m_size + m_long.size(); }
  /// Bytes held (arena, table, long keys' strings), for the memory figures.
  std::size_t memory_bytes() const;

 private:
  static constexpr std::size_t kBlock = std::size_t{1} << 22;  // 4 MiB of arena per block
  static constexpr std::uint64_t kOffsetBits = 40;
  static constexpr std::uint64_t kOffsetMask = (std::uint64_t{1} << kOffsetBits) - 1;

  /// Index of `key`'s slot, or of the empty slot where it would go; `found` tells which.
  std::size_t find(std::string_view key, std::uint64_t hash, bool& found) const;
  /// The key stored at arena offset `offset`.
  std::string_view stored(std::uint64_t offset) const;
  /// Copy `key` into the arena; its offset.
  std::uint64_t append(std::string_view key);
  /// Double the table and put every key in again.
  void grow();

  Hash m_hash;
  std::vector<std::unique_ptr<char[]>> m_blocks;
  std::size_t m_used = kBlock;  ///< bytes used of the last block (none yet: "full")
  /// Slots: 0 is empty, else (offset + 1) | tag << 40, tag the hash's top 24 bits.
  std::vector<std::uint64_t> m_slots;
  std::size_t m_size = 0;  ///< keys in the table
  std::unordered_set<std::string> m_long;
};

}  // namespace papersim::batch

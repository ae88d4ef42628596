#include "batch/key_set.hpp"

#include <cstring>
#include <functional>
#include <stdexcept>

namespace papersim::batch {

namespace {

std::uint64_t standard_hash(std::string_view key) { return std::hash<std::string_view>{}(key); }

}  // namespace

KeySet::KeySet(Hash hash) : m_hash(hash ? hash : standard_hash) {}

bool KeySet::insert(std::string_view key) {
  if (key.size() > kLongKey) return m_long.emplace(key).second;
  // Grow before the load passes 0.7, so that a probe always meets an empty slot.
  if (10 * (m_size + 1) > 7 * m_slots.size()) grow();
  const std::uint64_t hash = m_hash(key);
  bool found = false;
  const std::size_t i = find(key, hash, found);
  if (found) return false;
  m_slots[i] = (append(key) + 1) | (hash >> kOffsetBits << kOffsetBits);
  ++m_size;
  return true;
}

bool KeySet::contains(std::string_view key) const {
  if (key.size() > kLongKey) return m_long.count(std::string(key)) > 0;
  if (m_slots.empty()) return false;
  bool found = false;
  find(key, m_hash(key), found);
  return found;
}

std::size_t KeySet::memory_bytes() const {
  std::size_t bytes = m_blocks.size() * kBlock + m_slots.capacity() * sizeof(std::uint64_t);
  for (const auto& k : m_long) bytes += sizeof(std::string) + k.capacity();
  return bytes;
}

std::size_t KeySet::find(std::string_view key, std::uint64_t hash, bool& found) const {
  const std::size_t mask = m_slots.size() - 1;
  const std::uint64_t tag = hash >> kOffsetBits;
  for (std::size_t i = hash & mask;; i = (i + 1) & mask) {
    const std::uint64_t slot = m_slots[i];
    if (slot == 0) {
      found = false;
      return i;
    }
    if (slot >> kOffsetBits == tag && stored((slot & kOffsetMask) - 1) == key) {
      found = true;
      return i;
    }
  }
}

std::string_view KeySet::stored(std::uint64_t offset) const {
  const char* p = m_blocks[offset / kBlock].get() + offset % kBlock;
  std::uint32_t length = 0;
  std::memcpy(&length, p, sizeof length);
  return {p + sizeof length, length};
}

std::uint64_t KeySet::append(std::string_view key) {
  const std::size_t need = sizeof(std::uint32_t) + key.size();  // at most 4 + kLongKey < kBlock
  if (m_used + need > kBlock) {
    m_blocks.push_back(std::make_unique<char[]>(kBlock));
    m_used = 0;
  }
  const std::uint64_t offset = (m_blocks.size() - 1) * kBlock + m_used;
  if (offset + 1 > kOffsetMask) throw std::length_error("KeySet: more than 1 TiB of keys");
  char* p = m_blocks.back().get() + m_used;
  const auto length = static_cast<std::uint32_t>(key.size());
  std::memcpy(p, &length, sizeof length);
  std::memcpy(p + sizeof length, key.data(), key.size());
  m_used += need;
  return offset;
}

void KeySet::grow() {
  std::vector<std::uint64_t> old(m_slots.empty() ? 1024 : 2 * m_slots.size(), 0);
  old.swap(m_slots);
  const std::size_t mask = m_slots.size() - 1;
  for (const std::uint64_t slot : old) {
    if (slot == 0) continue;
    std::size_t i = m_hash(stored((slot & kOffsetMask) - 1)) & mask;
    while (m_slots[i] != 0) i = (i + 1) & mask;
    m_slots[i] = slot;
  }
}

}  // namespace papersim::batch

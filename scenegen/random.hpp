#pragma once
/// A small, portable random number generator. std::uniform_real_distribution is implementation
/// defined, so draws are made here to keep (seed -> scene) identical across standard libraries.
#include <cstdint>
#include <string_view>
#include <vector>

namespace papersim::scenegen {

/// splitmix64 step: used to seed and to derive independent streams.
inline std::uint64_t splitmix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

/// xoshiro256** generator with named sub-streams: `Rng(seed, "camera")` draws the same numbers
/// whatever the other components draw, so adding a draw to one component never shifts another.
class Rng {
 public:
  /// @param seed   sample seed
  /// @param stream name of the component drawing from this stream
  explicit Rng(std::uint64_t seed, std::string_view stream = "") {
    std::uint64_t h = 1469598103934665603ULL;  // FNV-1a of the stream name
    for (char c : stream) h = (h ^ static_cast<unsigned char>(c)) * 1099511628211ULL;
    std::uint64_t s = seed ^ (h * 0x9E3779B97F4A7C15ULL);
    for (auto& w : m_s) w = splitmix64(s);
  }
  /// Next raw 64-bit value.
  std::uint64_t next() {
    const std::uint64_t result = rotl(m_s[1] * 5, 7) * 9;
    const std::uint64_t t = m_s[1] << 17;
    m_s[2] ^= m_s[0];
    m_s[3] ^= m_s[1];
    m_s[1] ^= m_s[2];
    m_s[0] ^= m_s[3];
    m_s[2] ^= t;
    m_s[3] = rotl(m_s[3], 45);
    return result;
  }
  /// Uniform in [0, 1).
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  /// Uniform in [a, b).
  double uniform(double a, double b) { return a + (b - a) * uniform(); }
  /// Uniform integer in [a, b] (inclusive; a <= b), any range of int (b - a + 1 in 64 bits).
  int randint(int a, int b) {
    const auto n = static_cast<std::uint64_t>(static_cast<std::int64_t>(b) - a + 1);
    return a + static_cast<int>(next() % n);
  }
  /// A fresh 32-bit seed for a sub-generator (noise seeds recorded in meta.json).
  std::uint32_t seed32() { return static_cast<std::uint32_t>(next() >> 32); }

 private:
  static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  std::uint64_t m_s[4];
};

}  // namespace papersim::scenegen

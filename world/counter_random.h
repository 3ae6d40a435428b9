#pragma once
// Counter-based random numbers: a value is a pure function of (seed, counters), so results do
// not depend on evaluation order or thread count.
#include <cstdint>

namespace nephele {

// SplitMix64 finaliser: a bijective 64-bit mix with good avalanche.
constexpr std::uint64_t mix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

constexpr std::uint64_t hashCounters(std::uint64_t seed, std::uint64_t a, std::uint64_t b = 0,
                                     std::uint64_t c = 0) {
  return mix64(mix64(mix64(mix64(seed) ^ a) ^ b) ^ c);
}

// Uniform in [0, 1) from the top 53 bits.
constexpr double unitFromBits(std::uint64_t bits) {
  return double(bits >> 11) * 0x1.0p-53;
}

}  // namespace nephele

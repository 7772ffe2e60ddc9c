#pragma once
/// Seeds derived from a user's seed, one per independent piece of work.

#include <cstdint>

namespace csgvox {

/// The `index`-th seed derived from `seed`: SplitMix64's step and finaliser,
/// so neighbouring indices give unrelated generators.
inline std::uint64_t mixSeed(std::uint64_t seed, std::uint64_t index) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ull * (index + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

}  // namespace csgvox

// The portable bitset kernels (one word at a time) and the choice of a
// level's kernels.

#include "voxel/bitset_kernels.h"

#include <algorithm>
#include <array>
#include <bit>

#include "voxel/bitset_kernel_loops.h"

namespace csgvox {
namespace {

using Word = std::uint64_t;

// The primitives of bitset_kernel_loops.h for one word.
struct Portable {
  using Vec = Word;
  using Counts = std::size_t;
  using Sum = std::size_t;
  static constexpr std::size_t kLanes = 1;
  static constexpr std::size_t kStepsPerFold = ~std::size_t(0);

  static Vec load(const Word* p) { return *p; }
  static void store(Word* p, Vec v) { *p = v; }
  static Vec bitAnd(Vec x, Vec y) { return x & y; }
  static Vec bitAndNot(Vec x, Vec y) { return x & ~y; }
  static Vec bitOr(Vec x, Vec y) { return x | y; }
  static bool any(Vec v) { return v != 0; }
  static Word extractBits(Word x, Word m) {
    Word out = 0;
    for (Word bit = 1; m != 0; m &= m - 1, bit <<= 1) {
      if (x & m & (~m + 1)) out |= bit;
    }
    return out;
  }
  static std::size_t bitCount(Word m) { return std::size_t(std::popcount(m)); }
  static Counts zeroCounts() { return 0; }
  static Counts countBits(Counts c, Vec v) { return c + std::size_t(std::popcount(v)); }
  static Sum zeroSum() { return 0; }
  static Sum widen(Sum s, Counts c) { return s + c; }
  static std::size_t total(Sum s) { return s; }
};

constinit const BitsetKernels kPortable = bitset_loops::bitsetKernelsOf<Portable>();

// Index: the level; each entry the kernels of the highest level ≤ it that
// the CPU supports and the build has.
const std::array<const BitsetKernels*, 3>& kernelsByLevel() {
  static const auto table = kernelsByLevel(&kPortable, avx2BitsetKernels, avx512BitsetKernels);
  return table;
}

}  // namespace

const BitsetKernels* portableBitsetKernels() { return &kPortable; }

const BitsetKernels& bitsetKernels(SimdLevel level) {
  const auto& table = kernelsByLevel();
  return *table[std::size_t(std::clamp(int(level), 0, int(table.size()) - 1))];
}

// simdLevel() is never outside [Portable, Avx512].
const BitsetKernels& activeBitsetKernels() { return *kernelsByLevel()[std::size_t(simdLevel())]; }

}  // namespace csgvox

// The portable bitset kernels and the choice of a level's kernels.

#include "voxel/bitset_kernels.h"

#include <algorithm>
#include <array>
#include <bit>

namespace csgvox {
namespace {

using Word = std::uint64_t;

struct And {
  static Word apply(Word x, Word y) { return x & y; }
};
struct AndNot {
  static Word apply(Word x, Word y) { return x & ~y; }
};
struct Or {
  static Word apply(Word x, Word y) { return x | y; }
};

template <class Op>
std::size_t countOp(const Word* a, const Word* b, std::size_t n) {
  std::size_t c = 0;
  for (std::size_t i = 0; i < n; ++i) c += std::size_t(std::popcount(Op::apply(a[i], b[i])));
  return c;
}

template <class Op>
void applyOp(Word* a, const Word* b, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) a[i] = Op::apply(a[i], b[i]);
}

std::size_t count(const Word* a, std::size_t n) {
  std::size_t c = 0;
  for (std::size_t i = 0; i < n; ++i) c += std::size_t(std::popcount(a[i]));
  return c;
}

bool intersects(const Word* a, const Word* b, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    if (a[i] & b[i]) return true;
  }
  return false;
}

constinit const BitsetKernels kPortable{countOp<And>, countOp<AndNot>, countOp<Or>,
                                        count,        intersects,      applyOp<And>,
                                        applyOp<Or>,  applyOp<AndNot>};

}  // namespace

const BitsetKernels* portableBitsetKernels() { return &kPortable; }

const BitsetKernels& bitsetKernels(SimdLevel level) {
  // Index: the level; each entry the highest level ≤ it that the CPU
  // supports and the build has.
  static const auto table = [] {
    const SimdLevel cpu = detectedSimdLevel();
    const BitsetKernels* avx2 = cpu >= SimdLevel::Avx2 ? avx2BitsetKernels() : nullptr;
    const BitsetKernels* avx512 = cpu >= SimdLevel::Avx512 ? avx512BitsetKernels() : nullptr;
    const BitsetKernels* upToAvx2 = avx2 ? avx2 : &kPortable;
    return std::array<const BitsetKernels*, 3>{&kPortable, upToAvx2, avx512 ? avx512 : upToAvx2};
  }();
  return *table[std::size_t(std::clamp(int(level), 0, int(table.size()) - 1))];
}

}  // namespace csgvox

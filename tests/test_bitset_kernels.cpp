#include <gtest/gtest.h>

#include <bit>
#include <random>
#include <vector>

#include "voxel/bitset_kernels.h"

namespace csgvox {
namespace {

using Word = std::uint64_t;
constexpr Word kSentinel = 0xA5A5'5A5A'DEAD'BEEFull;

std::vector<Word> randomWords(std::size_t n, std::mt19937_64& rng) {
  std::vector<Word> w(n);
  for (Word& x : w) x = rng() & rng();  // about a quarter of the bits
  return w;
}

// Every kernel of `k` on n words starting `offset` words into buffers whose
// other words hold a sentinel, against plain loops; the sentinels must stay.
void checkKernels(const BitsetKernels& k, std::size_t n, std::size_t offset, std::mt19937_64& rng) {
  const std::vector<Word> x = randomWords(n, rng), y = randomWords(n, rng);
  std::vector<Word> bufA(n + offset + 9, kSentinel), bufB(n + offset + 9, kSentinel);
  std::copy(x.begin(), x.end(), bufA.begin() + std::ptrdiff_t(offset));
  std::copy(y.begin(), y.end(), bufB.begin() + std::ptrdiff_t(offset));
  Word* a = bufA.data() + offset;
  const Word* b = bufB.data() + offset;

  std::size_t both = 0, onlyA = 0, either = 0, inA = 0;
  for (std::size_t i = 0; i < n; ++i) {
    both += std::size_t(std::popcount(x[i] & y[i]));
    onlyA += std::size_t(std::popcount(x[i] & ~y[i]));
    either += std::size_t(std::popcount(x[i] | y[i]));
    inA += std::size_t(std::popcount(x[i]));
  }
  EXPECT_EQ(k.countAnd(a, b, n), both);
  EXPECT_EQ(k.countAndNot(a, b, n), onlyA);
  EXPECT_EQ(k.countOr(a, b, n), either);
  EXPECT_EQ(k.count(a, n), inA);
  EXPECT_EQ(k.intersects(a, b, n), both > 0);

  const auto expectInPlace = [&](void (*kernel)(Word*, const Word*, std::size_t), auto op,
                                 const char* name) {
    SCOPED_TRACE(name);
    std::copy(x.begin(), x.end(), a);
    kernel(a, b, n);
    for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(a[i], op(x[i], y[i])) << "word " << i;
    for (std::size_t i = 0; i < offset; ++i) ASSERT_EQ(bufA[i], kSentinel) << "before, word " << i;
    for (std::size_t i = offset + n; i < bufA.size(); ++i) {
      ASSERT_EQ(bufA[i], kSentinel) << "after, word " << i;
    }
  };
  expectInPlace(
      k.andInPlace, [](Word p, Word q) { return p & q; }, "and");
  expectInPlace(
      k.orInPlace, [](Word p, Word q) { return p | q; }, "or");
  expectInPlace(
      k.andNotInPlace, [](Word p, Word q) { return p & ~q; }, "and-not");
}

TEST(BitsetKernels, EveryLevelMatchesPlainLoopsAtAnyLengthAndAlignment) {
  std::mt19937_64 rng(5);
  for (SimdLevel level : supportedSimdLevels()) {
    const BitsetKernels& k = bitsetKernels(level);
    for (std::size_t n = 0; n <= 140; ++n) {
      for (std::size_t offset = 0; offset < 9; ++offset) {
        SCOPED_TRACE(testing::Message()
                     << simdLevelName(level) << ", " << n << " words at offset " << offset);
        checkKernels(k, n, offset, rng);
      }
    }
    for (std::size_t n : {1023u, 4096u, 4097u, 4096u + 31u}) {
      SCOPED_TRACE(testing::Message() << simdLevelName(level) << ", " << n << " words");
      checkKernels(k, n, 3, rng);
    }
  }
}

// All-ones words: each byte count is at its maximum, so a byte-wise sum that
// overflowed before being widened would show here.
TEST(BitsetKernels, FullWordsAreCountedExactly) {
  for (SimdLevel level : supportedSimdLevels()) {
    const BitsetKernels& k = bitsetKernels(level);
    for (std::size_t n : {1u, 4u, 123u, 124u, 125u, 4096u, 10000u}) {
      const std::vector<Word> ones(n, ~Word(0));
      SCOPED_TRACE(testing::Message() << simdLevelName(level) << ", " << n << " words");
      EXPECT_EQ(k.count(ones.data(), n), 64 * n);
      EXPECT_EQ(k.countAnd(ones.data(), ones.data(), n), 64 * n);
      EXPECT_EQ(k.countOr(ones.data(), ones.data(), n), 64 * n);
      EXPECT_EQ(k.countAndNot(ones.data(), ones.data(), n), 0u);
    }
  }
}

TEST(BitsetKernels, LevelsAreCappedToTheCpuAndTheBuild) {
  EXPECT_EQ(&bitsetKernels(SimdLevel::Portable), portableBitsetKernels());
  // Any request, even one naming no level, gets kernels the CPU can run.
  const BitsetKernels& top = bitsetKernels(detectedSimdLevel());
  EXPECT_EQ(&bitsetKernels(SimdLevel(7)), &top);
  EXPECT_EQ(&bitsetKernels(SimdLevel(-1)), portableBitsetKernels());
  if (detectedSimdLevel() == SimdLevel::Avx512 && avx512BitsetKernels() != nullptr) {
    EXPECT_EQ(&top, avx512BitsetKernels());
    EXPECT_NE(&bitsetKernels(SimdLevel::Avx2), &top);
  }
  const Word w[2] = {0xFF, 0x1};
  EXPECT_EQ(top.count(w, 2), 9u);
}

// Each vector file is compiled with its level's flags wherever the build
// gives them (x86-64 with GCC or Clang; cmake/csgvox_simd.cmake), in every
// module that has such files.
TEST(BitsetKernels, TheVectorKernelsAreBuiltWhereTheBuildGivesTheFlags) {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  if (detectedSimdLevel() >= SimdLevel::Avx2) {
    EXPECT_NE(avx2BitsetKernels(), nullptr);
  }
  if (detectedSimdLevel() >= SimdLevel::Avx512) {
    EXPECT_NE(avx512BitsetKernels(), nullptr);
  }
#else
  GTEST_SKIP() << "the build has no vector flags for this processor or compiler";
#endif
}

}  // namespace
}  // namespace csgvox

// The AVX2 bitset kernels: four words per vector, popcount by Mula's nibble
// lookup (VPSHUFB on each half byte, byte sums folded with VPSADBW), masked
// loads and stores for the last n % 4 words. This file is compiled with the
// AVX2 flags (cmake/csgvox_simd.cmake); as the header of core/cpu_features.h
// asks, it holds only intrinsics and plain loops with internal linkage, and
// nothing here runs before the run-time check.

#include "voxel/bitset_kernels.h"

#if defined(__AVX2__)

#include <immintrin.h>

namespace csgvox {
namespace {

using Word = std::uint64_t;

constexpr std::size_t kLanes = 4;  // words per vector
// Vectors whose byte counts (≤ 8 each) are summed in 8-bit lanes before they
// are widened: 31 × 8 = 248 ≤ 255.
constexpr std::size_t kVectorsPerFold = 31;

struct And {
  static __m256i apply(__m256i x, __m256i y) { return _mm256_and_si256(x, y); }
};
struct AndNot {
  static __m256i apply(__m256i x, __m256i y) { return _mm256_andnot_si256(y, x); }
};
struct Or {
  static __m256i apply(__m256i x, __m256i y) { return _mm256_or_si256(x, y); }
};
// count(a) as a two-operand kernel that ignores its second operand.
struct First {
  static __m256i apply(__m256i x, __m256i) { return x; }
};

__m256i load(const Word* p) { return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p)); }
void store(Word* p, __m256i v) { _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), v); }
// All ones in the first `n` < 4 lanes.
__m256i tailMask(std::size_t n) {
  return _mm256_cmpgt_epi64(_mm256_set1_epi64x(static_cast<long long>(n)),
                            _mm256_setr_epi64x(0, 1, 2, 3));
}
// The words at p under mask m, zeros elsewhere; reads no masked-out word.
__m256i loadTail(const Word* p, __m256i m) {
  return _mm256_maskload_epi64(reinterpret_cast<const long long*>(p), m);
}

// Popcount of each byte.
__m256i popcountBytes(__m256i v) {
  const __m256i lookup = _mm256_setr_epi8(0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4,  //
                                          0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4);
  const __m256i nibble = _mm256_set1_epi8(0x0f);
  const __m256i low = _mm256_and_si256(v, nibble);
  const __m256i high = _mm256_and_si256(_mm256_srli_epi16(v, 4), nibble);
  return _mm256_add_epi8(_mm256_shuffle_epi8(lookup, low), _mm256_shuffle_epi8(lookup, high));
}

// Byte counts widened to four 64-bit sums.
__m256i widen(__m256i bytes) { return _mm256_sad_epu8(bytes, _mm256_setzero_si256()); }

// Every operation maps two zero words to zero, so the zeros that loadTail
// puts after the last word add nothing to a count.
template <class Op>
std::size_t countOp(const Word* a, const Word* b, std::size_t n) {
  __m256i total = _mm256_setzero_si256();
  std::size_t i = 0;
  while (n - i >= kLanes) {
    const std::size_t left = (n - i) / kLanes;
    const std::size_t vectors = left < kVectorsPerFold ? left : kVectorsPerFold;
    __m256i bytes = _mm256_setzero_si256();
    for (std::size_t v = 0; v < vectors; ++v, i += kLanes) {
      bytes = _mm256_add_epi8(bytes, popcountBytes(Op::apply(load(a + i), load(b + i))));
    }
    total = _mm256_add_epi64(total, widen(bytes));
  }
  if (i < n) {
    const __m256i m = tailMask(n - i);
    total = _mm256_add_epi64(
        total, widen(popcountBytes(Op::apply(loadTail(a + i, m), loadTail(b + i, m)))));
  }
  const __m128i half =
      _mm_add_epi64(_mm256_castsi256_si128(total), _mm256_extracti128_si256(total, 1));
  return std::size_t(_mm_cvtsi128_si64(half)) + std::size_t(_mm_extract_epi64(half, 1));
}

std::size_t count(const Word* a, std::size_t n) { return countOp<First>(a, a, n); }

bool intersects(const Word* a, const Word* b, std::size_t n) {
  std::size_t i = 0;
  for (; i + 4 * kLanes <= n; i += 4 * kLanes) {
    const __m256i x = _mm256_or_si256(_mm256_and_si256(load(a + i), load(b + i)),
                                      _mm256_and_si256(load(a + i + 4), load(b + i + 4)));
    const __m256i y = _mm256_or_si256(_mm256_and_si256(load(a + i + 8), load(b + i + 8)),
                                      _mm256_and_si256(load(a + i + 12), load(b + i + 12)));
    const __m256i any = _mm256_or_si256(x, y);
    if (!_mm256_testz_si256(any, any)) return true;
  }
  for (; i + kLanes <= n; i += kLanes) {
    if (!_mm256_testz_si256(load(a + i), load(b + i))) return true;
  }
  if (i < n) {
    const __m256i m = tailMask(n - i);
    return !_mm256_testz_si256(loadTail(a + i, m), loadTail(b + i, m));
  }
  return false;
}

template <class Op>
void applyOp(Word* a, const Word* b, std::size_t n) {
  std::size_t i = 0;
  for (; i + 4 * kLanes <= n; i += 4 * kLanes) {
    const __m256i r0 = Op::apply(load(a + i), load(b + i));
    const __m256i r1 = Op::apply(load(a + i + 4), load(b + i + 4));
    const __m256i r2 = Op::apply(load(a + i + 8), load(b + i + 8));
    const __m256i r3 = Op::apply(load(a + i + 12), load(b + i + 12));
    store(a + i, r0);
    store(a + i + 4, r1);
    store(a + i + 8, r2);
    store(a + i + 12, r3);
  }
  for (; i + kLanes <= n; i += kLanes) store(a + i, Op::apply(load(a + i), load(b + i)));
  if (i < n) {
    const __m256i m = tailMask(n - i);
    _mm256_maskstore_epi64(reinterpret_cast<long long*>(a + i), m,
                           Op::apply(loadTail(a + i, m), loadTail(b + i, m)));
  }
}

constinit const BitsetKernels kAvx2{countOp<And>, countOp<AndNot>, countOp<Or>, count,
                                    intersects,   applyOp<And>,    applyOp<Or>, applyOp<AndNot>};

}  // namespace

const BitsetKernels* avx2BitsetKernels() { return &kAvx2; }

}  // namespace csgvox

#else

const csgvox::BitsetKernels* csgvox::avx2BitsetKernels() { return nullptr; }

#endif

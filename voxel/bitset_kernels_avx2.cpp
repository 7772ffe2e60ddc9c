// The AVX2 bitset kernels: four words per vector, popcount by Mula's nibble
// lookup (VPSHUFB on each half byte, byte counts widened with VPSADBW), masked
// loads and stores for the last n % 4 words. This file is compiled with the
// AVX2 flags (cmake/csgvox_simd.cmake); as the header of core/cpu_features.h
// asks, it holds only intrinsics and loops with internal linkage, and nothing
// here runs before the run-time check.

#include "voxel/bitset_kernels.h"

#if defined(__AVX2__)

#include <immintrin.h>

#include "voxel/bitset_kernel_loops.h"

namespace csgvox {
namespace {

using Word = std::uint64_t;

// The primitives of bitset_kernel_loops.h for AVX2.
struct Avx2 {
  using Vec = __m256i;
  using Mask = __m256i;    // all ones in the lanes to load or store
  using Counts = __m256i;  // 32 byte counts
  using Sum = __m256i;     // four 64-bit counts
  static constexpr std::size_t kLanes = 4;
  // A byte count grows by at most 8 per vector: 31 × 8 = 248 ≤ 255.
  static constexpr std::size_t kStepsPerFold = 31;

  static Vec load(const Word* p) { return _mm256_loadu_si256(reinterpret_cast<const Vec*>(p)); }
  static void store(Word* p, Vec v) { _mm256_storeu_si256(reinterpret_cast<Vec*>(p), v); }
  static Mask tailMask(std::size_t n) {
    return _mm256_cmpgt_epi64(_mm256_set1_epi64x(static_cast<long long>(n)),
                              _mm256_setr_epi64x(0, 1, 2, 3));
  }
  static Vec loadTail(const Word* p, Mask m) {
    return _mm256_maskload_epi64(reinterpret_cast<const long long*>(p), m);
  }
  static void storeTail(Word* p, Mask m, Vec v) {
    _mm256_maskstore_epi64(reinterpret_cast<long long*>(p), m, v);
  }
  static Vec bitAnd(Vec x, Vec y) { return _mm256_and_si256(x, y); }
  static Vec bitAndNot(Vec x, Vec y) { return _mm256_andnot_si256(y, x); }
  static Vec bitOr(Vec x, Vec y) { return _mm256_or_si256(x, y); }
  static bool any(Vec v) { return !_mm256_testz_si256(v, v); }
  static Word extractBits(Word x, Word m) { return _pext_u64(x, m); }
  static std::size_t bitCount(Word m) { return std::size_t(_mm_popcnt_u64(m)); }
  static Counts zeroCounts() { return _mm256_setzero_si256(); }
  static Counts countBits(Counts c, Vec v) {
    const Vec lookup = _mm256_setr_epi8(0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4,  //
                                        0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4);
    const Vec nibble = _mm256_set1_epi8(0x0f);
    const Vec low = _mm256_and_si256(v, nibble);
    const Vec high = _mm256_and_si256(_mm256_srli_epi16(v, 4), nibble);
    const Vec bytes =
        _mm256_add_epi8(_mm256_shuffle_epi8(lookup, low), _mm256_shuffle_epi8(lookup, high));
    return _mm256_add_epi8(c, bytes);
  }
  static Sum zeroSum() { return _mm256_setzero_si256(); }
  static Sum widen(Sum s, Counts c) {
    return _mm256_add_epi64(s, _mm256_sad_epu8(c, _mm256_setzero_si256()));
  }
  static std::size_t total(Sum s) {
    const __m128i half = _mm_add_epi64(_mm256_castsi256_si128(s), _mm256_extracti128_si256(s, 1));
    return std::size_t(_mm_cvtsi128_si64(half)) + std::size_t(_mm_extract_epi64(half, 1));
  }
};

constinit const BitsetKernels kAvx2 = bitset_loops::bitsetKernelsOf<Avx2>();

}  // namespace

const BitsetKernels* avx2BitsetKernels() { return &kAvx2; }

}  // namespace csgvox

#else

const csgvox::BitsetKernels* csgvox::avx2BitsetKernels() { return nullptr; }

#endif

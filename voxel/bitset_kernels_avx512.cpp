// The AVX-512 bitset kernels: eight words per vector, VPOPCNTDQ for the
// counts, masked loads and stores for the last n % 8 words. This file is
// compiled with the AVX-512 flags (cmake/csgvox_simd.cmake); as the header of
// core/cpu_features.h asks, it holds only intrinsics and loops with internal
// linkage, and nothing here runs before the run-time check.

#include "voxel/bitset_kernels.h"

#if defined(__AVX512F__) && defined(__AVX512VPOPCNTDQ__)

#include <immintrin.h>

#include "voxel/bitset_kernel_loops.h"

namespace csgvox {
namespace {

using Word = std::uint64_t;

// The primitives of bitset_kernel_loops.h for AVX-512. The bit operations are
// GCC/Clang vector operators (VPANDQ, VPANDNQ, VPORQ): GCC 12's
// _mm512_andnot_si512 trips -Wmaybe-uninitialized in its own header.
struct Avx512 {
  using Vec = __m512i;
  using Mask = __mmask8;
  using Counts = __m512i;  // eight 64-bit counts
  using Sum = __m512i;
  static constexpr std::size_t kLanes = 8;
  static constexpr std::size_t kStepsPerFold = ~std::size_t(0);

  static Vec load(const Word* p) { return _mm512_loadu_si512(p); }
  static void store(Word* p, Vec v) { _mm512_storeu_si512(p, v); }
  static Mask tailMask(std::size_t n) { return Mask((1u << n) - 1u); }
  static Vec loadTail(const Word* p, Mask m) { return _mm512_maskz_loadu_epi64(m, p); }
  static void storeTail(Word* p, Mask m, Vec v) { _mm512_mask_storeu_epi64(p, m, v); }
  static Vec bitAnd(Vec x, Vec y) { return x & y; }
  static Vec bitAndNot(Vec x, Vec y) { return x & ~y; }
  static Vec bitOr(Vec x, Vec y) { return x | y; }
  static bool any(Vec v) { return _mm512_test_epi64_mask(v, v) != 0; }
  static Word extractBits(Word x, Word m) { return _pext_u64(x, m); }
  static std::size_t bitCount(Word m) { return std::size_t(_mm_popcnt_u64(m)); }
  static Counts zeroCounts() { return _mm512_setzero_si512(); }
  static Counts countBits(Counts c, Vec v) { return _mm512_add_epi64(c, _mm512_popcnt_epi64(v)); }
  static Sum zeroSum() { return _mm512_setzero_si512(); }
  static Sum widen(Sum s, Counts c) { return _mm512_add_epi64(s, c); }
  // A plain sum of the lanes (_mm512_reduce_add_epi64 trips GCC 12's
  // -Wuninitialized inside its own header).
  static std::size_t total(Sum s) {
    alignas(64) Word lanes[kLanes];
    _mm512_store_si512(lanes, s);
    Word sum = 0;
    for (Word lane : lanes) sum += lane;
    return std::size_t(sum);
  }
};

constinit const BitsetKernels kAvx512 = bitset_loops::bitsetKernelsOf<Avx512>();

}  // namespace

const BitsetKernels* avx512BitsetKernels() { return &kAvx512; }

}  // namespace csgvox

#else

const csgvox::BitsetKernels* csgvox::avx512BitsetKernels() { return nullptr; }

#endif

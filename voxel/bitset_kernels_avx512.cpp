// The AVX-512 bitset kernels: eight words per vector, VPOPCNTDQ for the
// counts, masked loads and stores for the last n % 8 words. This file is
// compiled with the AVX-512 flags (cmake/csgvox_simd.cmake); as the header of
// core/cpu_features.h asks, it holds only intrinsics and plain loops with
// internal linkage, and nothing here runs before the run-time check.

#include "voxel/bitset_kernels.h"

#if defined(__AVX512F__) && defined(__AVX512VPOPCNTDQ__)

#include <immintrin.h>

namespace csgvox {
namespace {

using Word = std::uint64_t;

constexpr std::size_t kLanes = 8;           // words per vector
constexpr std::size_t kBlock = 4 * kLanes;  // words per unrolled step

// The operations as GCC/Clang vector operators (VPANDQ, VPANDNQ, VPORQ):
// GCC 12's _mm512_andnot_si512 trips -Wmaybe-uninitialized in its header.
struct And {
  static __m512i apply(__m512i x, __m512i y) { return x & y; }
};
struct AndNot {
  static __m512i apply(__m512i x, __m512i y) { return x & ~y; }
};
struct Or {
  static __m512i apply(__m512i x, __m512i y) { return x | y; }
};
// count(a) as a two-operand kernel that ignores its second operand.
struct First {
  static __m512i apply(__m512i x, __m512i) { return x; }
};

__m512i load(const Word* p) { return _mm512_loadu_si512(p); }
// The first `n` < 8 words at p, zeros after them; reads nothing past p + n.
__mmask8 tailMask(std::size_t n) { return __mmask8((1u << n) - 1u); }
__m512i loadTail(const Word* p, __mmask8 m) { return _mm512_maskz_loadu_epi64(m, p); }

// Every operation maps two zero words to zero, so the zeros that loadTail
// puts after the last word add nothing to a count.
template <class Op>
std::size_t countOp(const Word* a, const Word* b, std::size_t n) {
  __m512i s0 = _mm512_setzero_si512(), s1 = s0, s2 = s0, s3 = s0;
  std::size_t i = 0;
  for (; i + kBlock <= n; i += kBlock) {
    s0 = _mm512_add_epi64(s0, _mm512_popcnt_epi64(Op::apply(load(a + i), load(b + i))));
    s1 = _mm512_add_epi64(s1, _mm512_popcnt_epi64(Op::apply(load(a + i + 8), load(b + i + 8))));
    s2 = _mm512_add_epi64(s2, _mm512_popcnt_epi64(Op::apply(load(a + i + 16), load(b + i + 16))));
    s3 = _mm512_add_epi64(s3, _mm512_popcnt_epi64(Op::apply(load(a + i + 24), load(b + i + 24))));
  }
  for (; i + kLanes <= n; i += kLanes) {
    s0 = _mm512_add_epi64(s0, _mm512_popcnt_epi64(Op::apply(load(a + i), load(b + i))));
  }
  if (i < n) {
    const __mmask8 m = tailMask(n - i);
    s1 = _mm512_add_epi64(s1,
                          _mm512_popcnt_epi64(Op::apply(loadTail(a + i, m), loadTail(b + i, m))));
  }
  // A plain sum of the lanes (_mm512_reduce_add_epi64 trips GCC 12's
  // -Wuninitialized inside its own header).
  alignas(64) Word lanes[kLanes];
  _mm512_store_si512(lanes, _mm512_add_epi64(_mm512_add_epi64(s0, s1), _mm512_add_epi64(s2, s3)));
  Word sum = 0;
  for (Word lane : lanes) sum += lane;
  return std::size_t(sum);
}

std::size_t count(const Word* a, std::size_t n) { return countOp<First>(a, a, n); }

bool intersects(const Word* a, const Word* b, std::size_t n) {
  std::size_t i = 0;
  for (; i + kBlock <= n; i += kBlock) {
    const __m512i x = _mm512_or_si512(_mm512_and_si512(load(a + i), load(b + i)),
                                      _mm512_and_si512(load(a + i + 8), load(b + i + 8)));
    const __m512i y = _mm512_or_si512(_mm512_and_si512(load(a + i + 16), load(b + i + 16)),
                                      _mm512_and_si512(load(a + i + 24), load(b + i + 24)));
    const __m512i any = _mm512_or_si512(x, y);
    if (_mm512_test_epi64_mask(any, any) != 0) return true;
  }
  for (; i + kLanes <= n; i += kLanes) {
    if (_mm512_test_epi64_mask(load(a + i), load(b + i)) != 0) return true;
  }
  if (i < n) {
    const __mmask8 m = tailMask(n - i);
    return _mm512_test_epi64_mask(loadTail(a + i, m), loadTail(b + i, m)) != 0;
  }
  return false;
}

template <class Op>
void applyOp(Word* a, const Word* b, std::size_t n) {
  std::size_t i = 0;
  for (; i + kBlock <= n; i += kBlock) {
    const __m512i r0 = Op::apply(load(a + i), load(b + i));
    const __m512i r1 = Op::apply(load(a + i + 8), load(b + i + 8));
    const __m512i r2 = Op::apply(load(a + i + 16), load(b + i + 16));
    const __m512i r3 = Op::apply(load(a + i + 24), load(b + i + 24));
    _mm512_storeu_si512(a + i, r0);
    _mm512_storeu_si512(a + i + 8, r1);
    _mm512_storeu_si512(a + i + 16, r2);
    _mm512_storeu_si512(a + i + 24, r3);
  }
  for (; i + kLanes <= n; i += kLanes)
    _mm512_storeu_si512(a + i, Op::apply(load(a + i), load(b + i)));
  if (i < n) {
    const __mmask8 m = tailMask(n - i);
    _mm512_mask_storeu_epi64(a + i, m, Op::apply(loadTail(a + i, m), loadTail(b + i, m)));
  }
}

constinit const BitsetKernels kAvx512{countOp<And>, countOp<AndNot>, countOp<Or>, count,
                                      intersects,   applyOp<And>,    applyOp<Or>, applyOp<AndNot>};

}  // namespace

const BitsetKernels* avx512BitsetKernels() { return &kAvx512; }

}  // namespace csgvox

#else

const csgvox::BitsetKernels* csgvox::avx512BitsetKernels() { return nullptr; }

#endif

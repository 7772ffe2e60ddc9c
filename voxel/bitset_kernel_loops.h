#pragma once
/// The loops of the bitset kernels, written once over the vector primitives
/// of an instruction set. Each bitset_kernels*.cpp defines its primitives as a
/// struct `V` in an anonymous namespace and builds its table with
/// `bitsetKernelsOf<V>()`; since V has internal linkage, so has every
/// instantiation, which therefore stays in that file and is compiled for that
/// file's instruction set only.
///
/// V provides, for 64-bit words (`Word`):
///  - `Vec` and `kLanes`: a vector of kLanes words (a Word itself, 1 lane, for
///    the portable loops);
///  - `load(p)`, `store(p, v)`: kLanes words at p, any alignment;
///  - for kLanes > 1, `Mask tailMask(n)` for the first n < kLanes lanes, and
///    `loadTail(p, m)` (zeros outside m; reads no word outside m) and
///    `storeTail(p, m, v)` (writes no word outside m);
///  - `bitAnd(x, y)`, `bitAndNot(x, y)` = x & ~y, `bitOr(x, y)`, and
///    `any(v)`: some bit of v is set;
///  - for one word: `Word extractBits(Word x, Word m)`, the bits of x at the
///    set bits of m packed at the bottom (BMI2's PEXT), and
///    `std::size_t bitCount(Word m)`;
///  - counting: `Counts zeroCounts()`, `Counts countBits(Counts c, Vec v)`
///    (c plus the set bits of v in narrow lanes), `Sum zeroSum()`,
///    `Sum widen(Sum s, Counts c)`, `std::size_t total(Sum s)`, and
///    `kStepsPerFold`: how many countBits() of one vector each a Counts holds
///    before it must be widened.

#include <cstddef>
#include <cstdint>

#include "voxel/bitset_kernels.h"

namespace csgvox::bitset_loops {

using Word = std::uint64_t;

/// The word operation of a kernel; First is `x` alone (a one-set count).
enum class BitOp { And, AndNot, Or, First };

template <class V, BitOp kOp>
typename V::Vec combine(typename V::Vec x, typename V::Vec y) {
  if constexpr (kOp == BitOp::And) {
    return V::bitAnd(x, y);
  } else if constexpr (kOp == BitOp::AndNot) {
    return V::bitAndNot(x, y);
  } else if constexpr (kOp == BitOp::Or) {
    return V::bitOr(x, y);
  } else {
    return x;
  }
}

// op(a[i..], b[i..]) for one vector; First reads no b.
template <class V, BitOp kOp>
typename V::Vec loadCombined(const Word* a, const Word* b) {
  if constexpr (kOp == BitOp::First) {
    return V::load(a);
  } else {
    return combine<V, kOp>(V::load(a), V::load(b));
  }
}

// Every operation maps two zero words to zero, so the zeros that loadTail()
// puts after the last word add nothing to a count or a test.
template <class V, BitOp kOp, class Mask>
typename V::Vec loadCombinedTail(const Word* a, const Word* b, Mask m) {
  if constexpr (kOp == BitOp::First) {
    return V::loadTail(a, m);
  } else {
    return combine<V, kOp>(V::loadTail(a, m), V::loadTail(b, m));
  }
}

/// Σ popcount(op(a[i], b[i])) over n words.
template <class V, BitOp kOp>
std::size_t countOp(const Word* a, const Word* b, std::size_t n) {
  constexpr std::size_t kBlock = 4 * V::kLanes;
  typename V::Sum sum = V::zeroSum();
  std::size_t i = 0;
  while (n - i >= kBlock) {
    // Four independent counts, widened before their narrow lanes can overflow.
    typename V::Counts c0 = V::zeroCounts(), c1 = c0, c2 = c0, c3 = c0;
    for (std::size_t step = 0; step < V::kStepsPerFold && n - i >= kBlock; ++step, i += kBlock) {
      c0 = V::countBits(c0, loadCombined<V, kOp>(a + i, b + i));
      c1 = V::countBits(c1, loadCombined<V, kOp>(a + i + V::kLanes, b + i + V::kLanes));
      c2 = V::countBits(c2, loadCombined<V, kOp>(a + i + 2 * V::kLanes, b + i + 2 * V::kLanes));
      c3 = V::countBits(c3, loadCombined<V, kOp>(a + i + 3 * V::kLanes, b + i + 3 * V::kLanes));
    }
    sum = V::widen(V::widen(V::widen(V::widen(sum, c0), c1), c2), c3);
  }
  for (; n - i >= V::kLanes; i += V::kLanes) {
    sum = V::widen(sum, V::countBits(V::zeroCounts(), loadCombined<V, kOp>(a + i, b + i)));
  }
  if constexpr (V::kLanes > 1) {
    if (i < n) {
      const auto m = V::tailMask(n - i);
      sum = V::widen(sum, V::countBits(V::zeroCounts(), loadCombinedTail<V, kOp>(a + i, b + i, m)));
    }
  }
  return V::total(sum);
}

template <class V>
std::size_t countOne(const Word* a, std::size_t n) {
  return countOp<V, BitOp::First>(a, a, n);
}

/// True when some a[i] & b[i] is not zero; looks at four vectors at a time.
template <class V>
bool intersects(const Word* a, const Word* b, std::size_t n) {
  constexpr std::size_t kBlock = 4 * V::kLanes;
  constexpr BitOp kAnd = BitOp::And;
  std::size_t i = 0;
  for (; n - i >= kBlock; i += kBlock) {
    const auto x = V::bitOr(loadCombined<V, kAnd>(a + i, b + i),
                            loadCombined<V, kAnd>(a + i + V::kLanes, b + i + V::kLanes));
    const auto y = V::bitOr(loadCombined<V, kAnd>(a + i + 2 * V::kLanes, b + i + 2 * V::kLanes),
                            loadCombined<V, kAnd>(a + i + 3 * V::kLanes, b + i + 3 * V::kLanes));
    if (V::any(V::bitOr(x, y))) return true;
  }
  for (; n - i >= V::kLanes; i += V::kLanes) {
    if (V::any(loadCombined<V, kAnd>(a + i, b + i))) return true;
  }
  if constexpr (V::kLanes > 1) {
    if (i < n) return V::any(loadCombinedTail<V, kAnd>(a + i, b + i, V::tailMask(n - i)));
  }
  return false;
}

/// a[i] = op(a[i], b[i]); a == b is allowed.
template <class V, BitOp kOp>
void applyOp(Word* a, const Word* b, std::size_t n) {
  constexpr std::size_t kBlock = 4 * V::kLanes;
  std::size_t i = 0;
  for (; n - i >= kBlock; i += kBlock) {
    // All four loads before the stores, so that a == b needs no care.
    const auto r0 = loadCombined<V, kOp>(a + i, b + i);
    const auto r1 = loadCombined<V, kOp>(a + i + V::kLanes, b + i + V::kLanes);
    const auto r2 = loadCombined<V, kOp>(a + i + 2 * V::kLanes, b + i + 2 * V::kLanes);
    const auto r3 = loadCombined<V, kOp>(a + i + 3 * V::kLanes, b + i + 3 * V::kLanes);
    V::store(a + i, r0);
    V::store(a + i + V::kLanes, r1);
    V::store(a + i + 2 * V::kLanes, r2);
    V::store(a + i + 3 * V::kLanes, r3);
  }
  for (; n - i >= V::kLanes; i += V::kLanes) V::store(a + i, loadCombined<V, kOp>(a + i, b + i));
  if constexpr (V::kLanes > 1) {
    if (i < n) {
      const auto m = V::tailMask(n - i);
      V::storeTail(a + i, m, loadCombinedTail<V, kOp>(a + i, b + i, m));
    }
  }
}

/// Packs the bits of a that mask selects into out (zeroed, as many bits as
/// mask has set), word by word.
template <class V>
void compress(const Word* a, const Word* mask, std::size_t n, Word* out) {
  std::size_t at = 0;  // bits written so far
  for (std::size_t i = 0; i < n; ++i) {
    const Word m = mask[i];
    if (m == 0) continue;
    const Word bits = V::extractBits(a[i], m);
    const std::size_t k = V::bitCount(m);
    const std::size_t shift = at & 63;
    out[at >> 6] |= bits << shift;
    if (shift != 0 && shift + k > 64) out[(at >> 6) + 1] |= bits >> (64 - shift);
    at += k;
  }
}

/// The kernel table of the primitives V.
template <class V>
constexpr BitsetKernels bitsetKernelsOf() {
  return {countOp<V, BitOp::And>,
          countOp<V, BitOp::AndNot>,
          countOp<V, BitOp::Or>,
          countOne<V>,
          intersects<V>,
          applyOp<V, BitOp::And>,
          applyOp<V, BitOp::Or>,
          applyOp<V, BitOp::AndNot>,
          compress<V>};
}

}  // namespace csgvox::bitset_loops

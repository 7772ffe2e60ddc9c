#pragma once
/// The word-wise kernels behind VoxelSet, one implementation per
/// instruction-set level of core/cpu_features.h: the portable one
/// (bitset_kernels.cpp), AVX2 (bitset_kernels_avx2.cpp, Mula's nibble-lookup
/// popcount) and AVX-512 (bitset_kernels_avx512.cpp, VPOPCNTDQ). All give the
/// same results bit for bit for any word count, including counts that are not
/// a multiple of the vector width, and any alignment of the arrays.

#include <cstddef>
#include <cstdint>

#include "core/cpu_features.h"

namespace csgvox {

/// One level's kernels over `n` 64-bit words. The in-place kernels allow
/// `a == b` (the same array); otherwise the arrays must not overlap.
struct BitsetKernels {
  /// Σ popcount(a[i] & b[i]).
  std::size_t (*countAnd)(const std::uint64_t* a, const std::uint64_t* b, std::size_t n);
  /// Σ popcount(a[i] & ~b[i]).
  std::size_t (*countAndNot)(const std::uint64_t* a, const std::uint64_t* b, std::size_t n);
  /// Σ popcount(a[i] | b[i]).
  std::size_t (*countOr)(const std::uint64_t* a, const std::uint64_t* b, std::size_t n);
  /// Σ popcount(a[i]).
  std::size_t (*count)(const std::uint64_t* a, std::size_t n);
  /// True when some a[i] & b[i] is not zero.
  bool (*intersects)(const std::uint64_t* a, const std::uint64_t* b, std::size_t n);
  /// a[i] &= b[i].
  void (*andInPlace)(std::uint64_t* a, const std::uint64_t* b, std::size_t n);
  /// a[i] |= b[i].
  void (*orInPlace)(std::uint64_t* a, const std::uint64_t* b, std::size_t n);
  /// a[i] &= ~b[i].
  void (*andNotInPlace)(std::uint64_t* a, const std::uint64_t* b, std::size_t n);
  /// Packs the bits of `a` that `mask` selects: bit k of `out` is the bit of
  /// `a` at the k-th set bit of `mask` (word 0 first). `out` must hold as many
  /// bits as `mask` has set and start zeroed.
  void (*compress)(const std::uint64_t* a, const std::uint64_t* mask, std::size_t n,
                   std::uint64_t* out);
};

/// The portable kernels (plain loops; always available).
const BitsetKernels* portableBitsetKernels();
/// The AVX2 kernels, or nullptr when the build has none (not x86-64). Only to
/// be called on a CPU with detectedSimdLevel() ≥ Avx2.
const BitsetKernels* avx2BitsetKernels();
/// The AVX-512 kernels, or nullptr when the build has none. Only to be called
/// on a CPU with detectedSimdLevel() ≥ Avx512.
const BitsetKernels* avx512BitsetKernels();

/// The kernels of `level`, capped to detectedSimdLevel() and to the levels
/// the build has, so any level is safe to ask for.
const BitsetKernels& bitsetKernels(SimdLevel level);

/// bitsetKernels(simdLevel()): the kernels VoxelSet uses, chosen per call.
const BitsetKernels& activeBitsetKernels();

}  // namespace csgvox

#pragma once
/// The SARDF fitness kernel over one chunk of points (core/sardf.h), compiled
/// once per instruction-set level like the min/max kernel
/// (evolve/minmax_chunk.h) and chosen at run time.
///
/// SARDF equals min/max, value and gradient, wherever the two operands have
/// opposite signs, differ by R or more, or one is at least twice the other
/// (core/sardf.h): most points of most operations. The kernel runs a fused
/// program like the min/max kernel (values and the id of the leaf whose
/// ±field a point's value is), and flags, in the same vector loop, the points
/// of each operation that may lie in the blend band (a superset: a test on
/// floats with R rounded up). Only those go to the step `blend`, which
/// computes core/sardf.h's value and derivatives in double and blends the
/// operands' gradients (id −1: kept in the gradient stack). At the end the
/// points with id ≥ 0 look their terms up as min/max does, and `terms`
/// computes those of the blended ones. The value, gradient and terms of every
/// point are those of the point-by-point SARDF field, bit for bit; the sums
/// are the same on every level (same operations, fixed order).
///
/// Plain data only, as for minmax_chunk.h: the level files call no library
/// template or inline function; the two steps are passed in as pointers to
/// functions compiled portably.

#include <cstddef>
#include <cstdint>

#include "evolve/minmax_chunk.h"

namespace csgvox::fitness_detail {

/// One combination the blend step finishes: a = op(a, b) at the flagged
/// points of the chunk, where the vector loop left a as it was.
struct SardfBlendStep {
  float* va = nullptr;               ///< a's values
  std::int32_t* ia = nullptr;        ///< a's ids (−1: blended)
  float* ga = nullptr;               ///< a's gradients, [3][kChunk], at ids −1
  const float* vb = nullptr;         ///< b's values (null: b is the leaf leafCode)
  const std::int32_t* ib = nullptr;  ///< b's ids (null: b is the leaf leafCode)
  const float* gb = nullptr;         ///< b's gradients (null: b is the leaf leafCode)
  std::int32_t leafCode = 0;         ///< 2·leaf (+1: negated) when b is a leaf
  bool intersect = false;            ///< Min (SARDF intersection), else Max (union)
  const std::int32_t* flags = nullptr;  ///< nonzero at the points to finish
};

struct SardfChunk;

/// Finishes `step` over the chunk [start, start + m).
using SardfBlendFn = void (*)(const SardfChunk& k, const SardfBlendStep& step, std::size_t start,
                              std::size_t m);

/// Writes the distance and normal terms of the points of the chunk
/// [start, start + m) whose id in `ids` is −1 into out[i] and out[kChunk + i]
/// from their values and gradients (`gradients`: [3][kChunk]).
using SardfTermsFn = void (*)(const SardfChunk& k, const float* values, const std::int32_t* ids,
                              const float* gradients, std::size_t start, std::size_t m,
                              double* out);

/// One chunk's work: a fused program (fused()), the cached arrays and the
/// scratch of stackDepth entries.
struct SardfChunk {
  const Instr* code = nullptr;
  std::size_t codeSize = 0;
  const float* values = nullptr;        ///< [p][n]
  const float* distanceTerm = nullptr;  ///< [p][n]
  const float* normalTerm = nullptr;    ///< [2p][n]
  std::size_t n = 0;
  float band = 0.0f;  ///< R rounded up to a float: operands closer than this may blend
  float* stackValues = nullptr;        ///< [depth][kChunk]
  std::int32_t* stackIds = nullptr;    ///< [depth][kChunk]
  float* stackGradients = nullptr;     ///< [depth][3][kChunk]
  std::uint8_t* stackBlended = nullptr;  ///< [depth]: some id of the entry may be −1
  std::int32_t* flags = nullptr;       ///< [kChunk]
  double* blendedTerms = nullptr;      ///< [2][kChunk]
  SardfBlendFn blend = nullptr;
  SardfTermsFn terms = nullptr;
  const void* context = nullptr;  ///< for blend and terms: the point tables
};

/// Adds the chunk [start, start + m) (m <= kChunk) of Σ exp(−di²) and
/// Σ exp(−θi²) to sums[0] and sums[1].
using SardfChunkKernel = void (*)(const SardfChunk& k, std::size_t start, std::size_t m,
                                  double* sums);

/// The kernel of each level, as for the min/max kernel (evolve/minmax_chunk.h).
SardfChunkKernel portableSardfChunk();
SardfChunkKernel avx2SardfChunk();
SardfChunkKernel avx512SardfChunk();

}  // namespace csgvox::fitness_detail

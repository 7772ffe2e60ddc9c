#pragma once
/// The SARDF fitness kernel over one chunk of points (core/sardf.h), compiled
/// once per instruction-set level like the min/max kernel
/// (evolve/minmax_chunk.h) and chosen at run time.
///
/// It runs a fused program like the min/max kernel, over the same chunks:
/// every operation is first a vector loop that takes the min/max result
/// (value and the id of the leaf whose ±field it is) where the operands lie
/// outside SARDF's blend band — opposite signs, a difference of R or more,
/// or one twice the other: there SARDF is min/max exactly — and flags the
/// other points (a superset of those that blend, tested on floats with R
/// rounded up). The flagged points are packed together and core/sardf.h's
/// arcs, their derivatives and the blended gradients computed over them in
/// one vector loop, in float (id −1; their gradients kept in the stack,
/// the others are the leaves' cached ones). At the end the points with an id
/// look their terms up as min/max does; those of the blended points are
/// computed in float (exp and acos as polynomials), again packed. Values,
/// gradients and terms agree with the point-by-point SARDF in double to float
/// rounding; the sums are the same, bit for bit, on every level (the same
/// float operations in the same order, sums in a fixed order).
///
/// Plain data only, as for minmax_chunk.h.

#include <cstddef>
#include <cstdint>

#include "evolve/minmax_chunk.h"

namespace csgvox::fitness_detail {

/// One chunk's work: a fused program (fused()), the cached arrays and the
/// scratch of stackDepth entries.
struct SardfChunk {
  const Instr* code = nullptr;
  std::size_t codeSize = 0;
  const float* values = nullptr;                                     ///< [p][n]
  const float *gradX = nullptr, *gradY = nullptr, *gradZ = nullptr;  ///< [p][n]
  const float *normX = nullptr, *normY = nullptr, *normZ = nullptr;  ///< [n] scan normals
  const float* distanceTerm = nullptr;                               ///< [p][n]
  const float* normalTerm = nullptr;                                 ///< [2p][n]
  std::size_t n = 0;
  double exactRadius = 0.0;              ///< R, scan units: decides which of SARDF's cases applies
  float radius = 0.0f;                   ///< R as a float: the arcs
  float band = 0.0f;                     ///< R rounded up to a float: closer operands may blend
  float invEpsilon = 0.0f;               ///< 1 / εd, per scan unit
  float invAlpha = 0.0f;                 ///< 1 / α, per radian
  float* stackValues = nullptr;          ///< [depth][kChunk]
  std::int32_t* stackIds = nullptr;      ///< [depth][kChunk]; −1 where blended
  float* stackGradients = nullptr;       ///< [depth][3][kChunk], at the ids −1
  std::uint8_t* stackBlended = nullptr;  ///< [depth]: some id of the entry is −1
  std::int32_t* flags = nullptr;         ///< [kChunk]
  float* dense = nullptr;                ///< [10][kChunk]: packed flagged points
  std::int32_t* denseIds = nullptr;      ///< [3][kChunk]
  float* blendedTerms = nullptr;         ///< [2][kChunk]
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

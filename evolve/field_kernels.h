#pragma once
/// The inner loops of the fitness (evolve/fitness.h): a tree compiled to a
/// postfix program over the library's primitives, run over chunks of points
/// against the cached per-primitive arrays, and over the voxel bitsets.
/// Internal to the evolve module.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "core/cpu_features.h"
#include "core/csg_tree.h"
#include "core/set_operations.h"
#include "evolve/minmax_chunk.h"
#include "evolve/primitive_library.h"
#include "evolve/sardf_chunk.h"

namespace csgvox::fitness_detail {

/// A compiled tree.
struct Program {
  std::vector<Instr> code;
  std::size_t stackDepth = 1;  ///< most values held at once
};

/// Compiles a tree over `library` (union = max, intersection = min,
/// difference = min with negated operands, complement = negation).
/// @throw std::invalid_argument for an empty tree or a leaf not in the library.
Program compile(const CsgTree& tree, const PrimitiveLibrary& library);

/// `program` with each leaf that a Min or Max takes at once fused into it
/// (MinLeaf, MaxLeaf and their Neg forms): what min/max and the voxel term run.
Program fused(const Program& program);

/// The cached arrays a program runs over ([primitive][point] layouts).
struct PointTables {
  std::size_t n = 0;
  const float* values = nullptr;
  const float *gradX = nullptr, *gradY = nullptr, *gradZ = nullptr;  ///< smooth operations
  const float *normX = nullptr, *normY = nullptr, *normZ = nullptr;  ///< smooth operations
  const float* distanceTerm = nullptr;                               ///< [p][n]
  const float* normalTerm = nullptr;                                 ///< [2p][n]
  double epsilon = 0.0;                                              ///< εd, scan units
  double alpha = 0.0;                                                ///< α, radians
  double radius = 0.0;                                               ///< SARDF radius, scan units
};

/// Σ exp(−di²) and Σ exp(−θi²) over the points.
struct TermSums {
  double distance = 0.0;
  double normal = 0.0;
};

/// The min/max chunk kernel of `level`, or of the highest level below it
/// that the CPU and the build have.
MinMaxChunkKernel minMaxKernel(SimdLevel level);

/// The point terms of each fused program (fused()) with min/max: every
/// chunk of points is read once for all the programs (the cached arrays of a
/// large library do not fit in the cache; one chunk's do); each program's
/// sums are the same, bit for bit, as when run alone and whatever the number
/// of threads.
std::vector<TermSums> minMaxTerms(std::span<const Program> programs, const PointTables& tables);

/// The point terms of each (unfused) program with R-functions or SARDF,
/// every operation blended point by point (the fitness runs sardfTerms()
/// for SARDF; this is its reference).
/// @throw std::invalid_argument for min/max.
std::vector<TermSums> smoothTerms(std::span<const Program> programs, const PointTables& tables,
                                  SetOperationKind ops);

/// The SARDF chunk kernel of `level`, or of the highest level below it that
/// the CPU and the build have.
SardfChunkKernel sardfKernel(SimdLevel level);

/// The point terms of each fused program (fused()) with SARDF of radius
/// tables.radius, through the chunk kernel (evolve/sardf_chunk.h): min/max's
/// chunks and lookups wherever SARDF is min/max, smoothTerms()'s values,
/// gradients and terms in float where the operands blend. Like
/// minMaxTerms(), every chunk is read once for all the programs, and each
/// program's sums are the same, bit for bit, alone or together, on every
/// instruction-set level and whatever the number of threads.
std::vector<TermSums> sardfTerms(std::span<const Program> programs, const PointTables& tables);

/// |T △ L| of each fused program: voxels where the program's solid (from the
/// primitives' inside sets, [p][words]) and the labels (`labelCount` of them
/// set, none past the last voxel) disagree. Like the point terms, each chunk
/// of words is read once for all the programs.
std::vector<std::size_t> voxelMismatch(std::span<const Program> programs,
                                       const std::uint64_t* insideSets, const std::uint64_t* labels,
                                       std::size_t labelCount, std::size_t words,
                                       std::uint64_t lastWordMask);

}  // namespace csgvox::fitness_detail

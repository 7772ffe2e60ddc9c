#pragma once
/// The genetic search with Friedrich et al. 2018's search-space partitioning:
/// one search per maximal clique of the primitive-overlap graph, on the points
/// of the clique's primitives, all run in parallel; their trees merged at
/// common subtrees (evolve/partition.h); then a last search on all points,
/// seeded with the merged tree and the partitions' trees, which joins what
/// the merge could not (it stops after the stall rule like any search).

#include <cstddef>
#include <span>
#include <vector>

#include "evolve/fitness.h"
#include "evolve/genetic_search.h"
#include "evolve/partition.h"

namespace csgvox {

/// Options of evolvePartitioned().
struct PartitionOptions {
  double supportTolerance = 1.0;    ///< a point supports a primitive within this many εd of it
  double overlapMargin = 0.01;      ///< hulls grown by this fraction of D before the overlap test
  bool finalSearch = true;          ///< run the seeded search on all points after the merge
  std::size_t roughPoints = 20000;  ///< as GpOptions::roughPoints, for every search
};

/// What one partition's search gave.
struct PartitionRun {
  std::vector<std::size_t> primitives;  ///< library indices
  std::size_t points = 0;               ///< points of the partition
  std::size_t generations = 0;          ///< generations of its search
  std::size_t nodes = 0;                ///< nodes of its best tree
  double seconds = 0.0;                 ///< wall time of its search
};

/// Result of evolvePartitioned().
struct PartitionedResult {
  EvolveResult search;  ///< the final tree and its fitness on all points
  std::vector<PartitionRun> partitions;
  std::size_t mergedNodes = 0;    ///< nodes of the merged tree before the final search
  double partitionSeconds = 0.0;  ///< wall time of the graph, cliques and point split
  double searchSeconds = 0.0;     ///< wall time of the per-partition searches (in parallel)
  double mergeSeconds = 0.0;      ///< wall time of the merge
  double finalSeconds = 0.0;      ///< wall time of the final search
};

/// Runs the partitioned search on oriented points over a library. The
/// per-partition searches use `evolve` with seeds derived from evolve.seed
/// and the depth bound sqrt(π·C(n,2)) of an n-primitive partition (at most
/// evolve.variation.maxDepth), and no voxel term (a partition is a piece of
/// the solid); the final search uses `fitness` as given, with `target`.
/// A time limit is shared: half for the partitions, the rest for the end.
/// `onGeneration` reports the final search's generations.
/// @throw std::invalid_argument as evolve() and FitnessModel.
PartitionedResult evolvePartitioned(std::span<const Vec3> points, std::span<const Vec3> normals,
                                    double diagonal, const PrimitiveLibrary& library,
                                    const FitnessOptions& fitness, const EvolveOptions& evolve,
                                    const PartitionOptions& options = {},
                                    const GenerationCallback& onGeneration = {},
                                    const VoxelTarget* target = nullptr);

}  // namespace csgvox

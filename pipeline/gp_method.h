#pragma once
/// The genetic-programming baseline (Fayolle & Pasko 2016) on csgvox's own
/// detection: the fitted surfaces as unbounded solids plus separators, a
/// random initial population, Eq. 7 on the scan's points, and the genetic
/// search of evolve/genetic_search.h.

#include <cstddef>
#include <optional>
#include <span>

#include "core/point_cloud.h"
#include "core/surface.h"
#include "evolve/fitness.h"
#include "evolve/genetic_search.h"
#include "evolve/partitioned_search.h"
#include "pipeline/gp_primitives.h"

namespace csgvox {

/// Options of runGp().
struct GpOptions {
  EvolveOptions evolve;           ///< the search (population 150, crossover and mutation 0.3, ...)
  FitnessOptions fitness;         ///< Eq. 7 (min/max, εd = 0.01 D, α = 10°, λ = ln N)
  GpPrimitiveOptions primitives;  ///< separators and the clip box
  std::size_t roughPoints = 20000;  ///< generations use at most this many points (an even spread)
                                    ///< until the search stalls, then all (0: always all)
  bool partition = false;           ///< Friedrich's partitioning: a search per maximal clique of
                                    ///< the primitive-overlap graph, merged, then a seeded search
  PartitionOptions partitioning;  ///< its hulls and final search (roughPoints is taken from above)
};

/// Result of runGp().
struct GpResult {
  CsgTree tree;             ///< the best tree, bounded (see `clipped`)
  GpPrimitives primitives;  ///< the library the search combined
  EvolveResult search;      ///< the search's own figures (fitness on all points)
  std::optional<PartitionedResult> partitioned;  ///< the partitions' figures (with `partition`)
  bool clipped = false;  ///< the best tree reached out of the clip box (unbounded, or a long
                         ///< cylinder or cone) and was intersected with it
};

/// Runs the baseline on an oriented scan and its fitted surfaces.
/// `target` gives the voxel labels when options.fitness.voxelWeight > 0.
/// @throw std::invalid_argument when the scan has no normals, there are no
///        surfaces, or the voxel term is asked for without labels.
GpResult runGp(const PointCloud& scan, std::span<const Surface> surfaces,
               const GpOptions& options = {}, const GenerationCallback& onGeneration = {},
               const VoxelTarget* target = nullptr);

}  // namespace csgvox

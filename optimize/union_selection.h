#pragma once
/// Phase 2 of Wu et al. §4.2: choose the union of candidates (primitives and
/// subtrees without outside voxels) minimising Eq. 6:
///   E(z) = (1/M) Σ z_i − β |V+(P) ∩ ∪ V(C_i)| / |V+(P)|.

#include <chrono>
#include <cstdint>
#include <vector>

#include "core/run_control.h"
#include "voxel/voxel_set.h"

namespace csgvox {

/// Options of selectUnion.
struct UnionOptions {
  double beta = 0.9;  ///< weight of the coverage term of Eq. 6
  /// Cost of one candidate. 0: Wu's 1/M. > 0: this many voxels divided by
  /// |V+(P)|, so a candidate pays off when it adds about this many voxels.
  double minFeatureVoxels = 8.0;
  std::uint64_t nodeBudget = 50'000;  ///< branch-and-bound nodes before settling for local search
  /// Seeds the local search that gives branch and bound its first incumbent
  /// (its result matters only when the budget or the deadline stops branch
  /// and bound). The run's seed; 1 is the default run.
  std::uint64_t seed = 1;
  /// Its deadline stops branch and bound, which keeps its best solution so
  /// far (provedOptimal is then false); so does a cancel request. Default: never.
  RunControl control;
};

/// Result of selectUnion.
struct UnionResult {
  std::vector<std::uint32_t> chosen;  ///< indices of the chosen candidates, ascending
  double energy = 0.0;                ///< E(z)
  std::size_t covered = 0;            ///< |V+(P) ∩ ∪ V(C_i)|
  bool provedOptimal = false;         ///< true when branch and bound finished
};

/// Chooses the union of `candidates` (their voxel sets) covering `inside`
/// (V+(P)) best. M = candidates.size(). Exact unless the node budget runs
/// out (then the best of a local search, provedOptimal false).
UnionResult selectUnion(const VoxelSet& inside, const std::vector<const VoxelSet*>& candidates,
                        const UnionOptions& options = {});

/// E(z) of Eq. 6 for a given choice, evaluated directly (for tests).
double unionEnergy(const VoxelSet& inside, const std::vector<const VoxelSet*>& candidates,
                   const std::vector<std::uint8_t>& chosen, double beta);

}  // namespace csgvox

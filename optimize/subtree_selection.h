#pragma once
/// Phase 1 of Wu et al. §4.1: truncate a root primitive by intersecting it
/// with, or subtracting from it, some of its neighbours, choosing the actions
/// x that minimise Eq. 4:
///   E(x) = (1/L) Σ x_i − α |V+(root) ∩ V(sub)| / |V+(root) ∪ V−(sub)|.

#include <chrono>
#include <cstdint>
#include <vector>

#include "core/run_control.h"
#include "voxel/voxel_set.h"

namespace csgvox {

/// A truncation action on a root.
struct SubtreeAction {
  std::uint32_t primitive = 0;  ///< index of the neighbour in the candidate list
  bool subtract = false;        ///< false: root ∩ neighbour; true: root − neighbour
  bool operator==(const SubtreeAction&) const = default;
};

/// Options of selectSubtree.
struct SubtreeOptions {
  double alpha = 0.9;  ///< weight of the fit term of Eq. 4
  /// Cost of one action. 0: Wu's 1/L, which depends on how many neighbours
  /// the root has. > 0: this many voxels divided by |V+(root)|, so an action
  /// pays off when it corrects about this many voxels, whatever L is.
  double minFeatureVoxels = 8.0;
  std::uint64_t nodeBudget =
      20'000;  ///< branch-and-bound nodes before falling back to local search
  /// Seeds the local search that gives branch and bound its first incumbent
  /// (its result matters only when the budget or the deadline stops branch
  /// and bound). The run's seed; 1 is the default run.
  std::uint64_t seed = 1;
  /// Its deadline stops branch and bound, which keeps its best solution so
  /// far (provedOptimal is then false); so does a cancel request. Default: never.
  RunControl control;
};

/// Result of selectSubtree.
struct SubtreeResult {
  std::vector<SubtreeAction> actions;  ///< chosen actions
  double energy = 0.0;                 ///< E(x) of the choice
  VoxelSet voxels;                     ///< V(sub): the truncated root's voxels
  std::size_t actionCount = 0;         ///< L: the number of actions considered (2 |Ψ|)
  std::size_t usefulActions = 0;       ///< actions left after removing dominated ones
  bool provedOptimal = false;          ///< true when branch and bound finished
};

/// Chooses the truncation of `root` (voxel set V(root)) by its neighbours,
/// given the voxels labelled inside. `neighbours[i]` is V of candidate
/// `neighbourIds[i]`. Exact (branch and bound with a fit-term bound) unless
/// the node budget runs out, in which case the best solution of a local search
/// with restarts is returned and provedOptimal is false.
SubtreeResult selectSubtree(const VoxelSet& root, const VoxelSet& inside,
                            const std::vector<const VoxelSet*>& neighbours,
                            const std::vector<std::uint32_t>& neighbourIds,
                            const SubtreeOptions& options = {});

/// E(x) of Eq. 4 for a given choice, evaluated directly (for tests).
double subtreeEnergy(const VoxelSet& root, const VoxelSet& inside,
                     const std::vector<const VoxelSet*>& neighbours,
                     const std::vector<std::uint8_t>& chosen, double alpha);

}  // namespace csgvox

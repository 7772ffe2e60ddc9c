#pragma once
/// Wu et al. §4 end to end on voxels: roots, phase-1 subtrees, pruning,
/// phase-2 union, and the simplified CSG tree.

#include <span>
#include <vector>

#include "core/csg_tree.h"
#include "core/progress.h"
#include "optimize/skin_cuts.h"
#include "optimize/subtree_selection.h"
#include "optimize/union_selection.h"
#include "voxel/description_sets.h"

namespace csgvox {

/// Options of constructCsg.
struct ConstructOptions {
  SubtreeOptions subtree;    ///< phase 1 (alpha, solver budget; its seed is replaced by `seed`)
  UnionOptions unionChoice;  ///< phase 2 (beta, solver budget; its seed is replaced by `seed`)
  /// The run's seed: seeds the local searches that give both phases' branch
  /// and bound their first incumbent (it changes a tree only where a node
  /// budget or a deadline stops branch and bound). Same seed, same tree, at
  /// any thread count.
  std::uint64_t seed = 1;
  bool simplify = true;  ///< drop no-op operations and lift shared subtractions
  /// After phase 2, a local search over the whole union that drops actions
  /// and members while (primitives × minFeatureVoxels + voxels disagreeing
  /// with the labels) falls; undoes a root that cut too much and the members
  /// chosen to cover its loss.
  bool unionSearch = true;
  /// A candidate counts as free of outside voxels (Wu: |V−| = 0) when at most
  /// this fraction of its voxels are labelled outside; absorbs labelling noise.
  double outsideTolerance = 0.02;
  /// Scan units (0: off). A face of a subtracted box that lies within this
  /// distance inside the root's outer boundary is pushed out past it, so the
  /// cut goes through instead of leaving a skin thinner than voxels can see.
  double snapDistance = 0.0;
  /// When set, a cut is pushed through a skin only where the skin's outer
  /// face holds no scan points: a scanned face there is a real wall thinner
  /// than a voxel (a sheet-metal box), not an artefact of a hole that stops
  /// short.
  ScannedAt scannedAt;
};

/// Counts reported by constructCsg.
struct ConstructStats {
  std::size_t candidates = 0;       ///< primitive candidates given
  std::size_t usableRoots = 0;      ///< RPr: no outside voxels, inside the grid
  std::size_t truncationRoots = 0;  ///< RPr': to be truncated (after removing duplicates of RPr)
  std::size_t subtrees = 0;         ///< subtrees built in phase 1 with no outside voxels left
  std::size_t unionCandidates = 0;  ///< M: candidates of phase 2
  std::size_t selected = 0;         ///< candidates phase 2's selection put in the union
  std::size_t chosen = 0;           ///< members of the final union: the selected ones after the
                                    ///< union search (which adds primitives and subtrees
                                    ///< outside phase 2's candidates) and the no-op removal
  bool provedOptimal = true;        ///< every solve finished its branch and bound
};

/// Result of constructCsg.
struct Construction {
  CsgTree tree;     ///< the union of the chosen candidates (empty when none)
  VoxelSet voxels;  ///< the tree's voxels as computed from the description sets
  ConstructStats stats;
};

/// Builds a CSG tree from candidate solids and their descriptions on the
/// labelled grid. `candidates[i]` is described by `descriptions[i]`.
Construction constructCsg(std::span<const CsgTree> candidates,
                          std::span<const DescriptionSet> descriptions, const VoxelSet& inside,
                          const ConstructOptions& options = {},
                          const ProgressCallback& progress = {});

}  // namespace csgvox

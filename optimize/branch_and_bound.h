#pragma once
/// The exact solver of both binary optimisations of Wu et al. §4: choose a
/// subset of items, each a set of voxels, minimising an energy that depends
/// only on how many items are chosen and on how many voxels their union holds
/// in each channel (fixed subsets of the universe). Phase 1 (Eq. 4) unites
/// the voxels its actions remove from a root, with the root's inside and
/// outside voxels as channels; phase 2 (Eq. 6) unites the inside voxels its
/// candidates cover, with one channel, all of them. What differs between the
/// phases is the energy and its bound: a SelectionObjective.
///
/// The search: a greedy descent with perturbed restarts gives the incumbent,
/// then a depth-first branch and bound over the items in order proves it
/// optimal or improves it, unless a node budget or a deadline stops it. Both
/// run on classes of voxels (optimize/selection_classes.h), where every count
/// is exact, so their cost follows the number of classes, not of voxels.

#include <array>
#include <chrono>
#include <cstdint>
#include <span>
#include <vector>

#include "core/run_control.h"
#include "voxel/voxel_set.h"

namespace csgvox {

/// Voxels of the union in each channel of a SelectionProblem (at most two).
using ChannelCounts = std::array<std::size_t, 2>;

/// What a selection minimises.
class SelectionObjective {
 public:
  virtual ~SelectionObjective() = default;
  /// Energy of `chosen` items whose union holds counts[k] voxels of channel k.
  virtual double energy(std::size_t chosen, const ChannelCounts& counts) const = 0;
  /// A lower bound of the energy of every selection that adds one or more of
  /// the undecided items to the current one (`chosen` items, union counts
  /// `counts`), given that such a union holds at most `reach` voxels of the
  /// problem's bound channel. +infinity when none can have a lower energy
  /// than the current selection.
  virtual double bound(std::size_t chosen, const ChannelCounts& counts,
                       std::size_t reach) const = 0;
};

/// One item of a SelectionProblem.
struct SelectionItem {
  std::uint32_t id = 0;  ///< the caller's index of the item
  VoxelSet set;          ///< voxels the item adds to the union
};

/// Items over a universe of voxels, and the channels the energy counts in.
class SelectionProblem {
 public:
  /// `channels` (one or two, all of the universe's size) are the subsets of
  /// the universe the energy counts the union in. An item is worth adding
  /// only when it adds voxels of channel `boundChannel`, and the bound is
  /// taken over that channel: the objective must never fall by adding an
  /// item that adds no voxel of that channel.
  SelectionProblem(std::vector<VoxelSet> channels, std::size_t boundChannel);

  /// Adds an item with id `id` unless an item with the same set exists;
  /// returns whether it was added.
  bool add(VoxelSet set, std::uint32_t id);
  /// Reorders the items by descending `score` (one per item, in the current
  /// order); ties keep their order. Branch and bound finds good incumbents
  /// early and gets strong bounds when the most promising items come first.
  void sortByDescending(std::span<const double> score);

  /// Voxels in the universe.
  std::size_t universe() const { return channels_.front().size(); }
  /// Number of channels (1 or 2).
  std::size_t channelCount() const { return channels_.size(); }
  /// Channel k's voxels.
  const VoxelSet& channel(std::size_t k) const { return channels_[k]; }
  /// The channel that decides whether an item is worth adding and bounds the search.
  std::size_t boundChannel() const { return boundChannel_; }
  /// The items, in search order.
  const std::vector<SelectionItem>& items() const { return items_; }
  /// The union's count in each channel.
  ChannelCounts counts(const VoxelSet& united) const;

 private:
  std::vector<VoxelSet> channels_;
  std::size_t boundChannel_ = 0;
  std::vector<SelectionItem> items_;
};

/// Options of solveSelection.
struct SelectionOptions {
  int restarts = 3;                   ///< perturbed restarts of the greedy descent
  std::uint64_t seed = 1;             ///< seeds the restarts' perturbations
  std::uint64_t nodeBudget = 20'000;  ///< branch-and-bound nodes before keeping the incumbent
  /// Its deadline or a cancel request stops branch and bound, which keeps
  /// its best solution so far. Default: never.
  RunControl control;
};

/// The options of a phase's search from the phase's own options (any struct
/// with a run `seed`, a `nodeBudget` and a `control`): `restarts` restarts
/// seeded by the phase's stream `stream` of the run seed (streamSeed).
template <class PhaseOptions>
SelectionOptions phaseSearch(const PhaseOptions& phase, int restarts, std::uint64_t stream);

/// Result of solveSelection.
struct Selection {
  std::vector<std::uint8_t> chosen;  ///< per item of the problem, in its order: 1 when chosen
  double energy = 0.0;               ///< the objective's energy of the choice
  bool provedOptimal = false;        ///< true when branch and bound finished
};

/// The selection of `problem`'s items minimising `objective`: exact unless
/// the node budget, the deadline or a cancel request stops branch and bound first (then the
/// best found, provedOptimal false). Deterministic for a given seed.
Selection solveSelection(const SelectionProblem& problem, const SelectionObjective& objective,
                         const SelectionOptions& options = {});

class SelectionClasses;

/// The same for a problem given by its classes alone (the items in search
/// order, as SelectionClasses numbers them) and its bound channel; the same
/// answer as for the SelectionProblem the classes were built from.
Selection solveSelection(const SelectionClasses& classes, std::size_t boundChannel,
                         const SelectionObjective& objective, const SelectionOptions& options = {});

/// The seed of one random stream of a run seeded with `runSeed`: `stream`
/// itself for the default run seed 1, a well-mixed other value for any other
/// run seed.
std::uint64_t streamSeed(std::uint64_t runSeed, std::uint64_t stream);

template <class PhaseOptions>
SelectionOptions phaseSearch(const PhaseOptions& phase, int restarts, std::uint64_t stream) {
  return {.restarts = restarts,
          .seed = streamSeed(phase.seed, stream),
          .nodeBudget = phase.nodeBudget,
          .control = phase.control};
}

}  // namespace csgvox

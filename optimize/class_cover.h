#pragma once
/// A choice of items over SelectionClasses with every item's flip effect
/// cached: for an item not chosen, the voxels of each channel adding it would
/// add to the union; for a chosen one, those removing it would take out. A
/// local search then weighs every single flip for the price of one energy
/// evaluation each, and a flip updates only the items sharing a class whose
/// cover changes between none and one or between one and two.

#include <cstdint>
#include <span>
#include <vector>

#include "optimize/selection_classes.h"

namespace csgvox {

/// Coverage of a SelectionClasses by a choice of items, with cached flip effects.
class ClassCover {
 public:
  /// No item chosen. `classes` must outlive the cover.
  explicit ClassCover(const SelectionClasses& classes);

  /// Chooses exactly the items a with x[a] != 0 (x: one flag per item).
  void reset(std::span<const std::uint8_t> x);
  /// Adds item a when it is not chosen, removes it when it is.
  void flip(std::size_t a);

  /// True when item a is chosen.
  bool chosen(std::size_t a) const { return x_[a] != 0; }
  /// Voxels of the union of the chosen items in each channel.
  const ChannelCounts& counts() const { return counts_; }
  /// Item a's flip effect: what adding it adds to counts() when it is not
  /// chosen, what removing it takes out when it is.
  const ChannelCounts& flipEffect(std::size_t a) const { return effect_[a]; }
  /// counts() after flipping item a.
  ChannelCounts countsAfterFlip(std::size_t a) const;

 private:
  const SelectionClasses& classes_;
  std::vector<std::uint8_t> x_;
  std::vector<std::uint32_t> cover_;  // chosen items holding each class
  std::vector<std::uint64_t> sum_;    // the sum of their indices (the one item, when cover_ is 1)
  std::vector<ChannelCounts> effect_;
  ChannelCounts counts_{};
};

}  // namespace csgvox

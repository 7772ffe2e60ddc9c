#pragma once
/// Incremental bookkeeping for set-cover style local search: how many chosen
/// sets cover each voxel, with bitsets of the voxels covered at least once and
/// exactly once, so that the effect of adding or removing one set is a single
/// AND/AND-NOT plus popcount.

#include <bit>
#include <cstdint>
#include <span>
#include <vector>

#include "voxel/voxel_set.h"

namespace csgvox {

/// Indices of the non-zero 64-bit words of a set.
inline std::vector<std::uint32_t> nonZeroWords(const VoxelSet& s) {
  std::vector<std::uint32_t> out;
  const auto words = s.words();
  for (std::size_t w = 0; w < words.size(); ++w) {
    if (words[w]) out.push_back(std::uint32_t(w));
  }
  return out;
}

/// Coverage counts over a universe of `size` voxels.
class CoverState {
 public:
  explicit CoverState(std::size_t size) : counts_(size, 0), covered_(size), once_(size) {}

  const VoxelSet& covered() const { return covered_; }
  /// Members of `s` that adding it would newly cover.
  std::size_t gain(const VoxelSet& s) const { return VoxelSet::countAndNot(s, covered_); }
  /// Members of `s` that removing it (it must be chosen) would uncover.
  std::size_t loss(const VoxelSet& s) const { return VoxelSet::countAnd(s, once_); }

  void add(const VoxelSet& s) { update(s, +1); }
  void remove(const VoxelSet& s) { update(s, -1); }

  // The same on the words `words` of `s` only: the indices of its non-zero
  // words (see nonZeroWords). A sparse set then costs its own size, not the
  // universe's.
  std::size_t gain(const VoxelSet& s, std::span<const std::uint32_t> words) const {
    const auto a = s.words(), c = covered_.words();
    std::size_t n = 0;
    for (std::uint32_t w : words) n += std::size_t(std::popcount(a[w] & ~c[w]));
    return n;
  }
  std::size_t loss(const VoxelSet& s, std::span<const std::uint32_t> words) const {
    const auto a = s.words(), o = once_.words();
    std::size_t n = 0;
    for (std::uint32_t w : words) n += std::size_t(std::popcount(a[w] & o[w]));
    return n;
  }
  void add(const VoxelSet& s, std::span<const std::uint32_t> words) { update(s, words, +1); }
  void remove(const VoxelSet& s, std::span<const std::uint32_t> words) { update(s, words, -1); }

 private:
  void update(const VoxelSet& s, int delta) {
    const auto words = s.words();
    for (std::size_t w = 0; w < words.size(); ++w) updateWord(w, words[w], delta);
  }
  void update(const VoxelSet& s, std::span<const std::uint32_t> which, int delta) {
    const auto words = s.words();
    for (std::uint32_t w : which) updateWord(w, words[w], delta);
  }
  void updateWord(std::size_t w, std::uint64_t word, int delta) {
    for (std::uint64_t bits = word; bits; bits &= bits - 1) {
      const std::size_t i = w * 64 + std::size_t(std::countr_zero(bits));
      const int c = int(counts_[i]) + delta;
      counts_[i] = std::uint32_t(c);
      if (c > 0)
        covered_.set(i);
      else
        covered_.reset(i);
      if (c == 1)
        once_.set(i);
      else
        once_.reset(i);
    }
  }

  std::vector<std::uint32_t> counts_;
  VoxelSet covered_;
  VoxelSet once_;
};

}  // namespace csgvox

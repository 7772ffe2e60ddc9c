#pragma once
/// A set of voxels as a bitset: one bit per voxel of a VoxelGrid, packed in
/// 64-bit words. Set algebra is word-wise (AND, OR, AND-NOT) and sizes are
/// popcounts, so a 64³ set (4096 words) is combined and counted in well under
/// a microsecond. The word-wise kernels use AVX2 or AVX-512 where the CPU has
/// them (voxel/bitset_kernels.h, chosen per call by simdLevel() of
/// core/cpu_features.h); every level gives the same results.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace csgvox {

/// A fixed-size set of voxel indices [0, size()).
class VoxelSet {
 public:
  VoxelSet() = default;
  /// An empty set over `bits` voxels.
  explicit VoxelSet(std::size_t bits) : bits_(bits), words_((bits + 63) / 64, 0) {}

  /// Number of voxels the set ranges over (not the number of members).
  std::size_t size() const { return bits_; }
  std::size_t wordCount() const { return words_.size(); }
  std::span<const std::uint64_t> words() const { return words_; }

  bool test(std::size_t i) const { return (words_[i >> 6] >> (i & 63)) & 1u; }
  void set(std::size_t i) { words_[i >> 6] |= std::uint64_t(1) << (i & 63); }
  void reset(std::size_t i) { words_[i >> 6] &= ~(std::uint64_t(1) << (i & 63)); }
  /// Adds every voxel.
  void fill();
  /// Removes every voxel.
  void clear();

  /// Number of members.
  std::size_t count() const;
  bool none() const;

  VoxelSet& operator&=(const VoxelSet& other);
  VoxelSet& operator|=(const VoxelSet& other);
  /// this = this \ other.
  VoxelSet& subtract(const VoxelSet& other);
  /// Indices of the members, ascending.
  std::vector<std::uint32_t> members() const;
  /// The set restricted to `positions` and renumbered: bit p of the result is
  /// bit positions[p] of this set. Used to work inside a smaller universe.
  VoxelSet gather(std::span<const std::uint32_t> positions) const;
  /// gather(mask.members()) at word speed: the set restricted to the members
  /// of `mask` (of the same size) and renumbered in their order.
  VoxelSet compress(const VoxelSet& mask) const;
  /// The complement within [0, size()).
  VoxelSet complemented() const;

  friend VoxelSet operator&(VoxelSet a, const VoxelSet& b) { return a &= b; }
  friend VoxelSet operator|(VoxelSet a, const VoxelSet& b) { return a |= b; }
  friend VoxelSet operator-(VoxelSet a, const VoxelSet& b) { return a.subtract(b); }
  bool operator==(const VoxelSet& other) const = default;

  /// |a ∩ b| without building the intersection.
  static std::size_t countAnd(const VoxelSet& a, const VoxelSet& b);
  /// |a \ b|.
  static std::size_t countAndNot(const VoxelSet& a, const VoxelSet& b);
  /// |a ∪ b|.
  static std::size_t countOr(const VoxelSet& a, const VoxelSet& b);
  /// True when a ∩ b is not empty.
  static bool intersects(const VoxelSet& a, const VoxelSet& b);
  /// |a ∩ b| / |a ∪ b|; 1 when both are empty.
  static double iou(const VoxelSet& a, const VoxelSet& b);

 private:
  void clearPadding();

  std::size_t bits_ = 0;
  std::vector<std::uint64_t> words_;
};

}  // namespace csgvox

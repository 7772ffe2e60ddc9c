#pragma once
/// The fitness of a CSG tree on an oriented scan (Fayolle & Pasko 2016,
/// Eq. 7), with csgvox's volumetric term:
///
///   E(t) = Σi [exp(−di²) + exp(−θi²)] − λ·size(t) − w·N·|T(t) △ L| / |L|
///
/// di = f(xi)/εd, θi = angle(∇f(xi), −ni)/α (∇f points inwards, the scan
/// normals ni outwards), size(t) the number of nodes, N the number of points,
/// T(t) the voxels whose centre the tree holds and L the voxels labelled
/// inside. Every primitive's value, gradient and per-point terms are computed
/// once; a tree is compiled to a postfix program and evaluated over whole
/// arrays of points. With min/max the field at a point is one leaf's (signed)
/// field, so the terms are looked up, not recomputed.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "core/csg_tree.h"
#include "core/sardf.h"
#include "core/set_operations.h"
#include "evolve/primitive_library.h"
#include "voxel/voxel_grid.h"
#include "voxel/voxel_set.h"

namespace csgvox {

/// Options of the fitness.
struct FitnessOptions {
  double distanceTolerance = 0.01;  ///< εd, fraction of the scan's diagonal D
  double angleTolerance = 10.0;     ///< α, degrees (about 35 suits noisy scans)
  double sizeWeight = -1.0;         ///< λ per tree node; < 0: ln N (N = points evaluated)
  SetOperationKind operations = SetOperationKind::MinMax;  ///< field of the set operations
  double sardfRadius = kSardfRadiusFraction;  ///< SARDF: blending radius R, fraction of D
  double voxelWeight = 0.0;                   ///< w of the voxel term (0: off; needs voxel labels)
};

/// The voxel labels the volumetric term compares a tree's solid with.
struct VoxelTarget {
  VoxelGrid grid;   ///< the grid of the labels
  VoxelSet inside;  ///< voxels labelled inside
};

/// A fitness value and its parts (larger is better).
struct Fitness {
  double total = -std::numeric_limits<double>::infinity();  ///< E(t)
  double distanceTerm = 0.0;                                ///< Σ exp(−di²)
  double normalTerm = 0.0;                                  ///< Σ exp(−θi²)
  double sizePenalty = 0.0;                                 ///< λ·size(t)
  double voxelPenalty = 0.0;                                ///< w·N·|T △ L| / |L|
  std::size_t nodes = 0;                                    ///< size(t)
  std::size_t voxelMismatch = 0;  ///< |T △ L| (0 without the voxel term)
};

/// The fitness of trees over one fixed set of points and primitives.
/// Immutable after construction and safe to use from many threads.
class FitnessModel {
 public:
  /// Precomputes every primitive's field and terms at every point (and its
  /// inside set over the target's voxels when options.voxelWeight > 0).
  /// `diagonal` is the scan's D, which scales εd and the SARDF radius.
  /// @throw std::invalid_argument when points and normals differ in size,
  ///        there are no points, D is not > 0, or the voxel term is asked
  ///        for without a target.
  FitnessModel(std::span<const Vec3> points, std::span<const Vec3> normals, double diagonal,
               const PrimitiveLibrary& library, const FitnessOptions& options = {},
               const VoxelTarget* target = nullptr);
  /// `other`'s library, options and voxel term (shared, not computed again)
  /// on other points; λ < 0 is ln of their number.
  /// @throw std::invalid_argument when points and normals differ in size or
  ///        there are no points.
  FitnessModel(std::span<const Vec3> points, std::span<const Vec3> normals,
               const FitnessModel& other);
  ~FitnessModel();
  FitnessModel(FitnessModel&&) noexcept;
  FitnessModel& operator=(FitnessModel&&) noexcept;

  /// E(t) and its parts. Trees whose leaves are not the library's (by address
  /// or equal primitive) are refused.
  /// @throw std::invalid_argument for an empty tree or a foreign leaf.
  Fitness evaluate(const CsgTree& tree) const;

  /// E(t) of each tree, as evaluate(tree) gives it (bit for bit), computed
  /// together: with min/max operations each chunk of the points' cached
  /// arrays is read once for all the trees (about twice as fast as one tree
  /// after another once the arrays outgrow the cache; bench_evolve).
  /// @throw std::invalid_argument as evaluate(tree).
  std::vector<Fitness> evaluate(std::span<const CsgTree* const> trees) const;

  std::size_t pointCount() const;
  const PrimitiveLibrary& library() const;
  const FitnessOptions& options() const;
  /// λ in use (the option, or ln N).
  double sizeWeight() const;

 private:
  struct Data;
  // Every primitive's field and terms at the points.
  static std::unique_ptr<Data> pointData(std::span<const Vec3> points,
                                         std::span<const Vec3> normals, double diagonal,
                                         const PrimitiveLibrary& library,
                                         const FitnessOptions& options);
  std::unique_ptr<const Data> data_;
};

/// E(t) of one tree on `points` (with their outward `normals`), computed point
/// by point from the tree's value and gradient (CsgTree::evaluate with the
/// options' set operations): no per-primitive tables, so a single tree on
/// millions of points costs one tree evaluation and one exp/acos pair per
/// point, in memory independent of the points. The same E(t) as a
/// FitnessModel on the same points and primitives, up to the model's float
/// tables (relative 1e-6). Deterministic for any number of threads (the
/// points are summed in fixed blocks, in order). No voxel term.
/// @throw std::invalid_argument when points and normals differ in size,
///        there are no points, D is not > 0, the tree is empty, or
///        options.voxelWeight > 0.
Fitness treeFitness(const CsgTree& tree, std::span<const Vec3> points,
                    std::span<const Vec3> normals, double diagonal,
                    const FitnessOptions& options = {});

/// `count` indices of [0, n) spread evenly over a seeded shuffle (all of
/// them, in order, when count >= n): the points of a rough fitness.
std::vector<std::uint32_t> spreadSample(std::size_t n, std::size_t count, std::uint64_t seed);

/// `full` on `count` of its points (`points`, `normals`: the ones it was
/// built on), picked by spreadSample(seed): the model a search ranks by while
/// it is rough. It shares `full`'s voxel term. None when count is 0 or there
/// are no more than `count` points (the full model is then as cheap).
std::optional<FitnessModel> roughModel(const FitnessModel& full, std::span<const Vec3> points,
                                       std::span<const Vec3> normals, std::size_t count,
                                       std::uint64_t seed);

}  // namespace csgvox

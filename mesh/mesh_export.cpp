#include "mesh/mesh_export.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/tree_program.h"

namespace csgvox {
namespace {

using LeafT = openvdb::FloatTree::LeafNodeType;

constexpr double kBandVoxels = 3.0;  // narrow-band half width: |f| below it is stored exactly
constexpr int kMarginVoxels = 4;     // sampled voxels beyond the bounds on each side (> band)
constexpr int kLeafDim = static_cast<int>(LeafT::DIM);  // 8 voxels along a leaf side
constexpr int kBlockDim = 8 * kLeafDim;                 // coarse culling block side, voxels
// Estimated peak bytes per sampled leaf: the leaf itself, OpenVDB's meshing
// auxiliary trees and the output mesh (measured at several resolutions).
constexpr double kBytesPerLeaf = 9.0 * 1024.0;
// Dual contouring: eigenvalues of the normal matrix below this fraction of
// the largest are dropped; normals are sampled this many voxels inside the
// solid; edge crossings are located to this many voxels.
constexpr double kSingularCutoff = 0.01;
constexpr double kGradientProbe = 1e-4;
constexpr double kCrossingTolerance = 1e-6;
constexpr int kMinResolution = 8;
constexpr int kMaxResolution = 2048;
// Pruned programs cover their voxels grown by this many voxels on each side
// (a point of a cell whose first corner is in a leaf lies in that leaf's region).
constexpr double kRegionGrowth = 1.5;
// Superblocks of this many blocks along each side share one pruned program.
constexpr int kSuperblockBlocks = 8;
// OpenVDB refuses a transform whose voxel volume is below 3e-15.
constexpr double kMinVoxelSize = 1.5e-5;
// Single-precision vertices and level-set values must stay far from overflow.
constexpr double kMaxExtent = 1e30;

// The voxel lattice: voxel ijk samples the point origin + voxelSize * ijk.
struct Lattice {
  Vec3 origin;
  double voxelSize = 1.0;
  Vec3 at(const openvdb::Coord& ijk) const {
    return origin + voxelSize * Vec3(ijk.x(), ijk.y(), ijk.z());
  }
  // The sample points of the cube of `voxels` voxels from `origin`, grown by
  // kRegionGrowth voxels on each side.
  Aabb region(const openvdb::Coord& first, int voxels) const {
    Aabb b;
    b.min = at(first) - Vec3::Constant(kRegionGrowth * voxelSize);
    b.max = at(first.offsetBy(voxels - 1)) + Vec3::Constant(kRegionGrowth * voxelSize);
    return b;
  }
};

// Reports the fraction done of each stage to a ProgressCallback, from any
// thread (one call at a time, never lower than the last within a stage:
// two threads' counts may reach the lock in either order); remembers a
// request to stop.
class Progress {
 public:
  explicit Progress(const RunControl& control) : control_(control) {}
  void stage(std::string_view name, std::size_t total) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      last_ = 0.0;
    }
    stage_ = name;
    total_ = std::max<std::size_t>(total, 1);
    done_ = 0;
    report(0.0);
  }
  // Counts `n` more items of the stage done.
  void advance(std::size_t n) {
    const std::size_t before = done_.fetch_add(n);
    const std::size_t step = std::max<std::size_t>(total_ / 100, 1);
    if ((before + n) / step != before / step) report(double(before + n) / double(total_));
  }
  bool stopped() const { return control_.cancelled(); }
  // @throw std::runtime_error when the callback asked to stop.
  void check() const {
    if (stopped()) throw CancelledError("meshTree: cancelled");
  }

 private:
  void report(double fraction) {
    const std::lock_guard<std::mutex> lock(mutex_);
    last_ = std::max(last_, std::min(fraction, 1.0));
    control_.report(last_, stage_);
  }

  const RunControl& control_;
  std::string_view stage_;
  std::size_t total_ = 1;
  std::atomic<std::size_t> done_{0};
  std::mutex mutex_;
  double last_ = 0.0;  // the last fraction reported in this stage
};

// The tree's field near its surface: each sampled leaf of the lattice keeps
// a program pruned to the leaf's region (the primitives that can change the
// field within the narrow band there). Values are those of the tree, bit for
// bit: where the pruned program's value is not exact (|f| at or above its
// threshold) the whole tree is evaluated.
class NearField {
 public:
  NearField(const CsgTree& tree, const Lattice& lattice) : tree_(tree), lattice_(lattice) {}
  void add(const openvdb::Coord& leafOrigin, TreeProgram program) {
    index_.emplace(key(leafOrigin), programs_.size());
    programs_.push_back(std::move(program));
  }
  double value(const Vec3& p) const {
    if (const TreeProgram* program = find(p)) {
      const double f = program->value(p);
      if (std::abs(f) < program->threshold()) return f;
    }
    return tree_.value(p);
  }
  FieldValue evaluate(const Vec3& p) const {
    if (const TreeProgram* program = find(p)) {
      const FieldValue v = program->evaluate(p);
      if (std::abs(v.f) < program->threshold()) return v;
    }
    return tree_.evaluate(p);
  }

 private:
  static std::uint64_t key(const openvdb::Coord& c) {
    std::uint64_t k = 0;
    for (int i = 0; i < 3; ++i) k = (k << 21) | (static_cast<std::uint64_t>(c[i]) & 0x1fffffu);
    return k;
  }
  const TreeProgram* find(const Vec3& p) const {
    const Vec3 u = ((p - lattice_.origin) / lattice_.voxelSize).array().floor();
    if (!(u.array() >= 0.0).all() || !(u.array() < double(1 << 21)).all()) return nullptr;
    const openvdb::Coord leaf(static_cast<int>(u.x()) & ~(kLeafDim - 1),
                              static_cast<int>(u.y()) & ~(kLeafDim - 1),
                              static_cast<int>(u.z()) & ~(kLeafDim - 1));
    const auto it = index_.find(key(leaf));
    return it == index_.end() ? nullptr : &programs_[it->second];
  }

  const CsgTree& tree_;
  const Lattice& lattice_;
  std::vector<TreeProgram> programs_;
  std::unordered_map<std::uint64_t, std::size_t> index_;
};

void validate(const CsgTree& tree, const MeshOptions& options) {
  if (tree.empty()) throw std::invalid_argument("meshTree: the tree is empty");
  tree.validate();
  const Aabb bounds = tree.bounds();
  if (bounds.isEmpty()) throw std::invalid_argument("meshTree: the solid's bounds are empty");
  if (!bounds.isBounded()) {
    throw std::invalid_argument("meshTree: the solid is unbounded (a half-space or a complement)");
  }
  if (options.resolution < kMinResolution || options.resolution > kMaxResolution) {
    throw std::invalid_argument(
        "meshTree: resolution must be between " + std::to_string(kMinResolution) + " and " +
        std::to_string(kMaxResolution) + ", got " + std::to_string(options.resolution));
  }
  if (!(options.adaptivity >= 0.0 && options.adaptivity <= 1.0)) {
    throw std::invalid_argument("meshTree: adaptivity must be between 0 and 1");
  }
  if (!(options.memoryLimitMiB > 0.0)) {
    throw std::invalid_argument("meshTree: memoryLimitMiB must be > 0");
  }
}

// "sphere 'hole' (leaf 3)" or "sphere (leaf 3)": a leaf named for messages.
std::string describeLeaf(const Node& leaf, std::size_t index) {
  std::string s(primitiveTypeName(leaf.primitive.type()));
  if (!leaf.name.empty()) s += " '" + leaf.name + "'";
  return s + " (leaf " + std::to_string(index + 1) + " in depth-first order)";
}

// Refuses trees whose lattice OpenVDB or single precision cannot represent,
// naming the primitive responsible: the one with the largest extent.
void requireMeshable(const CsgTree& tree, const Aabb& bounds, double voxelSize, int resolution) {
  const std::vector<const Node*> leaves = tree.leaves();
  std::size_t largest = 0;
  double largestExtent = -1.0;
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    const Aabb b = leaves[i]->primitive.bounds();
    const double extent =
        b.isBounded()
            ? std::max(b.size().maxCoeff(), b.min.cwiseAbs().cwiseMax(b.max.cwiseAbs()).maxCoeff())
            : 0.0;
    if (extent > largestExtent) {
      largestExtent = extent;
      largest = i;
    }
  }
  const std::string who = "meshTree: " + describeLeaf(*leaves[largest], largest);
  const auto number = [](double x) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3g", x);
    return std::string(buf);
  };
  if (!std::isfinite(voxelSize) || !(bounds.size().array().isFinite().all()) ||
      largestExtent > kMaxExtent) {
    throw std::invalid_argument(who + " is too large to mesh: its coordinates reach " +
                                number(largestExtent) + " (at most " + number(kMaxExtent) + ")");
  }
  if (!(voxelSize >= kMinVoxelSize)) {
    throw std::invalid_argument(
        who + " is too small for the mesh resolution: the solid spans " +
        number(bounds.size().maxCoeff()) + ", a voxel of " + number(voxelSize) + " at resolution " +
        std::to_string(resolution) + " is below the smallest the mesher supports (" +
        number(kMinVoxelSize) + "); scale the part up or lower the resolution");
  }
}

// The leaves that may hold a voxel with |f| < band, each with the tree's
// program pruned to its region.
struct Candidates {
  std::vector<openvdb::Coord> origins;
  std::vector<TreeProgram> programs;
};

// Finds the candidate leaves. The field is 1-Lipschitz, so a block whose
// centre value exceeds its half diagonal plus the band holds no voxel with
// |f| < band. Blocks of 8^3 leaves are culled first. The tree is pruned on
// the way down (superblocks of 8^3 blocks, blocks, their octants and the
// octants of those), with thresholds above every value the tests compare, so
// the tests see the tree's exact values. Gives up (nullopt) as soon as more
// than `maxLeaves` leaves are found.
std::optional<Candidates> candidateLeaves(const TreeProgram& tree, const Lattice& lattice,
                                          const openvdb::Coord& dims, std::size_t maxLeaves,
                                          Progress& progress) {
  const double h = lattice.voxelSize;
  const double band = kBandVoxels * h;
  const auto halfDiagonal = [h](int voxels) { return 0.5 * (voxels - 1) * std::sqrt(3.0) * h; };
  const auto centreOf = [&](const openvdb::Coord& origin, int voxels) {
    const double half = 0.5 * (voxels - 1);
    return Vec3(lattice.at(origin) + Vec3::Constant(half * h));
  };
  const double blockThreshold = halfDiagonal(kBlockDim) + band + h;
  const double leafTestThreshold = halfDiagonal(kLeafDim) + band + h;
  const double leafThreshold = band + h;  // above the sampled band, in float too
  const int bx = (dims.x() + kBlockDim - 1) / kBlockDim;
  const int by = (dims.y() + kBlockDim - 1) / kBlockDim;
  const int bz = (dims.z() + kBlockDim - 1) / kBlockDim;
  const int sx = (bx + kSuperblockBlocks - 1) / kSuperblockBlocks;
  const int sy = (by + kSuperblockBlocks - 1) / kSuperblockBlocks;
  const int sz = (bz + kSuperblockBlocks - 1) / kSuperblockBlocks;
  constexpr int kSuperDim = kSuperblockBlocks * kBlockDim;
  std::vector<TreeProgram> super(std::size_t(sx) * sy * sz);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, super.size()), [&](const auto& range) {
    for (std::size_t s = range.begin(); s != range.end(); ++s) {
      const int i = static_cast<int>(s % sx), j = static_cast<int>((s / sx) % sy),
                k = static_cast<int>(s / (std::size_t(sx) * sy));
      const openvdb::Coord origin(i * kSuperDim, j * kSuperDim, k * kSuperDim);
      super[s] = tree.restricted(lattice.region(origin, kSuperDim), blockThreshold);
    }
  });
  const std::size_t blockCount = std::size_t(bx) * by * bz;
  progress.stage("cull", blockCount);
  std::vector<Candidates> perBlock(blockCount);
  std::atomic<std::size_t> found{0};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blockCount), [&](const auto& range) {
    for (std::size_t b = range.begin(); b != range.end(); ++b) {
      if (found.load(std::memory_order_relaxed) > maxLeaves || progress.stopped()) return;
      const int i = static_cast<int>(b % bx), j = static_cast<int>((b / bx) % by),
                k = static_cast<int>(b / (std::size_t(bx) * by));
      const openvdb::Coord blockOrigin(i * kBlockDim, j * kBlockDim, k * kBlockDim);
      const std::size_t s =
          std::size_t(i / kSuperblockBlocks) +
          std::size_t(sx) * (j / kSuperblockBlocks + std::size_t(sy) * (k / kSuperblockBlocks));
      const TreeProgram block =
          super[s].restricted(lattice.region(blockOrigin, kBlockDim), blockThreshold);
      const double fBlock = block.value(centreOf(blockOrigin, kBlockDim));
      progress.advance(1);
      if (std::abs(fBlock) >= halfDiagonal(kBlockDim) + band) continue;
      // Programs of the block's 4^3 sub-blocks of 16 voxels, through its octants.
      constexpr int kHalf = kBlockDim / 2, kQuarter = kBlockDim / 4;
      std::vector<TreeProgram> quarters(64);
      for (int o = 0; o < 8; ++o) {
        const openvdb::Coord halfOrigin =
            blockOrigin.offsetBy((o & 1) * kHalf, ((o >> 1) & 1) * kHalf, (o >> 2) * kHalf);
        const TreeProgram half =
            block.restricted(lattice.region(halfOrigin, kHalf), leafTestThreshold);
        for (int q = 0; q < 8; ++q) {
          const int x = 2 * (o & 1) + (q & 1), y = 2 * ((o >> 1) & 1) + ((q >> 1) & 1),
                    z = 2 * (o >> 2) + (q >> 2);
          const openvdb::Coord quarterOrigin =
              blockOrigin.offsetBy(x * kQuarter, y * kQuarter, z * kQuarter);
          quarters[std::size_t(x + 4 * y + 16 * z)] =
              half.restricted(lattice.region(quarterOrigin, kQuarter), leafTestThreshold);
        }
      }
      for (int z = 0; z < kBlockDim; z += kLeafDim) {
        for (int y = 0; y < kBlockDim; y += kLeafDim) {
          for (int x = 0; x < kBlockDim; x += kLeafDim) {
            const openvdb::Coord leafOrigin = blockOrigin.offsetBy(x, y, z);
            const TreeProgram& quarter =
                quarters[std::size_t(x / kQuarter + 4 * (y / kQuarter) + 16 * (z / kQuarter))];
            const double fLeaf = quarter.value(centreOf(leafOrigin, kLeafDim));
            if (std::abs(fLeaf) < halfDiagonal(kLeafDim) + band) {
              perBlock[b].origins.push_back(leafOrigin);
              perBlock[b].programs.push_back(
                  quarter.restricted(lattice.region(leafOrigin, kLeafDim), leafThreshold));
            }
          }
        }
      }
      found += perBlock[b].origins.size();
    }
  });
  progress.check();
  if (found > maxLeaves) return std::nullopt;
  Candidates all;
  for (auto& c : perBlock) {
    all.origins.insert(all.origins.end(), c.origins.begin(), c.origins.end());
    for (TreeProgram& p : c.programs) all.programs.push_back(std::move(p));
  }
  return all;
}

// Samples -f (OpenVDB level sets are negative inside) on the candidate leaves;
// voxels with |f| < band are active, the others hold +-background. Leaves
// without an active voxel are dropped: signedFloodFill restores their sign.
// The programs of the kept leaves go to `near`.
openvdb::FloatGrid::Ptr sampleLevelSet(Candidates& candidates, const Lattice& lattice,
                                       const Vec3& gridOrigin, NearField& near,
                                       Progress& progress) {
  const float background = static_cast<float>(kBandVoxels * lattice.voxelSize);
  const std::vector<openvdb::Coord>& origins = candidates.origins;
  std::vector<std::unique_ptr<LeafT>> leaves(origins.size());
  progress.stage("sample", origins.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, origins.size()), [&](const auto& range) {
    std::vector<Vec3> points(LeafT::SIZE);
    std::vector<double> f(LeafT::SIZE);
    for (std::size_t l = range.begin(); l != range.end(); ++l) {
      if (progress.stopped()) return;
      auto leaf = std::make_unique<LeafT>(origins[l], background, false);
      for (openvdb::Index n = 0; n < LeafT::SIZE; ++n) {
        points[n] = lattice.at(leaf->offsetToGlobalCoord(n));
      }
      candidates.programs[l].values(points, f);
      for (openvdb::Index n = 0; n < LeafT::SIZE; ++n) {
        const double value = -f[n];
        if (std::abs(value) < background) {
          leaf->setValueOn(n, static_cast<float>(value));
        } else {
          leaf->setValueOff(n, value > 0.0 ? background : -background);
        }
      }
      if (!leaf->isEmpty()) leaves[l] = std::move(leaf);
      progress.advance(1);
    }
  });
  progress.check();
  openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(background);
  for (std::size_t l = 0; l < leaves.size(); ++l) {
    if (!leaves[l]) continue;
    grid->tree().addLeaf(leaves[l].release());
    near.add(origins[l], std::move(candidates.programs[l]));
  }
  candidates = {};
  openvdb::tools::signedFloodFill(grid->tree());
  grid->setGridClass(openvdb::GRID_LEVEL_SET);
  // Index ijk maps to gridOrigin + h * ijk: the mesher's single-precision
  // points are then relative to gridOrigin, which keeps them accurate for
  // parts far from the world origin.
  auto transform = openvdb::math::Transform::createLinearTransform(lattice.voxelSize);
  transform->postTranslate(openvdb::Vec3d(lattice.origin.x() - gridOrigin.x(),
                                          lattice.origin.y() - gridOrigin.y(),
                                          lattice.origin.z() - gridOrigin.z()));
  grid->setTransform(transform);
  return grid;
}

// Zero of f on the segment a-b, where f(a) and f(b) lie on either side of
// the surface (Illinois variant of regula falsi: a few steps are enough for
// the piecewise-smooth distance fields of CSG trees). Stops when |f| is
// within `tolerance`.
Vec3 edgeCrossing(const NearField& field, Vec3 a, double fa, Vec3 b, double fb, double tolerance) {
  constexpr int kMaxSteps = 8;
  Vec3 x = a;
  int lastSide = 0;
  for (int step = 0; step < kMaxSteps; ++step) {
    const double t = fa / (fa - fb);
    x = a + t * (b - a);
    const double fx = field.value(x);
    if (std::abs(fx) <= tolerance) return x;
    if ((fx > 0.0) == (fa > 0.0)) {
      a = x;
      fa = fx;
      if (lastSide == -1) fb *= 0.5;
      lastSide = -1;
    } else {
      b = x;
      fb = fx;
      if (lastSide == 1) fa *= 0.5;
      lastSide = 1;
    }
  }
  return x;
}

// Dual contouring: the point that best fits the tangent planes of the
// surface where it crosses the edges of the cell of voxel `cell` (least
// squares, with near-singular directions pinned to the mass point of the
// crossings). The fit falls back to the mass point when it leaves the cell
// grown by half a voxel. Returns false when no edge of the cell is crossed.
template <class Accessor>
bool sharpPoint(const NearField& field, const Lattice& lattice, const Accessor& levelSet,
                const openvdb::Coord& cell, Vec3& result) {
  const double h = lattice.voxelSize;
  // Corner c has offset (c & 1, (c >> 1) & 1, (c >> 2) & 1); the grid holds -f.
  std::array<double, 8> f;
  std::array<Vec3, 8> corner;
  for (int c = 0; c < 8; ++c) {
    const openvdb::Coord ijk = cell.offsetBy(c & 1, (c >> 1) & 1, (c >> 2) & 1);
    corner[c] = lattice.at(ijk);
    f[c] = -static_cast<double>(levelSet.getValue(ijk));
  }
  static constexpr std::array<std::array<int, 2>, 12> kEdges = {{{0, 1},
                                                                 {2, 3},
                                                                 {4, 5},
                                                                 {6, 7},
                                                                 {0, 2},
                                                                 {1, 3},
                                                                 {4, 6},
                                                                 {5, 7},
                                                                 {0, 4},
                                                                 {1, 5},
                                                                 {2, 6},
                                                                 {3, 7}}};
  Mat3 ata = Mat3::Zero();
  Vec3 atb = Vec3::Zero();
  Vec3 mass = Vec3::Zero();
  int count = 0;
  for (const auto& [i, j] : kEdges) {
    if ((f[i] > 0.0) == (f[j] > 0.0)) continue;
    const Vec3 p = edgeCrossing(field, corner[i], f[i], corner[j], f[j], kCrossingTolerance * h);
    // The gradient is taken a hair inside the solid: a few primitives give
    // unreliable directions within rounding error outside their surface.
    const Vec3 inward = (f[i] > 0.0 ? corner[i] : corner[j]) - p;
    const double reach = inward.norm();
    const Vec3 probe =
        reach > 0.0 ? Vec3(p + std::min(kGradientProbe * h, 0.5 * reach) / reach * inward) : p;
    const Vec3 g = field.evaluate(probe).gradient;
    const double length = g.norm();
    if (!(length > 0.0)) continue;
    const Vec3 n = g / length;
    ata += n * n.transpose();
    atb += n * n.dot(p);
    mass += p;
    ++count;
  }
  if (count == 0) return false;
  mass /= count;
  // Solve for x = mass + d, keeping only well-determined directions.
  const Eigen::SelfAdjointEigenSolver<Mat3> eigen(ata);
  const Vec3& lambda = eigen.eigenvalues();
  const Mat3& v = eigen.eigenvectors();
  const Vec3 rhs = v.transpose() * (atb - ata * mass);
  Vec3 d = Vec3::Zero();
  for (int k = 0; k < 3; ++k) {
    if (lambda[k] > kSingularCutoff * lambda.maxCoeff()) d += v.col(k) * (rhs[k] / lambda[k]);
  }
  const Vec3 x = mass + d;
  const Vec3 local = (x - corner[0]) / h;  // position in the cell, 0..1 inside
  const bool inCell = (local.array() >= -0.5).all() && (local.array() <= 1.5).all();
  result = inCell ? x : mass;
  return true;
}

// Moves every vertex that is alone in its cell to its dual-contouring point.
// A cell with several vertices holds several sheets of surface: its vertices
// keep OpenVDB's positions.
void sharpenVertices(const NearField& field, const Lattice& lattice, const openvdb::FloatGrid& grid,
                     std::vector<Vec3>& vertices) {
  const auto cellOf = [&](const Vec3& p) {
    const Vec3 u = ((p - lattice.origin) / lattice.voxelSize).array().floor();
    return openvdb::Coord(static_cast<int>(u.x()), static_cast<int>(u.y()),
                          static_cast<int>(u.z()));
  };
  // (cell key, vertex) sorted by cell; cell indices are below 2^21.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> cells(vertices.size());
  for (std::size_t v = 0; v < vertices.size(); ++v) {
    const openvdb::Coord c = cellOf(vertices[v]);
    std::uint64_t key = 0;
    for (int k = 0; k < 3; ++k) key = (key << 21) | (static_cast<std::uint64_t>(c[k]) & 0x1fffffu);
    cells[v] = {key, static_cast<std::uint32_t>(v)};
  }
  tbb::parallel_sort(cells.begin(), cells.end());  // distinct pairs: one order
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cells.size()), [&](const auto& range) {
    const auto levelSet = grid.getConstUnsafeAccessor();  // read-only: safe to share the tree
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const bool alone = (i == 0 || cells[i - 1].first != cells[i].first) &&
                         (i + 1 == cells.size() || cells[i + 1].first != cells[i].first);
      if (!alone) continue;
      Vec3& vertex = vertices[cells[i].second];
      Vec3 sharp;
      if (sharpPoint(field, lattice, levelSet, cellOf(vertex), sharp)) vertex = sharp;
    }
  });
}

// Adds the triangle a b c unless two of its corners coincide.
void addTriangle(TriangleMesh& mesh, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  if (a == b || b == c || c == a) return;
  mesh.triangles.push_back({a, b, c});
}

}  // namespace

TriangleMesh meshTree(const CsgTree& tree, const MeshOptions& options, const RunControl& control) {
  validate(tree, options);
  openvdb::initialize();
  Progress progress(control);

  const Aabb bounds = tree.bounds();
  Lattice lattice;
  lattice.voxelSize = bounds.size().maxCoeff() / options.resolution;
  requireMeshable(tree, bounds, lattice.voxelSize, options.resolution);
  // Half a voxel of offset keeps faces at the bounds (axis-aligned box faces)
  // between samples rather than on them.
  lattice.origin = bounds.min - Vec3::Constant((kMarginVoxels + 0.5) * lattice.voxelSize);
  openvdb::Coord dims;
  for (int k = 0; k < 3; ++k) {
    dims[k] =
        static_cast<int>(std::ceil(bounds.size()[k] / lattice.voxelSize)) + 2 * kMarginVoxels + 2;
  }

  // The peak memory is about proportional to the number of sampled leaves.
  const auto maxLeaves =
      static_cast<std::size_t>(options.memoryLimitMiB * 1024.0 * 1024.0 / kBytesPerLeaf);
  std::optional<Candidates> candidates =
      candidateLeaves(TreeProgram(tree), lattice, dims, maxLeaves, progress);
  if (!candidates) {
    throw std::invalid_argument("meshTree: resolution " + std::to_string(options.resolution) +
                                " would need more than memoryLimitMiB = " +
                                std::to_string(static_cast<long long>(options.memoryLimitMiB)) +
                                " MiB for this tree; lower the resolution or raise the limit");
  }

  const Vec3 gridOrigin = bounds.center();
  NearField field(tree, lattice);
  openvdb::FloatGrid::Ptr grid = sampleLevelSet(*candidates, lattice, gridOrigin, field, progress);

  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  progress.stage("polygonise", 1);
  openvdb::tools::volumeToMesh(*grid, points, triangles, quads, 0.0, options.adaptivity);
  progress.advance(1);
  progress.check();

  TriangleMesh mesh;
  mesh.vertices.reserve(points.size());
  for (const openvdb::Vec3s& p : points) {
    mesh.vertices.push_back(gridOrigin + Vec3(p.x(), p.y(), p.z()));
  }
  points = {};
  const bool sharpen = options.sharpenEdges && options.adaptivity == 0.0;
  if (sharpen) {
    progress.stage("sharpen", 1);
    sharpenVertices(field, lattice, *grid, mesh.vertices);
    progress.advance(1);
    progress.check();
  }
  grid.reset();

  // Split each quad along the diagonal whose midpoint lies closer to the
  // surface (it follows sharp edges); the shorter one on a tie.
  std::vector<char> splitAlong02(quads.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, quads.size()), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const openvdb::Vec4I& q = quads[i];
      const Vec3 &a = mesh.vertices[q[0]], &b = mesh.vertices[q[1]], &c = mesh.vertices[q[2]],
                 &d = mesh.vertices[q[3]];
      const double off02 = sharpen ? std::abs(field.value(0.5 * (a + c))) : 0.0;
      const double off13 = sharpen ? std::abs(field.value(0.5 * (b + d))) : 0.0;
      splitAlong02[i] =
          off02 < off13 || (off02 == off13 && (a - c).squaredNorm() <= (b - d).squaredNorm());
    }
  });
  // OpenVDB winds its polygons clockwise seen from outside: reverse them.
  mesh.triangles.reserve(triangles.size() + 2 * quads.size());
  for (const openvdb::Vec3I& t : triangles) addTriangle(mesh, t[0], t[2], t[1]);
  for (std::size_t i = 0; i < quads.size(); ++i) {
    const openvdb::Vec4I& q = quads[i];
    if (splitAlong02[i]) {
      addTriangle(mesh, q[0], q[2], q[1]);
      addTriangle(mesh, q[0], q[3], q[2]);
    } else {
      addTriangle(mesh, q[1], q[0], q[3]);
      addTriangle(mesh, q[1], q[3], q[2]);
    }
  }
  return mesh;
}

}  // namespace csgvox

#include "mesh/mesh_export.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

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

// The voxel lattice: voxel ijk samples the point origin + voxelSize * ijk.
struct Lattice {
  Vec3 origin;
  double voxelSize = 1.0;
  Vec3 at(const openvdb::Coord& ijk) const {
    return origin + voxelSize * Vec3(ijk.x(), ijk.y(), ijk.z());
  }
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

// Origins of the leaves that may hold a voxel with |f| < band. The field is
// 1-Lipschitz, so a block whose centre value exceeds its half diagonal plus
// the band holds no such voxel. Blocks of 8^3 leaves are culled first.
// Gives up (nullopt) as soon as more than `maxLeaves` leaves are found.
std::optional<std::vector<openvdb::Coord>> candidateLeaves(const CsgTree& tree,
                                                           const Lattice& lattice,
                                                           const openvdb::Coord& dims,
                                                           std::size_t maxLeaves) {
  const double h = lattice.voxelSize;
  const double band = kBandVoxels * h;
  const auto halfDiagonal = [h](int voxels) { return 0.5 * (voxels - 1) * std::sqrt(3.0) * h; };
  const auto centreOf = [&](const openvdb::Coord& origin, int voxels) {
    const double half = 0.5 * (voxels - 1);
    return Vec3(lattice.at(origin) + Vec3::Constant(half * h));
  };
  const int bx = (dims.x() + kBlockDim - 1) / kBlockDim;
  const int by = (dims.y() + kBlockDim - 1) / kBlockDim;
  const int bz = (dims.z() + kBlockDim - 1) / kBlockDim;
  const std::size_t blockCount = std::size_t(bx) * by * bz;
  std::vector<std::vector<openvdb::Coord>> perBlock(blockCount);
  std::atomic<std::size_t> found{0};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blockCount), [&](const auto& range) {
    for (std::size_t b = range.begin(); b != range.end(); ++b) {
      if (found.load(std::memory_order_relaxed) > maxLeaves) return;
      const int i = static_cast<int>(b % bx), j = static_cast<int>((b / bx) % by),
                k = static_cast<int>(b / (std::size_t(bx) * by));
      const openvdb::Coord blockOrigin(i * kBlockDim, j * kBlockDim, k * kBlockDim);
      const double fBlock = tree.value(centreOf(blockOrigin, kBlockDim));
      if (std::abs(fBlock) >= halfDiagonal(kBlockDim) + band) continue;
      for (int z = 0; z < kBlockDim; z += kLeafDim) {
        for (int y = 0; y < kBlockDim; y += kLeafDim) {
          for (int x = 0; x < kBlockDim; x += kLeafDim) {
            const openvdb::Coord leafOrigin = blockOrigin.offsetBy(x, y, z);
            const double fLeaf = tree.value(centreOf(leafOrigin, kLeafDim));
            if (std::abs(fLeaf) < halfDiagonal(kLeafDim) + band) perBlock[b].push_back(leafOrigin);
          }
        }
      }
      found += perBlock[b].size();
    }
  });
  if (found > maxLeaves) return std::nullopt;
  std::vector<openvdb::Coord> leaves;
  for (const auto& v : perBlock) leaves.insert(leaves.end(), v.begin(), v.end());
  return leaves;
}

// Samples -f (OpenVDB level sets are negative inside) on the candidate leaves;
// voxels with |f| < band are active, the others hold +-background. Leaves
// without an active voxel are dropped: signedFloodFill restores their sign.
openvdb::FloatGrid::Ptr sampleLevelSet(const CsgTree& tree, const Lattice& lattice,
                                       const std::vector<openvdb::Coord>& origins,
                                       const Vec3& gridOrigin) {
  const float background = static_cast<float>(kBandVoxels * lattice.voxelSize);
  std::vector<std::unique_ptr<LeafT>> leaves(origins.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, origins.size()), [&](const auto& range) {
    for (std::size_t l = range.begin(); l != range.end(); ++l) {
      auto leaf = std::make_unique<LeafT>(origins[l], background, false);
      for (openvdb::Index n = 0; n < LeafT::SIZE; ++n) {
        const double value = -tree.value(lattice.at(leaf->offsetToGlobalCoord(n)));
        if (std::abs(value) < background) {
          leaf->setValueOn(n, static_cast<float>(value));
        } else {
          leaf->setValueOff(n, value > 0.0 ? background : -background);
        }
      }
      if (!leaf->isEmpty()) leaves[l] = std::move(leaf);
    }
  });
  openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(background);
  for (auto& leaf : leaves) {
    if (leaf) grid->tree().addLeaf(leaf.release());
  }
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
Vec3 edgeCrossing(const CsgTree& tree, Vec3 a, double fa, Vec3 b, double fb, double tolerance) {
  constexpr int kMaxSteps = 8;
  Vec3 x = a;
  int lastSide = 0;
  for (int step = 0; step < kMaxSteps; ++step) {
    const double t = fa / (fa - fb);
    x = a + t * (b - a);
    const double fx = tree.value(x);
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
bool sharpPoint(const CsgTree& tree, const Lattice& lattice, const Accessor& levelSet,
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
    const Vec3 p = edgeCrossing(tree, corner[i], f[i], corner[j], f[j], kCrossingTolerance * h);
    // The gradient is taken a hair inside the solid: a few primitives give
    // unreliable directions within rounding error outside their surface.
    const Vec3 inward = (f[i] > 0.0 ? corner[i] : corner[j]) - p;
    const double reach = inward.norm();
    const Vec3 probe =
        reach > 0.0 ? Vec3(p + std::min(kGradientProbe * h, 0.5 * reach) / reach * inward) : p;
    const Vec3 g = tree.evaluate(probe).gradient;
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
void sharpenVertices(const CsgTree& tree, const Lattice& lattice, const openvdb::FloatGrid& grid,
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
  std::sort(cells.begin(), cells.end());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cells.size()), [&](const auto& range) {
    const auto levelSet = grid.getConstUnsafeAccessor();  // read-only: safe to share the tree
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const bool alone = (i == 0 || cells[i - 1].first != cells[i].first) &&
                         (i + 1 == cells.size() || cells[i + 1].first != cells[i].first);
      if (!alone) continue;
      Vec3& vertex = vertices[cells[i].second];
      Vec3 sharp;
      if (sharpPoint(tree, lattice, levelSet, cellOf(vertex), sharp)) vertex = sharp;
    }
  });
}

// Adds the triangle a b c unless two of its corners coincide.
void addTriangle(TriangleMesh& mesh, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  if (a == b || b == c || c == a) return;
  mesh.triangles.push_back({a, b, c});
}

}  // namespace

TriangleMesh meshTree(const CsgTree& tree, const MeshOptions& options) {
  validate(tree, options);
  openvdb::initialize();

  const Aabb bounds = tree.bounds();
  Lattice lattice;
  lattice.voxelSize = bounds.size().maxCoeff() / options.resolution;
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
  const std::optional<std::vector<openvdb::Coord>> origins =
      candidateLeaves(tree, lattice, dims, maxLeaves);
  if (!origins) {
    throw std::invalid_argument("meshTree: resolution " + std::to_string(options.resolution) +
                                " would need more than memoryLimitMiB = " +
                                std::to_string(static_cast<long long>(options.memoryLimitMiB)) +
                                " MiB for this tree; lower the resolution or raise the limit");
  }

  const Vec3 gridOrigin = bounds.center();
  openvdb::FloatGrid::Ptr grid = sampleLevelSet(tree, lattice, *origins, gridOrigin);

  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(*grid, points, triangles, quads, 0.0, options.adaptivity);

  TriangleMesh mesh;
  mesh.vertices.reserve(points.size());
  for (const openvdb::Vec3s& p : points) {
    mesh.vertices.push_back(gridOrigin + Vec3(p.x(), p.y(), p.z()));
  }
  points = {};
  const bool sharpen = options.sharpenEdges && options.adaptivity == 0.0;
  if (sharpen) sharpenVertices(tree, lattice, *grid, mesh.vertices);
  grid.reset();

  // Split each quad along the diagonal whose midpoint lies closer to the
  // surface (it follows sharp edges); the shorter one on a tie.
  std::vector<char> splitAlong02(quads.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, quads.size()), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const openvdb::Vec4I& q = quads[i];
      const Vec3 &a = mesh.vertices[q[0]], &b = mesh.vertices[q[1]], &c = mesh.vertices[q[2]],
                 &d = mesh.vertices[q[3]];
      const double off02 = sharpen ? std::abs(tree.value(0.5 * (a + c))) : 0.0;
      const double off13 = sharpen ? std::abs(tree.value(0.5 * (b + d))) : 0.0;
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

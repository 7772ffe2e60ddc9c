#include "mesh/mesh_solid.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/MeshToVolume.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace csgvox {
namespace {

constexpr double kMaxVoxelsPerAxis = 4096.0;
constexpr float kBandVoxels =
    2.0f;  // narrow-band half width, voxels (wider is slower, no more exact)

// Feeds the mesh to meshToVolume in index space, converted in double
// precision (the world-space float overloads lose digits far from the origin).
class IndexSpaceMesh {
 public:
  IndexSpaceMesh(const TriangleMesh& mesh, const Vec3& origin, double voxelSize)
      : mesh_(mesh), origin_(origin), scale_(1.0 / voxelSize) {}
  std::size_t polygonCount() const { return mesh_.triangles.size(); }
  std::size_t pointCount() const { return mesh_.vertices.size(); }
  std::size_t vertexCount(std::size_t) const { return 3; }
  void getIndexSpacePoint(std::size_t n, std::size_t v, openvdb::Vec3d& pos) const {
    const Vec3 p = (mesh_.vertices[mesh_.triangles[n][v]] - origin_) * scale_;
    pos = openvdb::Vec3d(p.x(), p.y(), p.z());
  }

 private:
  const TriangleMesh& mesh_;
  Vec3 origin_;
  double scale_;
};

// Number of edges used by an odd number of triangles (0 for a closed mesh).
std::size_t countBoundaryEdges(const TriangleMesh& mesh) {
  std::vector<std::uint64_t> edges;
  edges.reserve(3 * mesh.triangles.size());
  for (const auto& t : mesh.triangles) {
    for (int i = 0; i < 3; ++i) {
      const std::uint64_t a = t[i], b = t[(i + 1) % 3];
      if (a != b) edges.push_back(std::min(a, b) << 32 | std::max(a, b));
    }
  }
  std::sort(edges.begin(), edges.end());
  std::size_t boundary = 0;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    boundary += (j - i) % 2;
    i = j;
  }
  return boundary;
}

}  // namespace

struct MeshSolid::Impl {
  openvdb::FloatGrid::Ptr grid;  // level set in index space: negative inside
  Vec3 origin;                   // world position of voxel (0, 0, 0)
  double voxelSize = 1.0;
  Aabb bounds;
};

MeshSolid::MeshSolid(const TriangleMesh& mesh, double voxelSize) {
  if (!(voxelSize > 0.0) || !std::isfinite(voxelSize)) {
    throw std::invalid_argument("MeshSolid: voxelSize must be finite and > 0");
  }
  if (mesh.triangles.empty()) throw std::invalid_argument("MeshSolid: the mesh has no triangles");
  for (const auto& t : mesh.triangles) {
    if (std::max({t[0], t[1], t[2]}) >= mesh.vertices.size()) {
      throw std::invalid_argument("MeshSolid: a triangle index is out of range");
    }
  }
  const Aabb bounds = mesh.bounds();
  if (!bounds.isBounded()) throw std::invalid_argument("MeshSolid: a vertex is not finite");
  if (bounds.size().maxCoeff() / voxelSize > kMaxVoxelsPerAxis) {
    throw std::invalid_argument("MeshSolid: the mesh spans more than " +
                                std::to_string(static_cast<int>(kMaxVoxelsPerAxis)) +
                                " voxels along an axis; use a larger voxelSize");
  }
  if (const std::size_t open = countBoundaryEdges(mesh); open > 0) {
    throw std::invalid_argument("MeshSolid: the mesh is not closed (" + std::to_string(open) +
                                " boundary edges)");
  }

  openvdb::initialize();
  auto impl = std::make_shared<Impl>();
  impl->origin = bounds.min;
  impl->voxelSize = voxelSize;
  impl->bounds = bounds;
  // The grid lives in index space (unit voxels); world points are converted
  // in double precision by IndexSpaceMesh and contains().
  const openvdb::math::Transform::Ptr identity =
      openvdb::math::Transform::createLinearTransform(1.0);
  impl->grid = openvdb::tools::meshToVolume<openvdb::FloatGrid>(
      IndexSpaceMesh(mesh, impl->origin, voxelSize), *identity, kBandVoxels, kBandVoxels);
  impl_ = std::move(impl);
}

bool MeshSolid::contains(const Vec3& p) const {
  if (!impl_->bounds.contains(p)) return false;
  const Vec3 ijk = (p - impl_->origin) / impl_->voxelSize;
  const auto accessor = impl_->grid->getConstUnsafeAccessor();
  const float value =
      openvdb::tools::BoxSampler::sample(accessor, openvdb::Vec3R(ijk.x(), ijk.y(), ijk.z()));
  return value <= 0.0f;
}

double MeshSolid::voxelSize() const { return impl_->voxelSize; }

Aabb MeshSolid::bounds() const { return impl_->bounds; }

}  // namespace csgvox

#include "voxel/labeling.h"

#include "primitives/nearest_neighbors.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>
#include <stdexcept>
#include <string>

namespace csgvox {
namespace {

VoxelSet occupiedVoxels(const VoxelGrid& grid, const PointCloud& scan) {
  VoxelSet occ(grid.voxelCount());
  const auto& d = grid.dims();
  for (const Vec3& p : scan.points) {
    const Vec3 g = grid.toGrid(p);
    const int i = int(std::floor(g.x())), j = int(std::floor(g.y())), k = int(std::floor(g.z()));
    if (i >= 0 && j >= 0 && k >= 0 && i < d[0] && j < d[1] && k < d[2]) occ.set(grid.index(i, j, k));
  }
  return occ;
}

// Wu et al. §4.1: outside when more than epsilon of the K nearest points
// have normals pointing towards the voxel centre.
std::vector<char> normalVote(const VoxelGrid& grid, const PointCloud& scan,
                             const LabelOptions& o) {
  const NearestNeighbors index(scan.points);
  std::vector<char> inside(grid.voxelCount(), 0);
  const std::size_t k = std::size_t(std::max(1, o.neighbors));
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, inside.size(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      std::vector<std::uint32_t> near;
                      for (std::size_t v = r.begin(); v != r.end(); ++v) {
                        const Vec3 c = grid.center(v);
                        index.kNearest(c, k, near);
                        std::size_t facing = 0;
                        for (std::uint32_t i : near) {
                          facing += scan.normals[i].dot(c - scan.points[i]) > 0.0;
                        }
                        inside[v] = !(double(facing) > o.epsilon * double(near.size()));
                      }
                    });
  return inside;
}

// Octree of oriented, area-weighted points for the Barnes-Hut winding number.
class DipoleTree {
 public:
  DipoleTree(const PointCloud& scan, std::vector<double> areas)
      : points_(scan.points), normals_(scan.normals), areas_(std::move(areas)) {
    order_.resize(points_.size());
    std::iota(order_.begin(), order_.end(), 0u);
    nodes_.reserve(2 * points_.size() / kLeafSize + 16);
    build(0, std::uint32_t(order_.size()));
  }

  double winding(const Vec3& q, double ratio) const {
    double w = 0.0;
    std::uint32_t stack[1024];  // depth <= 64 (halving doubles) times 8 children
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes_[stack[--top]];
      const Vec3 d = n.center - q;
      const double dist2 = d.squaredNorm();
      if (dist2 > ratio * ratio * n.radius * n.radius) {
        w += n.dipole.dot(d) / (dist2 * std::sqrt(dist2));
      } else if (n.childCount == 0) {
        for (std::uint32_t i = n.begin; i < n.end; ++i) {
          const std::uint32_t p = order_[i];
          const Vec3 e = points_[p] - q;
          const double l2 = e.squaredNorm();
          if (l2 > 0.0) w += areas_[p] * normals_[p].dot(e) / (l2 * std::sqrt(l2));
        }
      } else {
        for (std::uint32_t c = 0; c < n.childCount; ++c) {
          if (top < 1023) stack[top++] = n.children[c];
        }
      }
    }
    return w / (4.0 * std::numbers::pi);
  }

 private:
  static constexpr std::uint32_t kLeafSize = 16;
  struct Node {
    Vec3 center = Vec3::Zero();  // area-weighted centroid
    Vec3 dipole = Vec3::Zero();  // sum of area * normal
    double radius = 0.0;         // max distance of a point from the centroid
    std::uint32_t begin = 0, end = 0;
    std::array<std::uint32_t, 8> children{};
    std::uint32_t childCount = 0;
  };

  std::uint32_t build(std::uint32_t begin, std::uint32_t end) {
    const std::uint32_t id = std::uint32_t(nodes_.size());
    nodes_.emplace_back();
    Node n;
    n.begin = begin;
    n.end = end;
    double area = 0.0;
    Aabb box;
    for (std::uint32_t i = begin; i < end; ++i) {
      const std::uint32_t p = order_[i];
      n.center += areas_[p] * points_[p];
      n.dipole += areas_[p] * normals_[p];
      area += areas_[p];
      box.extend(points_[p]);
    }
    n.center = area > 0.0 ? Vec3(n.center / area) : box.center();
    for (std::uint32_t i = begin; i < end; ++i) {
      n.radius = std::max(n.radius, (points_[order_[i]] - n.center).norm());
    }
    if (end - begin > kLeafSize && box.diagonal() > 0.0) {
      // Split at the box centre into up to 8 octants.
      const Vec3 mid = box.center();
      std::array<std::vector<std::uint32_t>, 8> parts;
      for (std::uint32_t i = begin; i < end; ++i) {
        const Vec3& p = points_[order_[i]];
        parts[(p.x() > mid.x()) | ((p.y() > mid.y()) << 1) | ((p.z() > mid.z()) << 2)].push_back(
            order_[i]);
      }
      std::uint32_t pos = begin;
      std::vector<std::pair<std::uint32_t, std::uint32_t>> ranges;
      for (const auto& part : parts) {
        if (part.empty()) continue;
        std::copy(part.begin(), part.end(), order_.begin() + pos);
        ranges.emplace_back(pos, pos + std::uint32_t(part.size()));
        pos += std::uint32_t(part.size());
      }
      for (const auto& [b, e] : ranges) n.children[n.childCount++] = build(b, e);
    }
    nodes_[id] = n;
    return id;
  }

  const std::vector<Vec3>& points_;
  const std::vector<Vec3>& normals_;
  std::vector<double> areas_;
  std::vector<std::uint32_t> order_;
  std::vector<Node> nodes_;
};

// Area of the surface each point stands for: a disc reaching its k-th
// neighbour holds about k points.
std::vector<double> pointAreas(const PointCloud& scan, int k) {
  const NearestNeighbors index(scan.points);
  std::vector<double> areas(scan.size());
  const std::size_t kk = std::size_t(std::max(2, k)) + 1;  // the point itself comes first
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, scan.size(), 512),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      std::vector<std::uint32_t> near;
                      std::vector<double> d2;
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        index.kNearest(scan.points[i], kk, near, &d2);
                        areas[i] = std::numbers::pi * d2.back() / double(d2.size() - 1);
                      }
                    });
  return areas;
}

std::vector<char> windingNumber(const VoxelGrid& grid, const PointCloud& scan,
                                const LabelOptions& o) {
  const DipoleTree tree(scan, pointAreas(scan, o.areaNeighbors));
  std::vector<char> inside(grid.voxelCount(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, inside.size(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t v = r.begin(); v != r.end(); ++v) {
                        inside[v] = tree.winding(grid.center(v), o.farFieldRatio) >
                                    o.windingThreshold;
                      }
                    });
  return inside;
}

}  // namespace

VoxelLabels labelVoxels(const VoxelGrid& grid, const PointCloud& scan, const LabelOptions& o) {
  if (scan.empty()) throw std::invalid_argument("cannot label voxels from an empty scan");
  if (!scan.hasNormals()) throw std::invalid_argument("labelling voxels needs scan normals");
  const std::vector<char> in = o.method == LabelMethod::NormalVote ? normalVote(grid, scan, o)
                                                                    : windingNumber(grid, scan, o);
  VoxelLabels labels;
  labels.occupied = occupiedVoxels(grid, scan);
  labels.inside = labels.occupied;
  for (std::size_t v = 0; v < in.size(); ++v) {
    if (in[v]) labels.inside.set(v);
  }
  return labels;
}

std::string_view labelMethodName(LabelMethod method) {
  return method == LabelMethod::NormalVote ? "vote" : "winding";
}

LabelMethod labelMethodFromName(std::string_view name) {
  if (name == "vote") return LabelMethod::NormalVote;
  if (name == "winding") return LabelMethod::WindingNumber;
  throw std::invalid_argument("unknown labelling method '" + std::string(name) +
                              "' (use winding or vote)");
}

}  // namespace csgvox

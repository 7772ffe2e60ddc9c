#include "voxel/labeling.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>
#include <stdexcept>
#include <string>

#include "core/nearest_neighbors.h"

namespace csgvox {
namespace {

// Wu et al. §4.1: outside when more than epsilon of the K nearest points
// have normals pointing towards the point.
class NormalVote {
 public:
  NormalVote(const PointCloud& scan, const LabelOptions& o)
      : scan_(scan),
        index_(scan.points),
        k_(std::size_t(std::max(1, o.neighbors))),
        epsilon_(o.epsilon) {}

  bool inside(const Vec3& c, std::vector<std::uint32_t>& near) const {
    index_.kNearest(c, k_, near);
    std::size_t facing = 0;
    for (std::uint32_t i : near) facing += scan_.normals[i].dot(c - scan_.points[i]) > 0.0;
    return !(double(facing) > epsilon_ * double(near.size()));
  }

 private:
  const PointCloud& scan_;
  NearestNeighbors index_;
  std::size_t k_;
  double epsilon_;
};

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

// Area of the surface each point stands for: a disc reaching the k-th
// neighbour holds about k points. Noise of deviation σ across the surface
// spreads the points into a shell, and a ball of radius R then holds about
// ρπ(R² − 2σ²) of them (ρ the points per area): it must reach farther for
// its k points, inflating the area, and with it the winding number, whose
// 0.5 level then lies outside the surface (on a rod 4 voxels thick, a ring
// of voxels too many). Where that inflation would reach 5 % (2σ² ≥ 0.05 R²),
// the disc is also measured in the point's tangent plane, to the k-th of
// its 4k nearest points on the same side of the surface, and the smaller of
// the two is taken (the ball stays smaller where an edge's other face is
// near). A clean scan keeps the ball.
//
// The points of a thin wall's other side (facing more than 120 degrees away,
// and behind the point by more than three noise deviations) never count
// towards the ball: when the k nearest hold one, the disc reaches to the k-th
// of the 4k nearest that do not. (A point facing against its neighbours in
// their own surface, flipped or stray, has them beside it, not behind; one
// with fewer than k/2 points of its side among the 4k keeps the ball, lest
// a stray point stand for a wide disc.) Counted, they shrink the discs
// of the sparser side most (a scanner sees a tray's inner faces less densely
// than its outer ones: 19 800 points, k = 10, the inner faces' areas came to
// half their true size, the outer ones' to 0.93), and the winding number
// inside the pocket rose to 0.3, filling a tenth of it.
std::vector<double> pointAreas(const PointCloud& scan, int k, double noise) {
  constexpr double kOpposite = -0.5;  // cos 120 degrees
  const double behind = 3.0 * noise;  // the other side lies behind the point, past the noise
  const NearestNeighbors index(scan.points);
  std::vector<double> areas(scan.size());
  const std::size_t want = std::size_t(std::max(2, k));
  const std::size_t kk = std::min(4 * want + 1, scan.size());  // the point itself comes first
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, scan.size(), 512),
      [&](const tbb::blocked_range<std::size_t>& r) {
        std::vector<std::uint32_t> near;
        std::vector<double> d2, t2;
        // Whether the last point needed its tangent disc: on a noisy scan
        // nearly all do, and the wide query then also gives the ball.
        bool wide = false;
        for (std::size_t at = r.begin(); at != r.end(); ++at) {
          const std::size_t i = index.order()[at];  // neighbours together: cache-friendly
          const Vec3& n = scan.normals[i];
          index.kNearest(scan.points[i], wide ? kk : std::min(want + 1, scan.size()), near, &d2);
          const auto opposite = [&](std::size_t j) {
            return scan.normals[near[j]].dot(n) < kOpposite &&
                   (scan.points[near[j]] - scan.points[i]).dot(n) < -behind;
          };
          std::size_t m = std::min(want, near.size() - 1);
          bool across = false;
          for (std::size_t j = 1; j <= m && !across; ++j) across = opposite(j);
          if (across && near.size() < kk) {
            index.kNearest(scan.points[i], kk, near, &d2);
            m = std::min(want, near.size() - 1);
          }
          // The k-th neighbour, the other side of a thin wall skipped; a
          // point with fewer than k/2 of its own side among the 4k nearest
          // is a stray one and keeps the ball.
          std::size_t kth = m;
          if (across) {
            std::size_t count = 0, last = m;
            for (std::size_t j = 1; j < near.size() && count < m; ++j) {
              if (opposite(j)) continue;
              last = j;
              ++count;
            }
            if (2 * count >= want) {
              kth = last;
              m = count;
            }
          }
          const double ball = m > 0 ? std::numbers::pi * d2[kth] / double(m) : 0.0;
          areas[i] = ball;
          wide = m > 0 && 2.0 * noise * noise >= 0.05 * d2[kth];
          if (!wide) continue;
          if (near.size() < kk) index.kNearest(scan.points[i], kk, near, &d2);
          t2.clear();
          for (std::size_t j = 1; j < near.size(); ++j) {
            if (scan.normals[near[j]].dot(n) <= 0.0) continue;
            const Vec3 e = scan.points[near[j]] - scan.points[i];
            const double across = e.dot(n);
            t2.push_back(std::max(e.squaredNorm() - across * across, 0.0));
          }
          if (t2.size() < want) continue;
          std::nth_element(t2.begin(), t2.begin() + std::ptrdiff_t(want - 1), t2.end());
          areas[i] = std::min(ball, std::numbers::pi * t2[want - 1] / double(want));
        }
      });
  return areas;
}

// Inside when the winding number exceeds the threshold.
class WindingNumber {
 public:
  WindingNumber(const PointCloud& scan, const LabelOptions& o)
      : tree_(scan, pointAreas(scan, o.areaNeighbors, o.noise)),
        ratio_(o.farFieldRatio),
        threshold_(o.windingThreshold) {}

  bool inside(const Vec3& q, std::vector<std::uint32_t>& /*scratch*/) const {
    return tree_.winding(q, ratio_) > threshold_;
  }

 private:
  DipoleTree tree_;
  double ratio_;
  double threshold_;
};

// Occupied voxels whose centre is outside but whose points bound material
// that no voxel centre falls in: a wall thinner than a voxel, lying between
// two layers of centres. The points of such a voxel are grouped by normal
// (one group per side of a wall). A group's material is caught when a voxel
// up to 2.5 voxels behind its mean point (against its mean normal) has its
// centre inside: a thick solid, or a wall seen by the next layer of centres.
// Otherwise the voxel stays inside when the rule finds material a quarter or
// half a voxel behind the surface.
template <class Rule>
std::vector<std::size_t> thinWallVoxels(const VoxelGrid& grid, const PointCloud& scan,
                                        const std::vector<char>& in, const Rule& rule) {
  std::vector<std::pair<std::size_t, std::uint32_t>> byVoxel;  // (voxel, point)
  byVoxel.reserve(scan.size());
  for (std::uint32_t i = 0; i < scan.size(); ++i) {
    const std::size_t v = grid.voxelOf(scan.points[i]);
    if (v != VoxelGrid::npos && !in[v]) byVoxel.emplace_back(v, i);
  }
  std::sort(byVoxel.begin(), byVoxel.end());
  std::vector<std::size_t> starts;
  for (std::size_t a = 0; a < byVoxel.size(); ++a) {
    if (a == 0 || byVoxel[a].first != byVoxel[a - 1].first) starts.push_back(a);
  }
  starts.push_back(byVoxel.size());
  const double h = grid.voxelSize();
  std::vector<char> keep(starts.size() - 1, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, keep.size(), 64),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      std::vector<std::uint32_t> scratch;
                      std::vector<char> done;
                      for (std::size_t g = r.begin(); g != r.end(); ++g) {
                        const std::size_t b = starts[g], e = starts[g + 1], v = byVoxel[b].first;
                        done.assign(e - b, 0);
                        for (std::size_t a = b; a < e && !keep[g]; ++a) {
                          if (done[a - b]) continue;
                          // The points facing like point a: one side of a wall.
                          const Vec3& n0 = scan.normals[byVoxel[a].second];
                          Vec3 p = Vec3::Zero(), n = Vec3::Zero();
                          int count = 0;
                          for (std::size_t c = a; c < e; ++c) {
                            const std::uint32_t i = byVoxel[c].second;
                            if (done[c - b] || scan.normals[i].dot(n0) < 0.5) continue;
                            done[c - b] = 1;
                            p += scan.points[i];
                            n += scan.normals[i];
                            ++count;
                          }
                          p /= double(count);
                          if (n.norm() == 0.0) continue;
                          n.normalize();
                          bool caught = false;
                          for (double s : {0.5, 1.0, 1.5, 2.0, 2.5}) {
                            const std::size_t w = grid.voxelOf(p - s * h * n);
                            caught = caught || (w != VoxelGrid::npos && w != v && in[w]);
                          }
                          if (caught) continue;
                          for (double s : {0.25, 0.5}) {
                            if (rule.inside(p - s * h * n, scratch)) {
                              keep[g] = 1;
                              break;
                            }
                          }
                        }
                      }
                    });
  std::vector<std::size_t> kept;
  for (std::size_t g = 0; g < keep.size(); ++g) {
    if (keep[g]) kept.push_back(byVoxel[starts[g]].first);
  }
  return kept;
}

template <class Rule>
VoxelLabels label(const VoxelGrid& grid, const PointCloud& scan, const LabelOptions& o) {
  const Rule rule(scan, o);
  std::vector<char> in(grid.voxelCount(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, in.size(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      // A cancelled run's labels are not used.
                      if (o.control.cancelled()) return;
                      std::vector<std::uint32_t> scratch;
                      for (std::size_t v = r.begin(); v != r.end(); ++v) {
                        in[v] = rule.inside(grid.center(v), scratch);
                      }
                    });
  VoxelLabels labels;
  labels.occupied = VoxelSet(grid.voxelCount());
  for (const Vec3& p : scan.points) {
    const std::size_t v = grid.voxelOf(p);
    if (v != VoxelGrid::npos) labels.occupied.set(v);
  }
  labels.inside = VoxelSet(grid.voxelCount());
  for (std::size_t v = 0; v < in.size(); ++v) {
    if (in[v]) labels.inside.set(v);
  }
  if (o.boundary == BoundaryRule::Inside) {
    labels.inside |= labels.occupied;
  } else if (o.keepThinWalls) {
    for (std::size_t v : thinWallVoxels(grid, scan, in, rule)) labels.inside.set(v);
  }
  return labels;
}

}  // namespace

VoxelLabels labelVoxels(const VoxelGrid& grid, const PointCloud& scan, const LabelOptions& o) {
  if (scan.empty()) throw std::invalid_argument("cannot label voxels from an empty scan");
  if (!scan.hasNormals()) throw std::invalid_argument("labelling voxels needs scan normals");
  return o.method == LabelMethod::NormalVote ? label<NormalVote>(grid, scan, o)
                                             : label<WindingNumber>(grid, scan, o);
}

std::string_view labelMethodName(LabelMethod method) {
  return nameOf<LabelMethod>(kLabelMethodNames, method);
}

LabelMethod labelMethodFromName(std::string_view name) {
  return valueNamed<LabelMethod>(kLabelMethodNames, name, "labelling method");
}

}  // namespace csgvox

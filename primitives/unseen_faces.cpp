#include "primitives/unseen_faces.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <tuple>
#include <vector>

#include "core/nearest_neighbors.h"
#include "core/union_find.h"

namespace csgvox {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;

// A hull facet: its corners, outward unit normal and planar region.
struct Facet {
  std::array<Vec3, 3> v;
  Vec3 normal;
  std::size_t region = 0;
};

// A planar region of the hull: adjacent facets within kRegionCosine of each
// other, with the edges it shares with other regions.
struct Region {
  Vec3 normal = Vec3::Zero();  // area-weighted, unit
  Vec3 e0, e1;                 // frameFromAxis(normal): the plane's lattice axes
  std::vector<std::pair<Vec3, Vec3>> boundary;
};

// cos(2 degrees): hull facets this close in direction are one face.
constexpr double kRegionCosine = 0.9993908270190958;

struct Hull {
  std::vector<Facet> facets;
  std::vector<Region> regions;
};

Hull convexHull(const std::vector<Vec3>& points) {
  using Mesh = CGAL::Surface_mesh<K::Point_3>;
  std::vector<K::Point_3> in;
  in.reserve(points.size());
  for (const Vec3& p : points) in.emplace_back(p.x(), p.y(), p.z());
  Mesh hull;
  CGAL::convex_hull_3(in.begin(), in.end(), hull);
  Hull out;
  if (hull.number_of_faces() < 4) return out;
  const auto at = [&](Mesh::Vertex_index v) {
    const K::Point_3& p = hull.point(v);
    return Vec3(p.x(), p.y(), p.z());
  };
  // CGAL numbers the hull's faces, and starts each at a corner, in an order
  // that follows memory addresses, which change from run to run; everything
  // below goes in the order of the faces' corners (each face from its
  // smallest corner), so its sums, the regions' numbers and the points
  // made from them are the same in every run.
  const auto lexLess = [](const Vec3& a, const Vec3& b) {
    return std::tie(a.x(), a.y(), a.z()) < std::tie(b.x(), b.y(), b.z());
  };
  std::vector<std::array<Vec3, 3>> corners(hull.number_of_faces());
  std::vector<char> triangle(hull.number_of_faces(), 0);
  for (const auto f : hull.faces()) {
    std::array<Vec3, 3>& c = corners[f.idx()];
    std::size_t k = 0;
    for (const auto h : CGAL::halfedges_around_face(hull.halfedge(f), hull)) {
      if (k < 3) c[k] = at(hull.target(h));
      ++k;
    }
    if (k != 3) continue;
    triangle[f.idx()] = 1;
    const std::size_t first =
        std::size_t(std::min_element(c.begin(), c.end(), lexLess) - c.begin());
    std::rotate(c.begin(), c.begin() + std::ptrdiff_t(first), c.end());
  }
  std::vector<std::size_t> rank(hull.number_of_faces());
  for (std::size_t f = 0; f < rank.size(); ++f) rank[f] = f;
  std::sort(rank.begin(), rank.end(), [&](std::size_t a, std::size_t b) {
    return std::lexicographical_compare(corners[a].begin(), corners[a].end(), corners[b].begin(),
                                        corners[b].end(), lexLess);
  });
  std::vector<std::size_t> faceAt(rank.size());  // CGAL's face index -> canonical position
  for (std::size_t r = 0; r < rank.size(); ++r) faceAt[rank[r]] = r;
  std::vector<Mesh::Vertex_index> sortedVertices(hull.vertices().begin(), hull.vertices().end());
  std::sort(sortedVertices.begin(), sortedVertices.end(),
            [&](Mesh::Vertex_index a, Mesh::Vertex_index b) { return lexLess(at(a), at(b)); });
  Vec3 centre = Vec3::Zero();
  for (const auto v : sortedVertices) centre += at(v);
  centre /= double(hull.number_of_vertices());
  // Facets in that order; a degenerate face has a zero normal and no region.
  std::vector<Facet> byFace(hull.number_of_faces());
  std::vector<double> area(hull.number_of_faces(), 0.0);
  std::vector<char> valid(hull.number_of_faces(), 0);
  for (std::size_t pos = 0; pos < rank.size(); ++pos) {
    if (!triangle[rank[pos]]) continue;
    Facet& facet = byFace[pos];
    facet.v = corners[rank[pos]];
    Vec3 n = (facet.v[1] - facet.v[0]).cross(facet.v[2] - facet.v[0]);
    const double len = n.norm();
    if (!(len > 0.0)) continue;
    n /= len;
    if (n.dot(facet.v[0] - centre) < 0.0) n = -n;
    facet.normal = n;
    area[pos] = 0.5 * len;
    valid[pos] = 1;
  }
  std::vector<std::size_t> parent(byFace.size());
  for (std::size_t i = 0; i < parent.size(); ++i) parent[i] = i;
  for (const auto e : hull.edges()) {
    const auto h = hull.halfedge(e);
    const std::size_t f = faceAt[hull.face(h).idx()];
    const std::size_t g = faceAt[hull.face(hull.opposite(h)).idx()];
    if (valid[f] && valid[g] && byFace[f].normal.dot(byFace[g].normal) >= kRegionCosine) {
      parent[findRoot(parent, f)] = findRoot(parent, g);
    }
  }
  std::vector<std::size_t> regionOf(byFace.size(), std::size_t(-1));
  for (std::size_t f = 0; f < byFace.size(); ++f) {
    if (!valid[f]) continue;
    std::size_t& r = regionOf[findRoot(parent, f)];
    if (r == std::size_t(-1)) r = out.regions.size(), out.regions.emplace_back();
    byFace[f].region = r;
    out.regions[r].normal += area[f] * byFace[f].normal;
    out.facets.push_back(byFace[f]);
  }
  for (Region& r : out.regions) {
    // Summed over whichever facets CGAL made of the face: the same to
    // rounding from run to run, so rounded to a billionth.
    r.normal.normalize();
    for (int a = 0; a < 3; ++a) r.normal[a] = std::round(r.normal[a] * 1e9) / 1e9;
    r.normal.normalize();
    const Mat3 frame = frameFromAxis(r.normal);
    r.e0 = frame.col(0), r.e1 = frame.col(1);
  }
  for (const auto h : hull.halfedges()) {
    const std::size_t f = faceAt[hull.face(h).idx()];
    const std::size_t g = faceAt[hull.face(hull.opposite(h)).idx()];
    if (!valid[f]) continue;
    const std::size_t r = byFace[f].region;
    if (valid[g] && byFace[g].region == r) continue;
    out.regions[r].boundary.emplace_back(at(hull.source(h)), at(hull.target(h)));
  }
  return out;
}

// The share of a region's boundary within `clearance` of a scan point,
// sampled `step` apart: the face a part stood on is bounded by its walls'
// lowest points all around; a hull facet that bridges a concavity spans air.
double boundarySeen(const Region& r, const NearestNeighbors& tree, double step, double clearance) {
  std::size_t total = 0, seen = 0;
  for (const auto& [a, b] : r.boundary) {
    const double len = (b - a).norm();
    const int n = std::max(1, int(std::ceil(len / step)));
    for (int i = 0; i < n; ++i) {
      double d2 = 0.0;
      tree.nearest(a + ((i + 0.5) / n) * (b - a), &d2);
      ++total;
      seen += d2 <= clearance * clearance ? 1 : 0;
    }
  }
  return total == 0 ? 0.0 : double(seen) / double(total);
}

enum class Hit { Back, Front, None };

class RayCaster {
 public:
  RayCaster(const PointCloud& scan, const NearestNeighbors& tree, double spacing,
            const UnseenFaceOptions& o)
      : scan_(scan),
        tree_(tree),
        rho_(o.hitRadius * spacing),
        grazing_(o.grazing),
        minStep_(0.5 * spacing),
        layer_(0.5 * spacing),
        thin_(o.thinWall * spacing) {
    const Aabb box = scan.bounds();
    lo_ = box.min.array() - rho_;
    hi_ = box.max.array() + rho_;
  }

  // The first face of the scan along the ray from `origin` in unit
  // direction `d`: met from behind, from the front, or none (the ray leaves
  // the scan's box, or grazes walls only).
  Hit cast(const Vec3& origin, const Vec3& d) const {
    std::vector<std::uint32_t> near;
    std::vector<double> d2;
    Vec3 x = origin;
    while ((x.array() >= lo_.array()).all() && (x.array() <= hi_.array()).all()) {
      double nearest2 = 0.0;
      tree_.nearest(x, &nearest2);
      const double dist = std::sqrt(nearest2);
      if (dist > rho_) {
        x += std::max(dist - rho_, minStep_) * d;
        continue;
      }
      // The points near the ray that do not graze it; of those, the first
      // layer along it votes (the near face of a wall thinner than the
      // search radius, not both).
      tree_.kNearest(x, 16, near, &d2);
      double first = std::numeric_limits<double>::infinity();
      std::size_t used = 0;
      for (std::size_t i = 0; i < near.size(); ++i) {
        const Vec3 off = scan_.points[near[i]] - x;
        const double t = off.dot(d);
        if ((off - t * d).squaredNorm() > rho_ * rho_) continue;
        if (std::abs(scan_.normals[near[i]].dot(d)) < grazing_) continue;
        first = std::min(first, t);
        near[used++] = near[i];
      }
      double vote = 0.0;
      for (std::size_t i = 0; i < used; ++i) {
        if ((scan_.points[near[i]] - x).dot(d) <= first + layer_) {
          vote += scan_.normals[near[i]].dot(d);
        }
      }
      if (vote > 0.0) return behindFront(x, d) ? Hit::Front : Hit::Back;
      if (vote < 0.0) return Hit::Front;
      x += minStep_ * d;
    }
    return Hit::None;
  }

 private:
  // Whether points facing the ray (at least two, not grazing it) lie just
  // before x along it and near it: the near face of a thin wall that the
  // ray passed through a gap of.
  bool behindFront(const Vec3& x, const Vec3& d) const {
    std::vector<std::uint32_t> near;
    tree_.kNearest(x, 32, near);
    int facing = 0;
    for (const std::uint32_t i : near) {
      const Vec3 off = scan_.points[i] - x;
      const double t = off.dot(d);
      if (t >= 0.0 || t < -thin_ || (off - t * d).squaredNorm() > thin_ * thin_) continue;
      facing += scan_.normals[i].dot(d) <= -grazing_ ? 1 : 0;
    }
    return facing >= 2;
  }

  const PointCloud& scan_;
  const NearestNeighbors& tree_;
  double rho_, grazing_, minStep_, layer_, thin_;
  Vec3 lo_, hi_;
};

}  // namespace

UnseenFaces unseenHullFaces(const PointCloud& scan, double step, const UnseenFaceOptions& options) {
  UnseenFaces out;
  if (!options.enabled || scan.size() < 4 || !scan.hasNormals() || !(step > 0.0)) return out;
  const Hull hull = convexHull(scan.points);
  if (hull.facets.empty()) return out;
  const NearestNeighbors tree(scan.points);
  const double spacing = medianNearestDistance(scan.points, tree);
  if (!(spacing > 0.0)) return out;
  const double clearance = options.clearance * spacing;

  // Lattice samples of every facet, in a frame of its region's normal (so
  // the facets of one face share their lattice), twice `step` apart: the
  // rays are cast from them, and each kept sample gives the four points
  // `step` apart around it. CGAL triangulates a face of coplanar hull points
  // one way in one run and another in the next (its order follows memory
  // addresses), so the samples must not depend on the facets: a facet takes
  // the lattice points on it with a tolerance (one on an edge between two
  // facets would fall to both, or, rounded, to neither), each lattice point
  // of a region is kept once (from the facet farthest out along the normal),
  // and it lies on its facet's plane (the same plane for every facet of a
  // flat face), on a grid a millionth of `step` fine.
  const double coarse = 2.0 * step;
  constexpr double kOnEdge = 1e-9;  // barycentric tolerance
  const double grain = 1e-6 * step;
  const auto snap = [&](const Vec3& p) -> Vec3 {
    return grain *
           Vec3(std::round(p.x() / grain), std::round(p.y() / grain), std::round(p.z() / grain));
  };
  struct Sample {
    Vec3 p;
    std::size_t region;
    int i, j;
    double height;  // along the region's normal
  };
  std::vector<Sample> samples;
  for (const Facet& f : hull.facets) {
    const Region& r = hull.regions[f.region];
    const Vec3 &normal = r.normal, &e0 = r.e0, &e1 = r.e1;
    // On the facet's own plane: a region joins facets 2 degrees apart one
    // to the next, so a curved face's region holds facets far from its mean
    // normal, and the plane through a facet's centre across that normal
    // would leave lattice points up to five lattice steps off the hull, far
    // from the scan (on a uniform scan of InverseCSG 142, 2 400 to 2 700
    // points on faces it saw).
    const double along = f.normal.dot(normal);
    if (along < 0.5) continue;  // more than 60 degrees off the region's normal
    const double planeOffset = f.normal.dot(f.v[0]);
    std::array<double, 3> u, v;
    for (int k = 0; k < 3; ++k) u[k] = f.v[k].dot(e0) / coarse, v[k] = f.v[k].dot(e1) / coarse;
    const double area2 = (u[1] - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (v[1] - v[0]);
    if (std::abs(area2) < 1e-12) continue;
    const int i0 = int(std::ceil(std::min({u[0], u[1], u[2]}) - kOnEdge));
    const int i1 = int(std::floor(std::max({u[0], u[1], u[2]}) + kOnEdge));
    const int j0 = int(std::ceil(std::min({v[0], v[1], v[2]}) - kOnEdge));
    const int j1 = int(std::floor(std::max({v[0], v[1], v[2]}) + kOnEdge));
    for (int i = i0; i <= i1; ++i) {
      for (int j = j0; j <= j1; ++j) {
        // Barycentric coordinates in the lattice's plane.
        const double b1 = ((i - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (j - v[0])) / area2;
        const double b2 = ((u[1] - u[0]) * (j - v[0]) - (i - u[0]) * (v[1] - v[0])) / area2;
        if (b1 < -kOnEdge || b2 < -kOnEdge || b1 + b2 > 1.0 + kOnEdge) continue;
        const Vec3 inPlane = (i * coarse) * e0 + (j * coarse) * e1;
        const double height = (planeOffset - f.normal.dot(inPlane)) / along;
        samples.push_back({snap(height * normal + inPlane), f.region, i, j, height});
      }
    }
  }
  const auto lattice = [](const Sample& a, const Sample& b) {
    return std::tie(a.region, a.i, a.j) < std::tie(b.region, b.i, b.j);
  };
  std::sort(samples.begin(), samples.end(), [&](const Sample& a, const Sample& b) {
    return lattice(a, b) || (!lattice(b, a) && a.height > b.height);
  });
  samples.erase(std::unique(samples.begin(), samples.end(),
                            [&](const Sample& a, const Sample& b) {
                              return !lattice(a, b) && !lattice(b, a);
                            }),
                samples.end());
  std::vector<char> unseen(samples.size(), 0), keep(samples.size(), 0);
  tbb::parallel_for(std::size_t(0), samples.size(), [&](std::size_t s) {
    double nearest2 = 0.0;
    tree.nearest(samples[s].p, &nearest2);
    unseen[s] = nearest2 > clearance * clearance ? 1 : 0;
  });
  // Regions mostly unseen, and whether their boundary was seen.
  std::vector<std::size_t> total(hull.regions.size(), 0), unseenCount(hull.regions.size(), 0);
  for (std::size_t s = 0; s < samples.size(); ++s) {
    ++total[samples[s].region];
    unseenCount[samples[s].region] += unseen[s] ? 1 : 0;
  }
  std::vector<char> closable(hull.regions.size(), 0);
  for (std::size_t r = 0; r < hull.regions.size(); ++r) {
    if (unseenCount[r] == 0 || double(unseenCount[r]) < options.minUnseenShare * double(total[r])) {
      continue;
    }
    const double seen = boundarySeen(hull.regions[r], tree, spacing, clearance);
    closable[r] = seen >= options.minBoundarySeen ? 1 : 0;
  }
  const RayCaster caster(scan, tree, spacing, options);
  const double ct = std::cos(options.tilt), st = std::sin(options.tilt);
  tbb::parallel_for(std::size_t(0), samples.size(), [&](std::size_t s) {
    const Sample& q = samples[s];
    if (!unseen[s] || !closable[q.region]) return;
    const Region& r = hull.regions[q.region];
    const std::array<Vec3, 5> dirs = {-r.normal, -ct * r.normal + st * r.e0,
                                      -ct * r.normal - st * r.e0, -ct * r.normal + st * r.e1,
                                      -ct * r.normal - st * r.e1};
    int back = 0;
    for (const Vec3& d : dirs) {
      const Hit h = caster.cast(q.p, d);
      if (h == Hit::Front) return;
      back += h == Hit::Back ? 1 : 0;
    }
    keep[s] = back >= options.minBackHits ? 1 : 0;
  });
  // Too few kept in a region: strays over air, not a face.
  std::vector<std::size_t> kept(hull.regions.size(), 0);
  for (std::size_t s = 0; s < samples.size(); ++s) kept[samples[s].region] += keep[s] ? 1 : 0;
  for (std::size_t s = 0; s < samples.size(); ++s) {
    out.tested += unseen[s] ? 1 : 0;
    const std::size_t k = kept[samples[s].region];
    if (!keep[s] || k < std::size_t(std::max(0, options.minKept)) ||
        double(k) < options.minKeptShare * double(unseenCount[samples[s].region])) {
      continue;
    }
    const Region& r = hull.regions[samples[s].region];
    for (const double a : {-0.5, 0.5}) {
      for (const double b : {-0.5, 0.5}) {
        const Vec3 p = samples[s].p + (a * step) * r.e0 + (b * step) * r.e1;
        double nearest2 = 0.0;
        tree.nearest(p, &nearest2);
        if (nearest2 <= clearance * clearance) continue;
        out.points.points.push_back(p);
        out.points.normals.push_back(r.normal);
      }
    }
  }
  // On the grid and in the order of their positions, not of the hull's
  // regions: the labels sum the points' dipoles in that order.
  using Key = std::array<long long, 3>;
  std::vector<std::pair<Key, std::size_t>> order(out.points.size());
  for (std::size_t k = 0; k < order.size(); ++k) {
    const Vec3& p = out.points.points[k];
    order[k] = {
        Key{std::llround(p.x() / grain), std::llround(p.y() / grain), std::llround(p.z() / grain)},
        k};
  }
  std::sort(order.begin(), order.end());
  PointCloud sorted;
  for (const auto& [key, k] : order) {
    sorted.points.push_back(grain * Vec3(double(key[0]), double(key[1]), double(key[2])));
    sorted.normals.push_back(out.points.normals[k]);
  }
  out.points = std::move(sorted);
  out.area = double(out.points.size()) * step * step;
  return out;
}

}  // namespace csgvox

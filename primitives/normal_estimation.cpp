#include "primitives/normal_estimation.h"

#include <CGAL/Eigen_svd.h>
#include <CGAL/Orthogonal_k_neighbor_search.h>
#include <CGAL/Search_traits_3.h>
#include <CGAL/Search_traits_adapter.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/jet_estimate_normals.h>
#include <CGAL/property_map.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace csgvox {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using Point3 = Kernel::Point_3;
using Vector3 = Kernel::Vector_3;
using PointMap = CGAL::Pointer_property_map<Point3>::type;    // index -> point
using NormalMap = CGAL::Pointer_property_map<Vector3>::type;  // index -> normal

// Closest point pairs that decide how a piece is oriented against the
// largest piece.
constexpr std::size_t kMatchingPairs = 16;
// A point lies on a tangent plane when closer to it than this fraction of
// its neighbourhood radius, or than this multiple of the typical distance
// of neighbourhoods to their planes (noise).
constexpr double kOnPlaneRadiusFraction = 0.1;
constexpr double kOnPlaneNoiseFactor = 3.0;

/// Nearest-neighbour search over a subset of the points, by index.
class IndexTree {
 public:
  IndexTree(const std::vector<std::size_t>& indices, PointMap points)
      : points_(points),
        tree_(indices.begin(), indices.end(), Tree::Splitter(), Traits(points)) {
    tree_.build();
  }

  /// Index of the point nearest to q, and its squared distance.
  std::pair<std::size_t, double> nearest(const Point3& q) const {
    Search search(tree_, q, 1, 0.0, true, Distance(points_));
    const auto it = search.begin();
    return {it->first, it->second};
  }

  /// Appends the indices of the k points nearest to q, closest first;
  /// returns the squared distance of the farthest of them.
  double kNearest(const Point3& q, unsigned k, std::vector<std::uint32_t>& out) const {
    Search search(tree_, q, k, 0.0, true, Distance(points_));
    double farthest2 = 0.0;
    for (const auto& [index, d2] : search) {
      out.push_back(static_cast<std::uint32_t>(index));
      farthest2 = d2;
    }
    return farthest2;
  }

 private:
  using Traits = CGAL::Search_traits_adapter<std::size_t, PointMap, CGAL::Search_traits_3<Kernel>>;
  using Search = CGAL::Orthogonal_k_neighbor_search<Traits>;
  using Tree = Search::Tree;
  using Distance = Search::Distance;

  PointMap points_;
  Tree tree_;
};

bool isUsable(const Vector3& n) {
  const double len2 = n.squared_length();
  return std::isfinite(len2) && len2 > 1e-24;
}

/// Jet-fitted unit normals, unoriented. Points whose fit degenerates (e.g.
/// coincident neighbours) take the normal of the nearest point whose fit
/// succeeded.
void jetNormals(std::vector<Point3>& points, std::vector<Vector3>& normals, unsigned k) {
  std::vector<std::size_t> all(points.size());
  std::iota(all.begin(), all.end(), std::size_t{0});
  const PointMap pointMap = CGAL::make_property_map(points);
  const NormalMap normalMap = CGAL::make_property_map(normals);
  CGAL::jet_estimate_normals<CGAL::Sequential_tag>(
      all, k,
      CGAL::parameters::point_map(pointMap).normal_map(normalMap).svd_traits(CGAL::Eigen_svd()));

  std::vector<std::size_t> good;
  std::vector<std::size_t> bad;
  for (std::size_t i = 0; i < normals.size(); ++i) {
    if (isUsable(normals[i])) {
      normals[i] = normals[i] / std::sqrt(normals[i].squared_length());
      good.push_back(i);
    } else {
      bad.push_back(i);
    }
  }
  if (bad.empty()) return;
  if (good.empty()) {
    throw std::invalid_argument(
        "estimateNormals: no surface can be fitted to the points (all coincident or collinear?)");
  }
  const IndexTree tree(good, pointMap);
  for (std::size_t i : bad) normals[i] = normals[tree.nearest(points[i]).first];
}

/// The k nearest neighbours of every point, the point itself first.
struct Neighbourhoods {
  unsigned k = 0;
  std::vector<std::uint32_t> indices;  ///< k per point
  std::vector<double> radius;          ///< distance to the k-th neighbour

  const std::uint32_t* of(std::size_t i) const { return indices.data() + i * k; }
};

Neighbourhoods findNeighbourhoods(std::vector<Point3>& points, unsigned k) {
  const std::size_t n = points.size();
  std::vector<std::size_t> all(n);
  std::iota(all.begin(), all.end(), std::size_t{0});
  const IndexTree tree(all, CGAL::make_property_map(points));
  Neighbourhoods hoods;
  hoods.k = k;
  hoods.indices.reserve(n * k);
  hoods.radius.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t first = hoods.indices.size();
    hoods.radius[i] = std::sqrt(tree.kNearest(points[i], k, hoods.indices));
    hoods.indices.resize(first + k, static_cast<std::uint32_t>(i));  // (never short: n > k)
    // Coincident points may come in any order: put the point itself first.
    std::uint32_t* hood = hoods.indices.data() + first;
    std::uint32_t* self = std::find(hood, hood + k, static_cast<std::uint32_t>(i));
    if (self == hood + k) {
      *hood = static_cast<std::uint32_t>(i);  // more than k copies of the point
    } else {
      std::iter_swap(hood, self);
    }
  }
  return hoods;
}

/// Sharpens normals near edges. The jet fit blends the normals of the faces
/// that meet at an edge for every point within a neighbourhood of it. Each
/// point therefore considers the tangent planes of its neighbours that pass
/// through it (within a tolerance) and takes the normal of the plane that
/// holds most of its neighbours, keeping its own when that is among the best.
/// On smooth surfaces a point's own plane is the best and nothing changes.
void sharpenAtEdges(const std::vector<Point3>& points, std::vector<Vector3>& normals,
                    const Neighbourhoods& hoods) {
  const std::size_t n = points.size();
  const unsigned k = hoods.k;
  // Noise (or curvature) level of a typical point: the RMS distance of its
  // neighbours to its tangent plane. Edges are a minority.
  std::vector<double> residual(n);
  for (std::size_t i = 0; i < n; ++i) {
    double sum2 = 0.0;
    for (unsigned l = 0; l < k; ++l) {
      const double d = normals[i] * (points[hoods.of(i)[l]] - points[i]);
      sum2 += d * d;
    }
    residual[i] = std::sqrt(sum2 / k);
  }
  std::nth_element(residual.begin(), residual.begin() + static_cast<std::ptrdiff_t>(n / 2),
                   residual.end());
  const double typical = residual[n / 2];

  std::vector<Vector3> sharpened = normals;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t* hood = hoods.of(i);
    const double tolerance =
        std::max(kOnPlaneRadiusFraction * hoods.radius[i], kOnPlaneNoiseFactor * typical);
    auto support = [&](std::size_t j) {
      int count = 0;
      for (unsigned l = 0; l < k; ++l) {
        if (std::abs(normals[j] * (points[hood[l]] - points[j])) <= tolerance) ++count;
      }
      return count;
    };
    int best = support(i);
    for (unsigned c = 1; c < k; ++c) {
      const std::size_t j = hood[c];
      if (std::abs(normals[j] * (points[i] - points[j])) > tolerance) continue;
      const int count = support(j);
      if (count > best) {
        best = count;
        sharpened[i] = normals[j];
      }
    }
  }
  normals = std::move(sharpened);
}

/// How consistently the normals at p and q, on pieces of the scan separated
/// by a gap, are oriented: > 0 consistent, < 0 one should be flipped. Where
/// the gap runs along the surface, parallel normals agree; where it runs
/// across the surface (an edge, two walls facing each other), p and q must
/// lie on opposite sides of each other's tangent planes relative to the gap,
/// which holds both for free space and for material between them. (Within
/// a piece, where gaps are as small as the noise, the gap's direction means
/// nothing and only parallel normals count.)
double agreement(const Point3& p, const Vector3& np, const Point3& q, const Vector3& nq) {
  const Vector3 gap = q - p;
  const double length = std::sqrt(gap.squared_length());
  if (!(length > 0.0)) return np * nq;
  const Vector3 dir = gap / length;
  const double acrossP = np * dir;
  const double acrossQ = nq * dir;
  const double along = std::max(0.0, 1.0 - std::max(std::abs(acrossP), std::abs(acrossQ)));
  return along * (np * nq) - acrossP * acrossQ;
}

/// Weight of a neighbour-graph edge for orientation propagation: low when
/// the normals are parallel (their relative orientation is clear) and the
/// edge runs along the surface. Edges across the surface, such as those
/// jumping through a thin wall between parallel but oppositely oriented
/// faces, are penalised by how steeply they leave either tangent plane.
double edgeWeight(const Point3& p, const Vector3& np, const Point3& q, const Vector3& nq) {
  const Vector3 gap = q - p;
  const double length = std::sqrt(gap.squared_length());
  const double dot = std::abs(np * nq);
  if (!(length > 0.0)) return 1.0 - dot;
  const Vector3 dir = gap / length;
  return (1.0 - dot) + std::min(std::abs(np * dir), std::abs(nq * dir));
}

/// Orients normals consistently by propagating along a minimum spanning
/// forest of the k-neighbour graph (Hoppe et al. 1992, as in CGAL's
/// mst_orient_normals, but with edgeWeight instead of 1 - |n_i . n_j|: with
/// the classic weight, edges through thin walls cost nothing, and on the
/// noisy scans in data/ whole walls came out inverted). Returns the trees,
/// one per connected piece of the graph, each consistent within itself.
std::vector<std::vector<std::size_t>> orientAlongSpanningForest(
    const std::vector<Point3>& points, std::vector<Vector3>& normals, const Neighbourhoods& hoods) {
  const std::size_t n = points.size();
  struct Edge {
    double weight;
    std::uint32_t a, b;
    bool operator<(const Edge& o) const { return std::tie(weight, a, b) < std::tie(o.weight, o.a, o.b); }
  };
  std::vector<Edge> edges;
  edges.reserve(n * hoods.k);
  for (std::size_t i = 0; i < n; ++i) {
    for (unsigned c = 1; c < hoods.k; ++c) {
      const std::uint32_t j = hoods.of(i)[c];
      edges.push_back({edgeWeight(points[i], normals[i], points[j], normals[j]), static_cast<std::uint32_t>(std::min<std::size_t>(i, j)),
                       static_cast<std::uint32_t>(std::max<std::size_t>(i, j))});
    }
  }
  std::sort(edges.begin(), edges.end());

  // Kruskal.
  std::vector<std::uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  std::vector<std::vector<std::uint32_t>> tree(n);
  for (const Edge& e : edges) {
    const std::uint32_t ra = find(e.a);
    const std::uint32_t rb = find(e.b);
    if (ra == rb) continue;
    parent[ra] = rb;
    tree[e.a].push_back(e.b);
    tree[e.b].push_back(e.a);
  }

  // Breadth-first propagation from the first point of each tree.
  std::vector<char> visited(n, 0);
  std::vector<char> flipped(n, 0);
  std::vector<std::vector<std::size_t>> pieces;
  for (std::size_t root = 0; root < n; ++root) {
    if (visited[root]) continue;
    std::vector<std::size_t>& piece = pieces.emplace_back(1, root);
    visited[root] = 1;
    for (std::size_t head = 0; head < piece.size(); ++head) {
      const std::size_t i = piece[head];
      for (std::uint32_t j : tree[i]) {
        if (visited[j]) continue;
        visited[j] = 1;
        const bool disagree = normals[i] * normals[j] < 0.0;
        flipped[j] = flipped[i] != disagree;
        piece.push_back(j);
      }
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (flipped[i]) normals[i] = -normals[i];
  }
  return pieces;
}

/// Orients every piece but the largest like the largest, judged by the
/// closest point pairs between them.
void matchPieces(std::vector<Point3>& points, std::vector<Vector3>& normals,
                 const std::vector<std::vector<std::size_t>>& pieces) {
  if (pieces.size() < 2) return;
  const auto largest = std::max_element(
      pieces.begin(), pieces.end(), [](const auto& a, const auto& b) { return a.size() < b.size(); });
  const IndexTree tree(*largest, CGAL::make_property_map(points));
  for (auto piece = pieces.begin(); piece != pieces.end(); ++piece) {
    if (piece == largest) continue;
    std::vector<std::pair<double, double>> pairs;  // squared gap, agreement
    pairs.reserve(piece->size());
    for (std::size_t i : *piece) {
      const auto [j, d2] = tree.nearest(points[i]);
      pairs.emplace_back(d2, agreement(points[i], normals[i], points[j], normals[j]));
    }
    const std::size_t m = std::min(kMatchingPairs, pairs.size());
    std::partial_sort(pairs.begin(), pairs.begin() + static_cast<std::ptrdiff_t>(m), pairs.end());
    double vote = 0.0;
    for (std::size_t p = 0; p < m; ++p) vote += pairs[p].second;
    if (vote < 0.0) {
      for (std::size_t i : *piece) normals[i] = -normals[i];
    }
  }
}

/// Flips every normal when, at the scan's extreme points along ±x, ±y, ±z,
/// the normals mostly point inwards.
void orientOutwards(const std::vector<Point3>& points, std::vector<Vector3>& normals) {
  const std::size_t n = points.size();
  const std::size_t m = std::clamp<std::size_t>(n / 100, 1, 20);  // extreme points per direction
  std::vector<std::size_t> order(n);
  int agree = 0;
  int disagree = 0;
  double total = 0.0;
  for (int axis = 0; axis < 3; ++axis) {
    for (double sign : {1.0, -1.0}) {
      std::iota(order.begin(), order.end(), std::size_t{0});
      std::nth_element(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(m - 1),
                       order.end(), [&](std::size_t a, std::size_t b) {
                         return sign * points[a][axis] > sign * points[b][axis];
                       });
      double vote = 0.0;
      for (std::size_t i = 0; i < m; ++i) vote += sign * normals[order[i]][axis];
      vote /= static_cast<double>(m);
      if (vote > 0.0) ++agree;
      if (vote < 0.0) ++disagree;
      total += vote;
    }
  }
  if (disagree > agree || (disagree == agree && total < 0.0)) {
    for (Vector3& normal : normals) normal = -normal;
  }
}

}  // namespace

void estimateNormals(PointCloud& cloud, int neighbors) {
  if (neighbors < 6) {
    throw std::invalid_argument("estimateNormals: neighbors must be at least 6 (is " +
                                std::to_string(neighbors) + ")");
  }
  const std::size_t n = cloud.size();
  if (n <= static_cast<std::size_t>(neighbors)) {
    throw std::invalid_argument("estimateNormals: " + std::to_string(n) +
                                " points are too few for " + std::to_string(neighbors) +
                                " neighbours");
  }
  std::vector<Point3> points;
  points.reserve(n);
  for (const Vec3& p : cloud.points) {
    if (!p.allFinite()) throw std::invalid_argument("estimateNormals: a point is not finite");
    points.emplace_back(p.x(), p.y(), p.z());
  }
  std::vector<Vector3> normals(n, CGAL::NULL_VECTOR);
  const auto k = static_cast<unsigned>(neighbors);

  jetNormals(points, normals, k);
  const Neighbourhoods hoods = findNeighbourhoods(points, k);
  sharpenAtEdges(points, normals, hoods);
  matchPieces(points, normals, orientAlongSpanningForest(points, normals, hoods));
  orientOutwards(points, normals);

  cloud.normals.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    cloud.normals[i] = Vec3(normals[i].x(), normals[i].y(), normals[i].z()).normalized();
  }
}

}  // namespace csgvox

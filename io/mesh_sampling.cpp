#include "io/mesh_sampling.h"

#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <utility>
#include <vector>

#include "io/reader_support.h"

namespace csgvox::detail {
namespace {

// Merging duplicate vertices and orienting a soup need only coordinate
// comparisons, no geometric predicates: a plain kernel will do.
using IoKernel = CGAL::Simple_cartesian<double>;
using IoPoint = IoKernel::Point_3;
using IoVector = IoKernel::Vector_3;
using Polygon = std::vector<std::size_t>;

/// Newell normal of a polygon (length: twice its area when planar).
IoVector newellNormal(const std::vector<IoPoint>& points, const Polygon& polygon) {
  double nx = 0.0, ny = 0.0, nz = 0.0;
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const auto& a = points[polygon[i]];
    const auto& b = points[polygon[(i + 1) % polygon.size()]];
    nx += (a.y() - b.y()) * (a.z() + b.z());
    ny += (a.z() - b.z()) * (a.x() + b.x());
    nz += (a.x() - b.x()) * (a.y() + b.y());
  }
  return IoVector(nx, ny, nz);
}

/// Connected components of polygons sharing a vertex; returns the component
/// of each polygon.
std::vector<std::size_t> polygonComponents(std::size_t pointCount,
                                           const std::vector<Polygon>& polygons) {
  std::vector<std::size_t> parent(pointCount);
  std::iota(parent.begin(), parent.end(), std::size_t{0});
  auto find = [&](std::size_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (const Polygon& polygon : polygons) {
    for (std::size_t i = 1; i < polygon.size(); ++i) parent[find(polygon[i])] = find(polygon[0]);
  }
  std::vector<std::size_t> component(polygons.size());
  for (std::size_t f = 0; f < polygons.size(); ++f) component[f] = find(polygons[f][0]);
  return component;
}

/// Orients the soup consistently where it is orientable, keeping in each
/// connected piece the orientation most of its area had in the file, then
/// flips everything if the enclosed volume is negative.
void orientSoup(std::vector<IoPoint>& points, std::vector<Polygon>& polygons) {
  namespace PMP = CGAL::Polygon_mesh_processing;
  std::vector<IoVector> before;
  before.reserve(polygons.size());
  for (const Polygon& polygon : polygons) before.push_back(newellNormal(points, polygon));

  PMP::orient_polygon_soup(points, polygons);  // may duplicate non-manifold vertices

  const std::vector<std::size_t> component = polygonComponents(points.size(), polygons);
  std::vector<double> kept(points.size(), 0.0);  // per component root: area kept minus area flipped
  for (std::size_t f = 0; f < polygons.size(); ++f) {
    const IoVector after = newellNormal(points, polygons[f]);
    const double length = std::sqrt(after.squared_length());
    if (length > 0.0) kept[component[f]] += (before[f] * after) / length;
  }
  for (std::size_t f = 0; f < polygons.size(); ++f) {
    if (kept[component[f]] < 0.0) std::reverse(polygons[f].begin(), polygons[f].end());
  }

  IoVector centroid = CGAL::NULL_VECTOR;
  for (const IoPoint& p : points) centroid = centroid + (p - CGAL::ORIGIN);
  const IoPoint c = CGAL::ORIGIN + centroid / static_cast<double>(points.size());
  double volume = 0.0;
  for (const Polygon& polygon : polygons) {
    for (std::size_t i = 1; i + 1 < polygon.size(); ++i) {
      volume += CGAL::scalar_product(
          points[polygon[0]] - c,
          CGAL::cross_product(points[polygon[i]] - c, points[polygon[i + 1]] - c));
    }
  }
  if (volume < 0.0) {
    for (Polygon& polygon : polygons) std::reverse(polygon.begin(), polygon.end());
  }
}

}  // namespace

PointCloud sampleMeshFaces(PolygonSoup soup, const std::string& source, std::size_t count,
                           std::uint64_t seed) {
  namespace PMP = CGAL::Polygon_mesh_processing;
  std::vector<IoPoint> points;
  points.reserve(soup.points.size());
  for (const Vec3& p : soup.points) points.emplace_back(p.x(), p.y(), p.z());
  std::vector<Polygon> polygons = std::move(soup.polygons);
  PMP::merge_duplicate_points_in_polygon_soup(points, polygons);
  // Drops repeated corners and faces that are not proper polygons; they
  // carry no area, and the orientation needs simple polygons.
  std::erase_if(polygons, [](Polygon& polygon) {
    polygon.erase(std::unique(polygon.begin(), polygon.end()), polygon.end());
    while (polygon.size() > 1 && polygon.front() == polygon.back()) polygon.pop_back();
    Polygon sorted = polygon;
    std::sort(sorted.begin(), sorted.end());
    return polygon.size() < 3 || std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end();
  });
  if (polygons.empty()) parseError(source, "mesh has zero area (every face is degenerate)");
  orientSoup(points, polygons);

  // Fan triangles with their cumulative areas.
  struct Triangle {
    Vec3 a, b, c, normal;
  };
  std::vector<Triangle> triangles;
  std::vector<double> cumulative;
  double total = 0.0;
  auto vec = [&](std::size_t i) { return Vec3(points[i].x(), points[i].y(), points[i].z()); };
  for (const Polygon& polygon : polygons) {
    for (std::size_t i = 1; i + 1 < polygon.size(); ++i) {
      const Vec3 a = vec(polygon[0]), b = vec(polygon[i]), c = vec(polygon[i + 1]);
      const Vec3 cross = (b - a).cross(c - a);
      const double area = 0.5 * cross.norm();
      if (!(area > 0.0) || !std::isfinite(area)) continue;
      triangles.push_back({a, b, c, cross / (2.0 * area)});
      total += area;
      cumulative.push_back(total);
    }
  }
  if (triangles.empty() || !(total > 0.0) || !std::isfinite(total)) {
    parseError(source, "mesh has zero area");
  }

  std::mt19937_64 rng(seed);
  auto uniform = [&rng] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };  // [0, 1)
  PointCloud cloud;
  cloud.points.reserve(count);
  cloud.normals.reserve(count);
  for (std::size_t s = 0; s < count; ++s) {
    const double u = uniform() * total;
    const std::size_t t = std::min<std::size_t>(
        static_cast<std::size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), u) -
                                 cumulative.begin()),
        triangles.size() - 1);
    const double r1 = std::sqrt(uniform());
    const double r2 = uniform();
    const Triangle& tri = triangles[t];
    cloud.points.push_back((1.0 - r1) * tri.a + r1 * (1.0 - r2) * tri.b + r1 * r2 * tri.c);
    cloud.normals.push_back(tri.normal);
  }
  return cloud;
}

}  // namespace csgvox::detail

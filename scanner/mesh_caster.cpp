#include "scanner/mesh_caster.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <stdexcept>
#include <vector>

namespace csgvox {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Ray = Kernel::Ray_3;
using Segment = Kernel::Segment_3;
using TriangleIterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, TriangleIterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

Point toPoint(const Vec3& v) { return Point(v.x(), v.y(), v.z()); }

}  // namespace

struct MeshCaster::Impl {
  std::vector<Triangle> triangles;
  std::vector<Vec3> normals;  // unit, per triangle
  Tree tree;
};

MeshCaster::MeshCaster(const TriangleMesh& mesh) {
  auto impl = std::make_unique<Impl>();
  for (const auto& t : mesh.triangles) {
    for (std::uint32_t v : t) {
      if (v >= mesh.vertices.size()) {
        throw std::invalid_argument("mesh triangle refers to vertex " + std::to_string(v) +
                                    " of " + std::to_string(mesh.vertices.size()));
      }
    }
    const Vec3& a = mesh.vertices[t[0]];
    const Vec3& b = mesh.vertices[t[1]];
    const Vec3& c = mesh.vertices[t[2]];
    const Vec3 n = (b - a).cross(c - a);
    const double length = n.norm();
    if (!(length > 0.0)) continue;  // degenerate: no surface to hit
    impl->triangles.emplace_back(toPoint(a), toPoint(b), toPoint(c));
    impl->normals.push_back(n / length);
    bounds_.extend(a);
    bounds_.extend(b);
    bounds_.extend(c);
  }
  if (impl->triangles.empty()) throw std::invalid_argument("mesh has no triangle to scan");
  impl->tree.insert(impl->triangles.cbegin(), impl->triangles.cend());
  impl->tree.build();
  impl_ = std::move(impl);
}

MeshCaster::~MeshCaster() = default;

std::optional<RayHit> MeshCaster::firstHit(const Vec3& origin, const Vec3& direction,
                                           double maxDistance) const {
  const Ray ray(toPoint(origin), toPoint(origin + direction));
  const auto hit = impl_->tree.first_intersection(ray);
  if (!hit) return std::nullopt;
  Vec3 at;
  if (const Point* p = boost::get<Point>(&hit->first)) {
    at = Vec3(p->x(), p->y(), p->z());
  } else if (const Segment* s = boost::get<Segment>(&hit->first)) {
    // The ray lies in the triangle's plane: its nearer end.
    const Vec3 a(s->source().x(), s->source().y(), s->source().z());
    const Vec3 b(s->target().x(), s->target().y(), s->target().z());
    at = (a - origin).squaredNorm() <= (b - origin).squaredNorm() ? a : b;
  } else {
    return std::nullopt;
  }
  RayHit result;
  result.distance = (at - origin).dot(direction);
  if (result.distance > maxDistance) return std::nullopt;
  const std::size_t index = std::size_t(hit->second - impl_->triangles.cbegin());
  result.normal = impl_->normals[index];
  return result;
}

}  // namespace csgvox

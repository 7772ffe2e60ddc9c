#include "pipeline/gp_primitives.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/clipped_solid.h"
#include "primitives/bounding_box.h"

namespace csgvox {
namespace {

bool samePlane(const HalfSpace& a, const HalfSpace& b, double distance, double cosAngle) {
  const double c = a.normal.dot(b.normal);
  if (std::abs(c) < cosAngle) return false;
  // The same plane with the other orientation is the same separator.
  return c > 0 ? std::abs(a.offset - b.offset) <= distance
               : std::abs(a.offset + b.offset) <= distance;
}

}  // namespace

GpPrimitives gpPrimitives(const PointCloud& scan, std::span<const Surface> surfaces,
                          const GpPrimitiveOptions& options) {
  if (scan.points.empty()) throw std::invalid_argument("gpPrimitives: the scan is empty");
  if (surfaces.empty()) throw std::invalid_argument("gpPrimitives: no surfaces");
  GpPrimitives out;
  const Aabb box = scan.bounds();
  const double diagonal = box.diagonal();
  out.clipBox = box.grown(options.clipMargin * diagonal);

  std::vector<Primitive> primitives;
  std::vector<std::string> names;
  std::vector<HalfSpace> planes;
  for (const Surface& s : surfaces) {
    primitives.push_back(clippedSolid(s.shape, box));
    names.push_back(std::string(surfaceTypeName(s.type())) + std::to_string(names.size()));
    if (const HalfSpace* h = primitives.back().as<HalfSpace>()) planes.push_back(*h);
  }
  out.fitted = primitives.size();
  if (options.separators) {
    const double distance = options.samePlane * diagonal;
    const double cosAngle = std::cos(options.sameAngle * std::numbers::pi / 180.0);
    for (const Surface& s : surfaces) {
      if (s.type() == SurfaceType::Plane) continue;
      if (const TorusSurface* t = s.as<TorusSurface>()) {
        primitives.push_back(
            clippedSolid(CylinderSurface{t->center, t->axisDir, t->majorRadius}, box));
        names.push_back("separator" + std::to_string(names.size()));
      }
      if (s.inliers.size() < 4) continue;
      std::vector<Vec3> inliers;
      inliers.reserve(s.inliers.size());
      for (const std::uint32_t i : s.inliers) inliers.push_back(scan.points[i]);
      const OrientedBox obb = minimalOrientedBox(inliers);
      for (int axis = 0; axis < 3; ++axis) {
        for (const double side : {-1.0, 1.0}) {
          const Vec3 n = side * obb.axes.col(axis);
          const HalfSpace h{n, n.dot(obb.center) + obb.halfSize[axis]};
          bool known = false;
          for (const HalfSpace& q : planes) known = known || samePlane(q, h, distance, cosAngle);
          if (known) continue;
          planes.push_back(h);
          primitives.push_back(h);
          names.push_back("separator" + std::to_string(names.size()));
        }
      }
    }
  }
  out.separators = primitives.size() - out.fitted;
  out.library = PrimitiveLibrary(std::move(primitives), std::move(names));
  return out;
}

}  // namespace csgvox

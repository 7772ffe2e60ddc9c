#include "design/role_names.h"

#include <algorithm>

namespace csgvox {

std::string roleName(const Primitive& p, bool cuts, double partDiagonal) {
  // Proportions: "thin" is a side under a quarter of the next; "large" is a
  // radius of at least a tenth of the part's diagonal.
  constexpr double thin = 0.25;
  constexpr double large = 0.1;
  if (const auto* b = p.as<Box>()) {
    Vec3 s = b->halfSize;
    std::sort(s.data(), s.data() + 3);
    if (cuts) return s[0] < thin * s[1] || s[1] < thin * s[2] ? "slot" : "pocket";
    if (s[0] < thin * s[1]) return s[2] >= 0.25 * partDiagonal ? "plate" : "rib";
    return "block";
  }
  if (const auto* c = p.as<Cylinder>()) {
    if (cuts) return c->radius >= large * partDiagonal ? "bore" : "hole";
    if (c->height < 0.5 * c->radius) return "plate";
    return c->radius >= large * partDiagonal ? "hub" : "boss";
  }
  switch (p.type()) {
    case PrimitiveType::Cone:
      return cuts ? "chamfer" : "taper";
    case PrimitiveType::Sphere:
      return cuts ? "recess" : "dome";
    case PrimitiveType::Torus:
      return cuts ? "fillet" : "ring";
    case PrimitiveType::HalfSpace:
      return cuts ? "cut" : "side";
    default:
      return "part";
  }
}

}  // namespace csgvox
